"""trial.py: the dear way is kept only when it measured clearly faster; a target that turns newcomers away
settles it without a trial."""

from __future__ import annotations

from pltf.fuzz.trial import GAIN, SINGLES_KEPT, WARMUP, WINDOWS, Trial


def run(trial: Trial, fresh: float, dear: float, windows: int, singles: tuple[float, float] = (0, 0)) -> list[bool]:
    """Record ``windows`` windows at the given cases per second (``singles``: of them singles, fresh and dear);
    the ways they ran."""
    ways = []
    for _ in range(windows):
        way = trial.way()
        ways.append(way)
        trial.record(way, round(0.1 * (dear if way else fresh)), 0.1, singles=round(0.1 * singles[way]))
    return ways


def test_the_trial_alternates_after_the_warm_up_and_keeps_the_faster_way() -> None:
    t = Trial()
    ways = run(t, fresh=1000, dear=2000, windows=WARMUP + 2 * WINDOWS)
    assert ways[:WARMUP] == [False] * WARMUP
    assert ways[WARMUP:] == [False, True] * WINDOWS  # alternating: a noisy spell hits both
    assert t.decided is True and t.way() is True
    assert t.rates == {"fresh": 1000.0, "dear": 2000.0, "fresh singles": 0.0, "dear singles": 0.0}


def test_the_dear_way_must_pay_for_the_singles_it_skips() -> None:
    t = Trial()
    run(t, fresh=1000, dear=1000 * GAIN * 0.95, windows=WARMUP + 2 * WINDOWS)
    assert t.decided is False and t.way() is False
    assert run(t, fresh=1, dear=1000, windows=4) == [False] * 4  # decided: no more trial


def test_the_dear_way_must_not_give_up_the_singles_even_when_it_is_faster() -> None:
    """The fragile server of tests/fuzz: kept, it serves twice the cases per second but a sixth of the singles
    (the dear way skips them); a stall behind an unknown id would go unseen. Fresh connections are kept."""
    t = Trial()
    run(t, fresh=2000, dear=4500, windows=WARMUP + 2 * WINDOWS, singles=(600, 100))
    assert t.decided is False
    assert t.rates["fresh singles"] == 600 and t.rates["dear singles"] == 100
    t = Trial()  # the accept-once relay: the kept way serves singles on the other port as fast
    run(t, fresh=500, dear=900, windows=WARMUP + 2 * WINDOWS, singles=(400, 400 * SINGLES_KEPT))
    assert t.decided is True


def test_a_target_that_turns_newcomers_away_settles_it() -> None:
    t = Trial()
    t.settle(True)
    assert run(t, fresh=5000, dear=1, windows=20) == [True] * 20
    assert t.seen == 0


def test_the_next_way_is_known_ahead_so_a_window_is_credited_with_its_own_cases() -> None:
    t = Trial()
    nexts = []
    for _ in range(WARMUP + 2 * WINDOWS):
        nexts.append(t.next_way())
        t.record(t.way(), 100, 0.1, singles=50)
    ways = [False] * WARMUP + [False, True] * WINDOWS
    assert nexts == [*ways[1:], t.decided]
    assert not t.settled
    t.settle(True)
    assert t.settled and t.next_way() is True
