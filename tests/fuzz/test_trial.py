"""trial.py: the dear way is kept only when it measured clearly faster; a target that turns newcomers away
settles it without a trial."""

from __future__ import annotations

from pltf.fuzz.trial import GAIN, WARMUP, WINDOWS, Trial


def run(trial: Trial, fresh: float, dear: float, windows: int) -> list[bool]:
    """Record ``windows`` windows at the given cases per second; the ways they ran."""
    ways = []
    for _ in range(windows):
        way = trial.way()
        ways.append(way)
        trial.record(way, round(0.1 * (dear if way else fresh)), 0.1)
    return ways


def test_the_trial_alternates_after_the_warm_up_and_keeps_the_faster_way() -> None:
    t = Trial()
    ways = run(t, fresh=1000, dear=2000, windows=WARMUP + 2 * WINDOWS)
    assert ways[:WARMUP] == [False] * WARMUP
    assert ways[WARMUP:] == [False, True] * WINDOWS  # alternating: a noisy spell hits both
    assert t.decided is True and t.way() is True
    assert t.rates == {"fresh": 1000.0, "dear": 2000.0}


def test_the_dear_way_must_pay_for_the_singles_it_skips() -> None:
    t = Trial()
    run(t, fresh=1000, dear=1000 * GAIN * 0.95, windows=WARMUP + 2 * WINDOWS)
    assert t.decided is False and t.way() is False
    assert run(t, fresh=1, dear=1000, windows=4) == [False] * 4  # decided: no more trial


def test_a_target_that_turns_newcomers_away_settles_it() -> None:
    t = Trial()
    t.settle(True)
    assert run(t, fresh=5000, dear=1, windows=20) == [True] * 20
    assert t.seen == 0
