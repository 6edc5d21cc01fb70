"""The platform at every time scale, sans-IO: the platform ``pltf serve`` runs (world, CAN boards, task interpreter)
driven with explicit simulated times, as reference_server/network.py drives it.

The time scale reaches the platform only through when things happen in simulated time: a client's round trip of
20 wall ms is 0.02 simulated s at time scale 1 and 0.2 s at time scale 10, and the shell's timer wakes late by
wall milliseconds. Issue 23 (``6.3/CMD_SHUTDOWN_PLTF/halts-motion`` failed at time scale 1 only) was the first:
the case restarted the platform 30 ms after CMD_SHUTDOWN_PLTF, while it still braked without its CAN bus, and
took the rest of the braking for a resumed move. The second is the control loop's (reference_server/control_loop.py).
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from pltf.reference_server.cli import build_platform
from pltf.reference_server.commands import Outcome
from pltf.reference_server.control_loop import ControlLoop
from pltf.reference_server.platform import Platform
from pltf.reference_server.storage import Storage
from pltf.spec.codec import REQUESTS
from pltf.spec.model import enum_classes

R: Any = REQUESTS
MotionMode: Any = enum_classes()["MotionMode"]
OperationState: Any = enum_classes()["OperationState"]
STOP_WITHIN = 3.0  # simulated s the conformance suite gives a halted platform to stop (conformance_tests motion)
RAMP = 2000.0  # mm/s^2: the motor boards' ramp (fake_hardware MotorParams.acc_limit), the gentlest way they stop


@pytest.fixture
def make_platform(tmp_path: Path) -> Iterator[Callable[[], Platform]]:
    made: list[Platform] = []

    def make() -> Platform:
        storage = Storage(tmp_path / f"data{len(made)}")
        storage.seed_from_fixtures()
        p = build_platform(storage, 1)
        p.boot(0.0)
        made.append(p)
        return p

    yield make
    for p in made:
        p.close()


class Driver:
    """Telegrams at given simulated times, the platform ticked up to each first (a stepped clock)."""

    def __init__(self, p: Platform) -> None:
        self.p, self.loop, self.t = p, ControlLoop(p, 1.0, 0.0), 0.0

    def at(self, t: float, *telegrams: Any) -> list[Outcome]:
        self.loop.advance(t)
        self.t = t
        return [self.p.handle(tel, t) for tel in telegrams]

    def true_speed(self) -> float:
        """mm/s of the body over the next control period (the truth, which no telegram reports)."""
        a = self.p.motion.true_pose
        self.at(self.t + 0.02)
        b = self.p.motion.true_pose
        return math.hypot(b.x - a.x, b.y - a.y) / 0.02

    def estimate(self) -> tuple[float, float]:
        pos = self.p.motion.pose
        return pos.x, pos.y


def moving(d: Driver) -> None:
    """Running in Automatic, a MOVE_ABS 600 mm ahead under way at about 400 mm/s (the case's ``_moving``)."""
    d.at(0.0, R.CMD_CONNECT_TO_PLTF(), R.CMD_INIT_PLTF())
    d.at(1.0, R.CMD_SET_MODE(mode=MotionMode.MODE_MOTION_AUTOMATIC), R.CMD_START())
    start = d.estimate()
    d.at(1.5, R.CMD_MOVE_ABS(x=round(start[0]) + 600, y=round(start[1]), angle=0))
    t = 1.5
    while d.p.motion.v < 380.0:
        t += 0.02
        d.at(t)


def restart(d: Driver, t: float, gap: float) -> float:
    """CONNECT + INIT at ``t``, START once Ready, each request ``gap`` simulated s after the one before (the
    client's round trip times the time scale); the simulated time of the START."""
    d.at(t, R.CMD_CONNECT_TO_PLTF(), R.CMD_INIT_PLTF())
    while d.p.chart.state.value != "ready":
        t += gap
        d.at(t)
    d.at(t + gap, R.CMD_START())
    return t + gap


@pytest.mark.parametrize(("scale", "gap"), [(1, 0.015), (10, 0.15)])
def test_a_shutdown_brakes_the_platform_blind_and_a_restart_never_resumes_the_old_move(
    make_platform: Callable[[], Platform], scale: int, gap: float
) -> None:
    d = Driver(make_platform())
    moving(d)
    v0, t0, at_shutdown = d.p.motion.v, d.t, d.p.motion.true_pose
    d.at(t0, R.CMD_SHUTDOWN_PLTF())
    status: Any = d.p.handle(R.CMD_GET_STATUS(), t0 + 0.02).reply
    assert status is not None
    # guide 6.3 "shutdown the CAN communication": no encoder frames (E-HW-004), no odometry - the status cannot
    # show that the body still brakes; a client sees "at rest" at once
    assert (status.operation_state, status.vel_trans) == (OperationState.ST_OP_NOT_INITIALIZED, 0)
    assert d.true_speed() > 100.0, "the motor boards cannot stop 400 mm/s within one control period"
    t_start = restart(d, d.t + gap, gap)
    at_start = d.true_speed()
    if scale == 1:  # the restart comes while the body still brakes (issue 23): it rolls on after CMD_START ...
        assert at_start > 20.0
    else:  # ... while a client ten times slower in simulated time restarts a platform that has stopped
        assert at_start == 0.0
    d.at(t_start + 2.0)
    assert d.true_speed() == 0.0
    # ... but only as far as stopping takes it (the brakes, at worst the boards' ramp, two periods late): the old
    # move, 450 mm further on, does not resume
    true = d.p.motion.true_pose
    assert math.hypot(true.x - at_shutdown.x, true.y - at_shutdown.y) <= v0 * v0 / (2 * RAMP) + v0 * 0.04


@pytest.mark.parametrize("gap", [0.015, 0.15, 0.3])
def test_restarted_after_the_stopping_time_the_platform_stands_at_every_client_speed(
    make_platform: Callable[[], Platform], gap: float
) -> None:
    """The case's fix: after CMD_SHUTDOWN_PLTF it waits STOP_WITHIN simulated s before the restart, so the
    platform it restarts stands, whatever the time scale made of the client's round trips."""
    d = Driver(make_platform())
    moving(d)
    t0 = d.t
    d.at(t0, R.CMD_SHUTDOWN_PLTF())
    t_start = restart(d, t0 + STOP_WITHIN, gap)
    d.at(t_start + gap)
    before = d.estimate()
    d.at(t_start + gap + 1.0)
    after = d.estimate()
    assert math.hypot(after[0] - before[0], after[1] - before[1]) < 1.0
    assert d.p.motion.v == 0.0


# ---------------------------------------------------------------- the same scenario at every time scale


class Shell:
    """reference_server/network.py's use of the control loop on a virtual wall clock: a timer that wakes up to
    ``late`` wall s after each tick is due (seeded, ``SimClock.work``), and telegrams handed to the platform at the
    clock's reading (``SimClock.now``)
    (``stale``: at the simulated time without running the ticks due - the shell before the control loop's rule)."""

    def __init__(self, p: Platform, scale: float, late: float = 0.015, stale: bool = False) -> None:
        self.p, self.stale = p, stale
        self.loop = ControlLoop(p, scale, wall=0.0)
        self.rng, self.late = random.Random(7), late
        self.timer = self.loop.wall_at(self.loop.next_tick) + self.rng.uniform(0.0, late)

    def at(self, t: float, telegram: Any) -> Outcome:
        wall = self.loop.wall_at(t)
        while self.timer <= wall:
            self.loop.now(self.timer)
            self.timer = self.loop.wall_at(self.loop.next_tick) + self.rng.uniform(0.0, self.late)
        now = self.loop.sim(wall) if self.stale else self.loop.now(wall, burst=0)  # network.SimClock.now
        return self.p.handle(telegram, now)


def scenario() -> list[tuple[float, Any]]:
    """Issue 23's sequence and velocity commands, with GET_STATUS every 50 simulated ms."""
    auto, vel = MotionMode.MODE_MOTION_AUTOMATIC, MotionMode.MODE_MOTION_VEL
    steps: list[tuple[float, Any]] = [
        (0.0, R.CMD_CONNECT_TO_PLTF()),
        (0.0, R.CMD_INIT_PLTF()),
        (1.0, R.CMD_SET_MODE(mode=auto)),
        (1.0, R.CMD_START()),
        (1.5, R.CMD_MOVE_ABS(x=2600, y=10000, angle=0)),
        (2.107, R.CMD_SHUTDOWN_PLTF()),
        (2.131, R.CMD_CONNECT_TO_PLTF()),
        (2.131, R.CMD_INIT_PLTF()),
        (2.163, R.CMD_START()),
        (3.5, R.CMD_STOP()),
        (3.5, R.CMD_SET_MODE(mode=vel)),
        (3.51, R.CMD_START()),
        *[(3.6 + 0.1 * k, R.CMD_MOVE_VEL(vel_trans=300, vel_rot=200)) for k in range(10)],
        (4.65, R.CMD_BREAK()),
    ]
    steps += [(0.05 * k + 0.001, R.CMD_GET_STATUS()) for k in range(110)]
    # off the control periods' grid: a time on it is a tick's or the next one's by a rounding error
    return sorted(((t + 0.0071, telegram) for t, telegram in steps), key=lambda s: s[0])


def run(p: Platform, scale: float, stale: bool = False) -> list[bytes]:
    shell = Shell(p, scale, stale=stale)
    frames = []
    for t, telegram in scenario():
        outcome = shell.at(t, telegram)
        if outcome.frame is not None:
            frames.append(outcome.frame)
    return frames


def test_the_same_commands_at_the_same_simulated_times_give_the_same_replies_at_every_time_scale(
    make_platform: Callable[[], Platform],
) -> None:
    one = run(make_platform(), 1.0)
    assert len(one) == 110
    for scale in (10.0, 20.0):
        other = run(make_platform(), scale)
        first = next((i for i, (a, b) in enumerate(zip(one, other, strict=True)) if a != b), None)
        assert first is None, f"time scale {scale:g}: GET_STATUS {first} differs from time scale 1"


def test_without_running_the_ticks_due_first_a_late_timer_changed_the_outcome(
    make_platform: Callable[[], Platform],
) -> None:
    """The shell before reference_server/control_loop.py: a telegram met the state the last timer wake-up left;
    the same scenario then depended on the time scale (wake-ups 15 ms late are 7 periods at time scale 10)."""
    assert run(make_platform(), 1.0, stale=True) != run(make_platform(), 10.0, stale=True)
