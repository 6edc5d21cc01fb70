"""verdict: the oracle of one finished unit, confirmation by replay, and when a target is gone (no sockets)."""

from __future__ import annotations

import pytest

from pltf.fuzz.target import CUT, Outcome
from pltf.fuzz.verdict import (
    BAD_REPLY,
    DROPPED,
    NOT_ADMITTED,
    OK,
    TIMED_OUT,
    Liveness,
    confirm,
    confirmed,
    judge,
)


def outcome(replies: int = 0, got: int | None = None, **flags: object) -> Outcome:
    """An outcome with ``replies`` decoded replies (the oracle counts them) and ``got`` bytes received."""
    out = Outcome(replies=[object() for _ in range(replies)], **flags)  # type: ignore[arg-type, misc]
    out.got = 100 * replies if got is None else got
    return out


@pytest.mark.parametrize(
    ("out", "owed", "keep", "kind", "how"),
    [
        (outcome(refused=True), 1, True, NOT_ADMITTED, "refused"),  # nobody listens (or a closed listener)
        (outcome(closed=True), 1, True, NOT_ADMITTED, "closed"),  # accepted and closed (or reset) unread
        (outcome(timed_out=True), 1, True, NOT_ADMITTED, "timed-out"),  # left in the listen backlog
        (outcome(replies=3, closed=True), 3, True, OK, ""),
        (outcome(replies=1, closed=True), 3, True, DROPPED, ""),  # served, then closed on accepted frames
        (outcome(replies=1, closed=True), 1, False, OK, ""),  # a case the target should refuse: the close is right
        (outcome(replies=1, timed_out=True), 1, False, TIMED_OUT, ""),
        (outcome(replies=1, bad_reply="reply does not decode: x"), 1, True, BAD_REPLY, ""),
        (outcome(got=5, bad_reply="reply does not decode: x"), 1, True, BAD_REPLY, ""),  # garbage is an answer
    ],
)
def test_judge(out: Outcome, owed: int, keep: bool, kind: str, how: str) -> None:
    v = judge(out, owed, led=True, keep=keep)
    assert (v.kind, v.how) == (kind, how)
    assert v.suspicious == (kind in (DROPPED, TIMED_OUT, BAD_REPLY))


def test_a_reply_cut_by_the_close_on_a_refused_case_is_counted_not_suspected() -> None:
    out = outcome(replies=1, bad_reply=f"{CUT}: 3 bytes", closed=True)
    assert judge(out, 1, led=True, keep=False).cut
    assert judge(out, 1, led=True, keep=True).kind == BAD_REPLY  # after accepted frames it is a bad reply


def test_without_a_lead_nothing_back_is_not_a_turn_away() -> None:
    assert judge(outcome(closed=True), 0, led=False, keep=False).kind == OK


def test_confirm_stops_as_soon_as_the_answer_is_known() -> None:
    calls: list[int] = []

    def replay(results: list[str]) -> object:
        def one() -> str | None:
            calls.append(1)
            return results[len(calls) - 1]

        return one

    seen = confirm(DROPPED, replay([DROPPED, DROPPED, OK]))  # type: ignore[arg-type]
    assert seen == [DROPPED, DROPPED] and confirmed(DROPPED, seen)
    calls.clear()
    seen = confirm(DROPPED, replay([OK, OK, DROPPED]))  # type: ignore[arg-type]
    assert seen == [OK, OK] and not confirmed(DROPPED, seen)  # two clean replays: it cannot reach two of three
    calls.clear()
    seen = confirm(DROPPED, replay([DROPPED, OK, DROPPED]))  # type: ignore[arg-type]
    assert seen == [DROPPED, OK, DROPPED] and confirmed(DROPPED, seen)
    calls.clear()
    seen = confirm(DROPPED, replay([DROPPED, None, DROPPED]))  # type: ignore[arg-type]
    assert seen == [DROPPED] and not confirmed(DROPPED, seen)  # the replay could not run: not believed


def test_liveness_dead_hang_deaf_and_a_stuck_port() -> None:
    live = Liveness(ports=2, patience=1.0, now=0.0)
    live.turned_away(0, "refused", 0.5)
    assert live.verdict(5.0) is None  # port 1 has not failed: alive
    live.turned_away(1, "closed", 0.6)
    assert live.verdict(0.9) is None  # not yet for long enough
    assert live.verdict(1.1) == "dead"
    live = Liveness(ports=2, patience=1.0, now=0.0)
    live.turned_away(0, "refused", 0.5)
    live.turned_away(0, "closed", 0.6)  # refused once: a dying process resets its last connections, then is gone
    live.turned_away(1, "closed", 0.6)
    assert live.verdict(2.0) == "dead"
    live = Liveness(ports=2, patience=1.0, now=0.0)
    live.turned_away(0, "timed-out", 0.5)
    live.turned_away(1, "timed-out", 0.5)
    assert live.verdict(2.0) == "hang"
    live = Liveness(ports=2, patience=1.0, now=0.0)
    live.turned_away(0, "closed", 0.5)
    live.turned_away(1, "closed", 0.5)
    assert live.verdict(2.0) == "deaf"
    live = Liveness(ports=2, patience=1.0, now=0.0)
    live.turned_away(1, "closed", 0.5)
    live.admitted(0, 1.2)
    assert live.stuck(1.4) is None  # port 1 has not served us for 0.9 s only
    assert live.stuck(1.6) == 1 and live.verdict(1.6) is None  # port 0 serves, port 1 has not for 1.1 s
    live.admitted(1, 1.5)
    assert live.stuck(3.0) is None
