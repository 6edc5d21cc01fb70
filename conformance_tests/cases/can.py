"""Guide 6.3 CAN communication commands: listening ids, the message buffer, boards (outputs, brakes, ultrasonic).

Rules of this module: the suite cannot make CAN traffic appear (it never assumes a simulator-only channel), so
it listens on every 11-bit id (erratum E-CMD-006) and checks what the target's own bus carries; when the bus is
silent the buffer cases are N/A. Listening ids are removed again at the end, which also clears ids another
client had added (noted in the report).
"""

from __future__ import annotations

import itertools
from typing import Any

from pltf.conformance_tests.cases._common import no_unsolicited
from pltf.conformance_tests.catalogue import Level, case
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import Fail, NotApplicable
from pltf.spec.codec import build

ALL_IDS = range(2048)
_BUFFER = (
    'guide 6.3 CMD_ADD_CAN_LISTENING_ID: "Add a CAN-ID to the receive list. All messages with CAN-IDs of '
    'the list will be buffered and sent on request."; CMD_GET_CAN_MESSAGES: "0: The message is kept, '
    '1: The received message will be deleted"'
)


def _listen(ctx: CaseContext, ids: range, add: bool = True) -> None:
    name = "CMD_ADD_CAN_LISTENING_ID" if add else "CMD_REMOVE_CAN_LISTENING_ID"
    ctx.session().send_many([build("request", name, can_id=i) for i in ids], f"{len(ids)} x {name}")


def _listen_all(ctx: CaseContext) -> None:
    ctx.note("all 2048 CAN listening ids were added and removed again (ids other clients had added are gone)")
    ctx.on_exit("remove the CAN listening ids", lambda: _listen(ctx, ALL_IDS, add=False))
    _listen(ctx, ALL_IDS)


def _messages(ctx: CaseContext, delete: int) -> tuple[Any, ...]:
    return ctx.get("CMD_GET_CAN_MESSAGES", delete=delete).messages  # type: ignore[attr-defined, no-any-return]


def _traffic(ctx: CaseContext) -> tuple[Any, ...]:
    ctx.ready()
    _listen_all(ctx)
    _messages(ctx, 1)
    msgs = ctx.poll(lambda: _messages(ctx, 0), lambda m: len(m) > 0, within=2.0)
    if not msgs:
        raise NotApplicable("no CAN message arrived on any id within 2 s: the target's bus is silent")
    return msgs


def _newest(msgs: tuple[Any, ...]) -> list[Any]:
    newest = max(m.timestamp for m in msgs)
    return [m for m in msgs if m.timestamp == newest]


@case(
    "6.3/CMD_GET_CAN_MESSAGES/keep-and-delete",
    requirement=_BUFFER,
    telegrams=("CMD_ADD_CAN_LISTENING_ID", "CMD_GET_CAN_MESSAGES"),
)
def keep_and_delete(ctx: CaseContext) -> None:
    first = _traffic(ctx)
    second = _messages(ctx, 0)
    newest = max(m.timestamp for m in first)
    kept = [m for m in first if m.timestamp >= min((x.timestamp for x in second), default=newest)]
    missing = [m for m in kept if m not in second]
    # The newest message returned with 'keep' must still be there, unless newer traffic filled the whole buffer
    # in one round trip (a buffer drops its oldest first). Such an overflow is told from a buffer that deletes
    # on 'keep' by asking once more at once: two whole overflows back to back mean a buffer that cannot hold
    # one round trip's traffic, and it is judged as one that loses kept messages. (The count of messages is no
    # witness: on a loaded machine more traffic comes between two requests.)
    last = _newest(first)
    if not missing and not any(m in second for m in last):
        third = _messages(ctx, 0)
        if not second or not any(m in third for m in _newest(second)):
            missing = last
    if missing:
        raise Fail(f"{len(missing)} messages returned with 'keep' were gone at the next request")
    deleted = _messages(ctx, 1)
    after = _messages(ctx, 0)
    cut = max((m.timestamp for m in deleted), default=newest)
    stale = [m for m in after if m.timestamp <= cut and m in deleted]
    if stale:
        raise Fail(f"{len(stale)} messages returned with 'delete' were returned again")


@case(
    "6.3/CMD_REMOVE_CAN_LISTENING_ID/stops-buffering",
    requirement='guide 6.3 CMD_REMOVE_CAN_LISTENING_ID: "Removes a CAN-ID from the receive list" - its messages '
    "are no longer buffered",
    telegrams=("CMD_REMOVE_CAN_LISTENING_ID", "CMD_GET_CAN_MESSAGES"),
)
def stops_buffering(ctx: CaseContext) -> None:
    msgs = _traffic(ctx)
    ids = sorted({m.can_id for m in msgs})
    _listen(ctx, ALL_IDS, add=False)
    _messages(ctx, 1)
    ctx.sleep(1.0)
    late = _messages(ctx, 0)
    if late:
        raise Fail(
            f"{len(late)} messages (ids {sorted({m.can_id for m in late})[:5]}) were buffered after every "
            f"id was removed (traffic had been seen on {ids[:5]})"
        )


@case(
    "6.3/CMD_GET_CAN_MESSAGES/listened-ids-only",
    requirement=_BUFFER + " - and only those",
    telegrams=("CMD_ADD_CAN_LISTENING_ID", "CMD_GET_CAN_MESSAGES"),
)
def listened_only(ctx: CaseContext) -> None:
    msgs = _traffic(ctx)
    busiest = max({m.can_id for m in msgs}, key=lambda i: sum(1 for m in msgs if m.can_id == i))
    _listen(ctx, ALL_IDS, add=False)
    ctx.send("CMD_ADD_CAN_LISTENING_ID", can_id=busiest)
    _messages(ctx, 1)
    ctx.sleep(1.0)
    got = _messages(ctx, 1)
    others = sorted({m.can_id for m in got} - {busiest})
    if others:
        raise Fail(f"listening on id {busiest} only, messages of ids {others[:5]} were returned")
    if not got:
        raise NotApplicable(f"id {busiest} carried no message in the second period")


@case(
    "6.4/CMD_GET_CAN_MESSAGES/timestamps",
    errata=("E-REP-001",),
    requirement="erratum E-REP-001: the time stamp of a CAN message is seconds since the server started; the "
    "buffer lists messages in the order received (time stamps never decrease)",
    telegrams=("CMD_GET_CAN_MESSAGES",),
)
def timestamps(ctx: CaseContext) -> None:
    msgs = _traffic(ctx)
    stamps = [m.timestamp for m in msgs]
    if any(b < a for a, b in itertools.pairwise(stamps)):
        raise Fail(f"time stamps go backwards: {stamps[:8]}")
    if min(stamps) < 0:
        raise Fail(f"negative time stamp {min(stamps)}")
    if max(stamps) > 1e9:
        ctx.deviate("E-REP-001", 1, "time stamps look like UNIX epoch seconds")


@case(
    "6.3/CMD_SET_DIGOUT/sets-output",
    level=Level.MAY,
    switches_outputs=True,
    errata=("E-CMD-004",),
    requirement='guide 6.3 CMD_SET_DIGOUT: "Set one of the digital output channels"; 6.4 IO-Board \'Digital '
    "out'; erratum E-CMD-004: channels are 0-based (bit n = channel n). Optional hardware (guide 5.8: "
    'the IO board channels "are for general purpose and therefore optional")',
    telegrams=("CMD_SET_DIGOUT", "CMD_GET_STATUS"),
)
def sets_output(ctx: CaseContext) -> None:
    ctx.ready()
    channel = 3
    mask = ctx.status().telegram.io_digital_out  # type: ignore[attr-defined]
    old = (mask >> channel) & 1
    ctx.on_exit("restore digital output 3", lambda: ctx.send("CMD_SET_DIGOUT", board=0, channel=channel, value=old))
    ctx.send("CMD_SET_DIGOUT", board=0, channel=channel, value=1 - old)
    st = ctx.poll(lambda: ctx.status().telegram.io_digital_out, lambda m: m != mask, within=1.0)  # type: ignore[attr-defined]
    ctx.send("CMD_SET_DIGOUT", board=1, channel=15, value=0)  # relay board: no status to check it against
    if st == mask:
        raise NotApplicable("the IO board's digital out did not change: no IO board outputs on this target")
    if st ^ mask == 1 << channel:
        return
    if st ^ mask == 1 << (channel - 1):
        ctx.deviate("E-CMD-004", 0, f"channel {channel} switched bit {channel - 1} (1-based channels)")
        return
    raise Fail(f"setting channel {channel} changed digital out from {mask:#06x} to {st:#06x}")


@case(
    "6.3/CMD_SET_BRAKE/both-motors",
    switches_outputs=True,
    errata=("E-CMD-015",),
    requirement='guide 6.3 CMD_SET_BRAKE: "Sets the brakes of the drives" for CANNODE_MOTORRIGHT = 1 and '
    "CANNODE_MOTORLEFT = 2, 0 enabled, 1 disabled - accepted silently in Ready",
    telegrams=("CMD_SET_BRAKE",),
)
def both_motors(ctx: CaseContext) -> None:
    before = ctx.ready()
    for state in (0, 1):
        for motor in (1, 2):
            ctx.send("CMD_SET_BRAKE", motor=motor, state=state)
    after = ctx.status()
    if (after.op, after.mode) != (before.op, before.mode):
        raise Fail(f"CMD_SET_BRAKE changed the platform: {before.describe()} -> {after.describe()}")
    no_unsolicited(ctx, "CMD_SET_BRAKE")


@case(
    "6.3/CMD_START_ULTRASONIC/measures",
    level=Level.MAY,
    switches_outputs=True,
    errata=("E-CMD-005",),
    requirement='guide 6.3 CMD_START_ULTRASONIC: "Start the ultrasonic sensor measurement" (erratum E-CMD-005: '
    "a bit mask of the active sensors); 6.4 'Measured distances of the ultrasonic sensors'",
    telegrams=("CMD_START_ULTRASONIC", "CMD_STOP_ULTRASONIC", "CMD_GET_STATUS"),
)
def us_measures(ctx: CaseContext) -> None:
    ctx.ready()
    ctx.send("CMD_STOP_ULTRASONIC")
    ctx.send("CMD_START_ULTRASONIC", active_channels=0xFFFF)
    st = ctx.poll(lambda: ctx.status().telegram, lambda t: any(t.us_distance), within=2.0)  # type: ignore[attr-defined]
    if not any(st.us_distance):  # type: ignore[attr-defined]
        raise NotApplicable("no ultrasonic distance was reported after CMD_START_ULTRASONIC (no US board)")
