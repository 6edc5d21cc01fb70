"""The control loop without a clock (reference_server/control_loop.py): wall-clock readings in, whole ticks out."""

from __future__ import annotations

import logging
import random

import pytest

from pltf.reference_server.control_loop import BURST, CONTROL_PERIOD, MAX_CATCH_UP, ControlLoop


class Ticks:
    """A platform that only records when it was ticked."""

    def __init__(self) -> None:
        self.times: list[float] = []

    def tick(self, now: float) -> None:
        self.times.append(now)


def consecutive(times: list[float]) -> bool:
    return all(abs(t - (k + 1) * CONTROL_PERIOD) < 1e-9 for k, t in enumerate(times))


@pytest.mark.parametrize("scale", [1.0, 10.0, 20.0])
def test_ticks_come_at_whole_periods_one_after_another_however_late_the_readings(scale: float) -> None:
    rng, ticked = random.Random(int(scale)), Ticks()
    loop = ControlLoop(ticked, scale, wall=100.0)
    wall = 100.0
    for _ in range(2000):
        wall += rng.uniform(0.0, 0.03)  # a timer that wakes late, reads between timer wake-ups
        backlog = int(loop.sim(wall) / CONTROL_PERIOD) - loop.ticks
        now = loop.now(wall)
        last = ticked.times[-1] if ticked.times else 0.0  # the state a command at ``now`` meets
        assert last <= now + 1e-9 < last + CONTROL_PERIOD
        # caught up: the clock's time; more than a burst behind: the platform's own, a burst further on
        assert now == pytest.approx(loop.sim(wall) if backlog <= BURST else last)
    assert consecutive(ticked.times)
    assert loop.held == 0.0


def test_a_reading_between_two_timer_wake_ups_runs_the_ticks_due_first() -> None:
    ticked = Ticks()
    loop = ControlLoop(ticked, 20.0, wall=0.0)
    assert loop.now(0.0) == 0.0 and ticked.times == []
    now = loop.now(0.0101)  # 0.202 s simulated: ten periods due, whatever the timer did
    assert now == pytest.approx(0.202) and len(ticked.times) == 10 and consecutive(ticked.times)
    assert loop.next_tick == pytest.approx(0.22)
    assert loop.wall_at(loop.next_tick) == pytest.approx(0.011)


def test_a_telegram_runs_a_late_timers_ticks_but_leaves_a_backlog_to_the_timer() -> None:
    ticked = Ticks()
    loop = ControlLoop(ticked, 20.0, wall=0.0)
    assert loop.now(0.0101, burst=0) == pytest.approx(0.202)  # ten periods due: a late timer, run at once
    assert len(ticked.times) == 10
    assert loop.now(0.1, burst=0) == pytest.approx(0.2)  # 90 due: the timer's; the time of the last tick
    assert len(ticked.times) == 10
    assert loop.now(0.1) == pytest.approx(0.2 + BURST * CONTROL_PERIOD)  # the timer: a burst
    assert len(ticked.times) == 10 + BURST and consecutive(ticked.times) and loop.held == 0.0


def test_a_backlog_is_worked_off_a_burst_per_reading_without_holding_the_time() -> None:
    ticked = Ticks()
    loop = ControlLoop(ticked, 1.0, wall=0.0)
    wall = MAX_CATCH_UP * CONTROL_PERIOD + 0.001  # blocked for 10 wall s, just within the limit
    readings = [loop.now(wall)]
    assert len(ticked.times) == BURST and readings[0] == pytest.approx(BURST * CONTROL_PERIOD)
    while len(readings) < 100 and readings[-1] < loop.sim(wall):
        readings.append(loop.now(wall))
    assert len(readings) == MAX_CATCH_UP // BURST and readings[-1] == pytest.approx(wall)
    assert readings == sorted(readings) and consecutive(ticked.times) and len(ticked.times) == MAX_CATCH_UP
    assert loop.held == 0.0


def test_a_blocked_loop_holds_the_simulated_time_and_never_hands_over_a_longer_step(
    caplog: pytest.LogCaptureFixture,
) -> None:
    ticked = Ticks()
    loop = ControlLoop(ticked, 20.0, wall=0.0)
    for k in range(1, 6):
        loop.now(0.02 * k + 0.0001)  # 2 s simulated, 20 periods a reading: 100 ticks
    assert len(ticked.times) == 100
    with caplog.at_level(logging.WARNING, logger="pltf.server"):
        now = loop.now(1.1)  # blocked for 1 wall s: 1000 periods due, more than MAX_CATCH_UP
    assert MAX_CATCH_UP < 1000
    assert len(ticked.times) == 101 and consecutive(ticked.times)  # one period more, not a 20 s step
    assert now == pytest.approx(2.02) and loop.held == pytest.approx(19.98)
    assert "simulated time was held" in caplog.text
    # from there the simulated time runs on at the time scale, from where it stood
    while loop.now(1.2005) < 4.0:
        pass
    assert loop.now(1.2005) == pytest.approx(2.02 + 2.01)
    assert len(ticked.times) == 201 and consecutive(ticked.times) and loop.held == pytest.approx(19.98)


def test_beyond_what_the_machine_simulates_the_time_runs_slower_in_whole_periods() -> None:
    """Time scale 100 with a reading every 15 wall ms on average: 75 periods due per reading, 25 run (as if each
    reading took the machine that long): the simulated time is held now and then, every step stays one period."""
    rng, ticked = random.Random(5), Ticks()
    loop = ControlLoop(ticked, 100.0, wall=0.0)
    wall, readings = 0.0, []
    for _ in range(500):
        wall += rng.uniform(0.0, 0.03)
        readings.append(loop.now(wall))
    assert consecutive(ticked.times) and len(ticked.times) <= 500 * BURST
    assert readings == sorted(readings) and readings[-1] <= loop.sim(wall) + 1e-9
    assert loop.held > 0.0 and loop.sim(wall) == pytest.approx(wall * 100.0 - loop.held)


def test_a_stepped_clock_advances_by_whole_periods() -> None:
    ticked = Ticks()
    loop = ControlLoop(ticked, 1.0, wall=0.0)
    loop.advance(0.1)
    loop.advance(0.1)
    assert len(ticked.times) == 5 and consecutive(ticked.times)


@pytest.mark.parametrize("scale", [0.0, -1.0, float("inf"), float("nan")])
def test_a_time_scale_must_be_positive_and_finite(scale: float) -> None:
    with pytest.raises(ValueError, match="time scale"):
        ControlLoop(Ticks(), scale, wall=0.0)


def test_the_platform_boots_at_the_time_the_loop_begins_and_no_tick_comes_before() -> None:
    ticked = Ticks()
    loop = ControlLoop(ticked, 10.0, wall=5.0)
    assert loop.begin(5.0071) == pytest.approx(0.071)  # the server's start-up took 7 wall ms
    assert ticked.times == [] and loop.next_tick == pytest.approx(0.08)
    loop.now(5.0101)
    assert ticked.times == pytest.approx([0.08, 0.10])
