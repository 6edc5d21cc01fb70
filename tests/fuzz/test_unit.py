"""unit: what one verdict covers and the session that carries it (no sockets)."""

from __future__ import annotations

from pltf.fuzz.case import Case, Delivery
from pltf.fuzz.target import GET_STATUS, LEAD
from pltf.fuzz.unit import PIPELINE_BYTES, Unit, window_units
from pltf.fuzz.wire import CLOSE, KEEP, frame, survey
from pltf.spec.codec import REQUESTS, encode

STATUS_ID = REQUESTS.CMD_GET_STATUS.ID
POSITION_ID = REQUESTS.CMD_GET_POSITION.ID
POSITION = encode(REQUESTS.CMD_GET_POSITION())
START = encode(REQUESTS.CMD_START())


WHOLE = Delivery()


def case(*frames: bytes, delivery: Delivery = WHOLE) -> Case:
    kind, answered = survey(b"".join(frames))
    return Case(tuple(frames), "gen.boundary", "x", expect=kind, answered=tuple(answered), delivery=delivery)


def test_a_batch_opens_with_the_lead_then_its_prelude_and_check_and_owes_every_reply() -> None:
    assert LEAD == POSITION  # the cheapest request a server answers
    unit = Unit([case(POSITION), case(encode(REQUESTS.CMD_STOP()))], [START], ("running", 0))
    s = unit.session()
    assert s.frames == [LEAD, START, GET_STATUS, POSITION, encode(REQUESTS.CMD_STOP())]
    assert s.led and s.half_close and s.sync and not s.gate
    assert s.answered == [POSITION_ID, STATUS_ID, POSITION_ID]
    assert unit.check_at == 1  # the lead's reply, then the check's
    assert unit.owed(s, 4) == 4  # lead, check, position, sync
    assert unit.batch and unit.keep and unit.whole


def test_a_refused_single_owes_the_replies_before_it_and_a_big_one_is_gated() -> None:
    bad = frame(b"\xfe")  # unknown id: the target closes
    small = Unit([case(bad)])
    s = small.session()
    assert s.frames == [LEAD, bad] and not s.gate and not s.sync
    assert small.owed(s, 1) == 1 and not small.keep and not small.batch
    big = Unit([case(frame(b"\xfe" + bytes(PIPELINE_BYTES)))])
    assert big.session().gate and big.owed(big.session(), 1) == 1  # the rest waits for the lead's reply
    slow = Unit([case(bad, delivery=Delivery("slow", 4, 0.01))])
    assert slow.session().gate and slow.session().delivery.mode == "slow" and not slow.whole


def test_a_unit_that_runs_again_is_gated_and_a_kept_connection_has_no_lead() -> None:
    unit = Unit([case(POSITION)])
    assert not unit.session().gate
    unit.tries = 1
    assert unit.session().gate
    kept = unit.session(lead=False, kept=True)
    assert kept.frames == [POSITION] and not kept.half_close and kept.sync and not kept.led


def test_a_lead_alone_proves_a_port_serves() -> None:
    unit = Unit([])
    s = unit.session()
    assert s.frames == [LEAD] and not s.sync and s.half_close and not unit.keep and not unit.batch
    assert unit.owed(s, 1) == 1  # the lead's reply, nothing else (a GET_STATUS may be slow on a target)
    assert survey(s.data) == (KEEP, [POSITION_ID]) and survey(frame(b"\xfe"))[0] == CLOSE


def test_a_window_becomes_batches_among_singles_the_first_batch_behind_the_prelude() -> None:
    accepted = [case(POSITION) for _ in range(300)]
    refused = [case(frame(b"\xfe")) for _ in range(10)]
    start = encode(REQUESTS.CMD_START())
    cases = [c for pair in zip(accepted[:10], refused, strict=True) for c in pair] + accepted[10:]
    units = window_units(cases, lambda: [start], ("running", 0), lambda c: [start] if c is refused[3] else [])
    batches = [u for u in units if u.batch]
    assert [len(u.cases) for u in batches] == [128, 128, 44]  # BATCH_CASES at most
    assert batches[0].prelude == [start] and batches[0].target == ("running", 0)
    assert not batches[1].prelude and not batches[2].prelude
    singles = [u for u in units if not u.batch]
    assert [u.cases[0] for u in singles] == refused  # in their order
    assert [bool(u.prelude) for u in singles] == [k == 3 for k in range(10)]
    assert units.index(batches[0]) > 0 and units[-1] is batches[-1]  # spread among the singles
    asked: list[int] = []
    only = window_units(refused, lambda: asked.append(1) or [start], ("ready", 0), lambda c: [])  # type: ignore[func-returns-value]
    assert len(only) == 10 and not any(u.batch or u.prelude for u in only) and not asked  # no batch: it waits


def test_rarest_keeps_the_singles_whose_telegrams_ran_least_and_every_id_comes_round() -> None:
    """On a dear target only some singles of a window run: the rare telegrams (an unknown id) first, in order."""
    import collections

    from pltf.fuzz.unit import rarest

    def single(ident: int) -> Unit:
        name = REQUESTS.by_id[ident].NAME if ident in REQUESTS.by_id else f"id {ident}"
        return Unit([Case((frame(bytes([ident, 0])),), "gen.any_id", name, expect=CLOSE)])

    seen: collections.Counter[str] = collections.Counter()
    common = [single(STATUS_ID) for _ in range(6)]
    window = [*common[:3], single(77), *common[3:], single(177)]
    kept = rarest(window, 3, seen)
    assert [u.cases[0].telegram for u in kept] == ["CMD_GET_STATUS", "id 77", "id 177"]
    assert kept[1] is window[3] and kept[2] is window[-1]  # in their order, the others skipped
    assert seen == {"CMD_GET_STATUS": 1, "id 77": 1, "id 177": 1}
    ids = range(200, 256)  # a window of 56 ids, 8 run per window: each one runs within 7 windows
    ran: set[str] = set()
    for _ in range(7):
        ran.update(u.cases[0].telegram for u in rarest([single(i) for i in ids], 8, seen))
    assert ran == {f"id {i}" for i in ids}
    assert rarest(window[:2], 3, seen) == window[:2]  # room for all: all run
