"""pace.py: a batch on the kept connection owes the other port singles; the next batch waits for them unless
none waits."""

from __future__ import annotations

from pltf.fuzz.pace import TURN, Pace


def test_a_batch_owes_a_turn_of_singles_per_case() -> None:
    p = Pace(turn=0.35)
    assert [p.singles(n) for n in (0, 1, 20, 128)] == [0, 1, 7, 45]
    assert Pace().turn == TURN


def test_the_next_batch_waits_for_the_singles_owed_counting_those_served_meanwhile() -> None:
    p = Pace(turn=0.5)
    assert p.ready(singles_waiting=True)  # nothing owed before the first batch
    p.batch_started(8)
    assert p.owed == 4 and not p.ready(singles_waiting=True)
    for _ in range(3):
        p.single_served()
    assert not p.ready(singles_waiting=True)
    p.single_served()
    assert p.ready(singles_waiting=True)
    p.single_served()  # more singles than owed: nothing carried over to the next batch
    assert p.owed == 0
    p.batch_started(2)
    assert p.owed == 1 and p.batches == 2


def test_a_batch_never_waits_for_singles_that_are_not_there() -> None:
    p = Pace(turn=1.0)
    p.batch_started(128)
    assert not p.ready(singles_waiting=True)
    assert p.ready(singles_waiting=False)
