"""The control loop's rules without a clock: simulated time read off a wall-clock reading, ticks at whole periods.

Rules:
- The platform model integrates one step only: ``Platform.tick(k * CONTROL_PERIOD)`` (50 Hz simulated), each
  tick exactly one period after the one before. The motion, the boards, the sensors and every timer of the
  model see the same sequence of simulated times at every time scale; the time scale decides only how many
  wall seconds that sequence takes.
- ``now(wall)`` is the simulated time at the wall-clock reading ``wall`` (seconds, any monotonic origin), and
  it first runs the ticks due by then. The network shell calls it from its timer AND for everything it hands
  the platform between two timer wake-ups (a telegram, a control-channel request): a command at simulated time
  t meets the state of the last tick at or before t, however late the shell's timer woke up. (Without that,
  at time scale 20 a wake-up 10 ms late - ten periods - let a command land on a state ten periods old, and
  the periods it skipped ran after it with the command already in force: the outcome depended on the load
  and the time scale.)
- The shell's timer works the ticks off, at most ``burst`` a reading (``now(wall)``), so its I/O is served
  between two bursts. A reading for a telegram (``now(wall, burst=0)``) runs the ticks due itself only when they
  are a burst or fewer (a late timer); a longer backlog (the loop was blocked a moment, or the machine cannot
  keep up) is the timer's, and the telegram takes the time of the last tick - the platform's own time, a
  little behind the clock: it still meets the state of its own time and the ticks after it stay after it, and
  a reply never waits for the backlog. A timer late by less than ``burst`` periods (25 ms at time scale 20)
  changes nothing at all.
- A shell that fell more than ``max_catch_up`` periods behind (blocked for long, or a time scale beyond what
  this machine can simulate) neither hands the platform a longer step nor works off that backlog: the
  simulated time stands still for the part that could not be simulated (the wall-clock origin moves on by it,
  logged as a warning), so the platform's trajectory is that of an undisturbed run, only later in wall time.
- Sans-IO: no clock, no sleep; the caller reads its clock and passes the reading.
"""

from __future__ import annotations

import logging
import math
from typing import Protocol

log = logging.getLogger("pltf.server")

CONTROL_PERIOD = 0.02  # simulated s (50 Hz)
MAX_CATCH_UP = 500  # periods (10 s simulated) of backlog worked off; beyond that the simulated time is held
BURST = 25  # ticks a reading runs at most (0.5 s simulated, about 12 ms of the world's work on an idle core)
HELD_WARNING_EVERY = 10.0  # simulated s between two warnings about held time


class Ticked(Protocol):
    def tick(self, now: float) -> None: ...


class ControlLoop:
    """Ticks ``platform`` every ``period`` of simulated time; simulated time = (wall - origin) * ``time_scale``."""

    def __init__(
        self,
        platform: Ticked,
        time_scale: float,
        wall: float,
        *,
        period: float = CONTROL_PERIOD,
        max_catch_up: int = MAX_CATCH_UP,
        burst: int = BURST,
    ) -> None:
        if not time_scale > 0 or math.isinf(time_scale):
            raise ValueError(f"time scale must be > 0, not {time_scale}")
        self.platform = platform
        self.time_scale = time_scale
        self.period = period
        self.max_catch_up = max_catch_up
        self.burst = burst
        self.origin = wall  # the wall-clock reading at simulated time 0 (moves on while the time is held)
        self.ticks = 0  # the platform has been ticked up to ticks * period
        self.held = 0.0  # simulated s the time stood still (the loop could not keep up)
        self._warned_at = -math.inf

    def begin(self, wall: float) -> float:
        """The simulated time at ``wall``, where the platform starts (boots): no tick before it is run."""
        now = self.sim(wall)
        self.ticks = int(now / self.period)
        return now

    def sim(self, wall: float) -> float:
        """The simulated time at ``wall``, without ticking."""
        return (wall - self.origin) * self.time_scale

    def wall_at(self, sim: float) -> float:
        """The wall-clock reading at which the simulated time is ``sim`` (unless the time is held before)."""
        return self.origin + sim / self.time_scale

    @property
    def next_tick(self) -> float:
        """The simulated time of the next tick."""
        return (self.ticks + 1) * self.period

    def now(self, wall: float, burst: int | None = None) -> float:
        """The simulated time at ``wall``, with the platform ticked up to it. Behind by more than ``self.burst``
        ticks: ``burst`` ticks on (default ``self.burst``; 0 for a telegram) and the time of the last tick."""
        sim = self.sim(wall)
        due = int(sim / self.period) - self.ticks
        if due > self.max_catch_up:
            hold = (due - 1) * self.period  # the part this machine could not simulate: it never happens
            self.origin += hold / self.time_scale
            self.held += hold
            sim -= hold
            due = 1
            if self.ticks * self.period - self._warned_at >= HELD_WARNING_EVERY:
                self._warned_at = self.ticks * self.period
                log.warning(
                    "control loop %.1f s (simulated) behind: the simulated time was held (%.1f s in all)",
                    hold,
                    self.held,
                )
        n = due if due <= self.burst else min(due, self.burst if burst is None else burst)
        for _ in range(n):
            self.ticks += 1
            self.platform.tick(self.ticks * self.period)
        return sim if n == due else self.ticks * self.period

    def advance(self, sim: float) -> None:
        """Tick the platform up to the simulated time ``sim`` (a clock of the caller's own: a stepped test)."""
        while self.next_tick <= sim + 1e-9:
            self.ticks += 1
            self.platform.tick(self.ticks * self.period)
