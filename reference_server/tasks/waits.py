"""The <wait> element (guide 6.5): entering a wait, and whether it is over, in simulated time.

Rules:
- Two clocks come in: ``t``, the program's time in seconds (it stands still while the program is paused,
  E-TASK-005), for delay, random and the timeout; ``now``, the simulated platform time, for <date>, which
  compares the platform's local wall time (E-TASK-010).
- Each condition is one row of ``_CONDITIONS``: a predicate over the facade's sensors. A wait whose event
  holds on the tick its timeout expires ends by the event, not the timeout.
- <date> is checked at every whole second between two ticks, so a coarse tick (a remote computer polling
  every 100 ms at a high time scale) never steps over the matching second.
- <random> draws its duration once, on entry, from the interpreter's seeded generator (E-TASK-009).
"""

from __future__ import annotations

import datetime
import random
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pltf.reference_server.tasks import model as m
from pltf.reference_server.tasks.facade import Sensors

MAX_DATE_STEPS = 86_400  # seconds checked per tick at most (one simulated day between two ticks)


@dataclass
class PendingWait:
    wait: m.Wait
    since: float  # program time at entry, s
    until: float | None  # end of a delay or random wait, program time
    deadline: float | None  # timeout, program time
    last_now: float  # simulated time of the last <date> check

    def describe(self, t: float) -> str:
        """One line for logs and the progress view."""
        ev = self.wait.event
        what = "timeout only" if ev is None else describe_event(ev)
        parts = [what]
        if self.until is not None:
            parts.append(f"{max(0.0, self.until - t):.1f} s left")
        if self.deadline is not None:
            parts.append(f"timeout in {max(0.0, self.deadline - t):.1f} s")
        return ", ".join(parts)


def describe_event(ev: m.WaitEvent) -> str:
    if isinstance(ev, m.Detected):
        return ev.what.value
    if isinstance(ev, m.Infrared | m.Radar):
        side = "any" if ev.direction is None else ev.direction.name.lower()
        return f"{type(ev).__name__.lower()} {side}"
    if isinstance(ev, m.Delay):
        return f"delay {ev.ms:g} ms"
    if isinstance(ev, m.Random):
        return f"random {ev.min_ms:g}..{ev.max_ms:g} ms"
    if isinstance(ev, m.UserEvent):
        return f"user event {ev.id}"
    if isinstance(ev, m.BatteryCharge):
        return f"battery >= {ev.limit:g} %"
    if isinstance(ev, m.Date):
        fields = ("year", "month", "day", "hour", "minute", "second")
        return "date " + " ".join(f"{f}={getattr(ev, f)}" for f in fields if getattr(ev, f) is not None)
    return {m.Collision: "collision", m.LostLocalization: "lost localization", m.TargetReached: "target"}[type(ev)]


def enter(wait: m.Wait, t: float, now: float, rng: random.Random) -> PendingWait:
    ev = wait.event
    until = None
    if isinstance(ev, m.Delay):
        until = t + ev.ms / 1000.0
    elif isinstance(ev, m.Random):
        until = t + rng.uniform(ev.min_ms, ev.max_ms) / 1000.0
    deadline = None if wait.timeout_ms is None else t + wait.timeout_ms / 1000.0
    return PendingWait(wait, t, until, deadline, now)


def event_holds(p: PendingWait, t: float, now: float, sensors: Sensors, events: frozenset[str]) -> bool:
    ev = p.wait.event
    if ev is None:  # E-XML-019: an empty wait waits for its timeout only
        return False
    if p.until is not None:
        return t >= p.until
    if isinstance(ev, m.Date):
        reached = _date_reached(ev, sensors, p.last_now, now)
        p.last_now = now
        return reached
    if isinstance(ev, m.UserEvent):
        return ev.id in events
    return _CONDITIONS[type(ev)](ev, sensors)


def timed_out(p: PendingWait, t: float) -> bool:
    return p.deadline is not None and t >= p.deadline


def _matches(d: m.Date, at: datetime.datetime) -> bool:
    pairs = (
        (d.year, at.year),
        (d.month, at.month),
        (d.day, at.day),
        (d.hour, at.hour),
        (d.minute, at.minute),
        (d.second, at.second),
    )
    return all(want is None or want == have for want, have in pairs)


def _date_reached(d: m.Date, sensors: Sensors, before: float, now: float) -> bool:
    """Whether a whole second of local time in (before, now] - or ``now`` itself on entry - matches."""
    start = sensors.local_time(before).replace(microsecond=0)
    end = sensors.local_time(now).replace(microsecond=0)
    steps = int((end - start).total_seconds())
    first = 1 if now > before else 0
    first = max(first, steps - MAX_DATE_STEPS)
    return any(_matches(d, start + datetime.timedelta(seconds=k)) for k in range(first, steps + 1))


_CONDITIONS: dict[type[Any], Callable[[Any, Sensors], bool]] = {
    m.Collision: lambda ev, s: s.collision(),
    m.Detected: lambda ev, s: s.detected(ev.what),
    m.LostLocalization: lambda ev, s: s.localization_lost(),
    m.TargetReached: lambda ev, s: s.target_reached(),
    m.Infrared: lambda ev, s: s.infrared(ev.direction),
    m.Radar: lambda ev, s: s.radar(ev.direction),
    m.BatteryCharge: lambda ev, s: s.battery_percent() >= ev.limit,  # E-XML-024: at or above the limit
}
