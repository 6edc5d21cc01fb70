"""Guide 6.2: the message format - header, length, split and coalesced frames, malformed input, half-close."""

from __future__ import annotations

import struct

from pltf.conformance_tests.cases._common import NO, MotionMode, far_frame
from pltf.conformance_tests.catalogue import Level, Tier, case
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import ConnectionClosed, Fail
from pltf.conformance_tests.wire import Session
from pltf.spec.codec import build, encode

VEL = MotionMode.MODE_MOTION_VEL


def _frame(name: str, **fields: object) -> bytes:
    return encode(build("request", name, **fields))


def _raw(hexdata: str) -> bytes:
    """A frame around ``hexdata`` (header and the right length): for telegrams the codec refuses to build."""
    data = bytes.fromhex(hexdata)
    return bytes.fromhex("ff01fe02") + struct.pack(">I", len(data)) + data


def _status(s: Session) -> object:
    return s.request(build("request", "CMD_GET_STATUS"))


@case(
    "6.2/framing/header-and-length",
    tier=Tier.SMOKE,
    errata=("E-WIRE-002", "E-WIRE-001"),
    requirement='guide 6.2: "every message consists of a header" FF 01 FE 02, then the number of data bytes N '
    "(MSB first), then the data; replies are framed the same way (E-WIRE-001)",
    telegrams=("CMD_GET_STATUS",),
)
def header_and_length(ctx: CaseContext) -> None:
    s = ctx.fresh()
    s.send_raw(bytes.fromhex("ff01fe02 00000001 12"), "CMD_GET_STATUS as captured")
    s.read_reply("CMD_GET_STATUS")


@case(
    "6.2/types/int-msb-first",
    tier=Tier.SMOKE,
    errata=("E-WIRE-005",),
    requirement='guide 6.2: "The data types are sent in the Motorola format with the most significant byte (MSB) '
    'first" - the captured CMD_SET_MODE(MODE_MOTION_VEL) frame ff01fe02 00000005 0f 00000003 sets '
    "mode 3",
    telegrams=("CMD_SET_MODE",),
)
def int_msb_first(ctx: CaseContext) -> None:
    ctx.ready()
    s = ctx.session()
    s.send_raw(bytes.fromhex("ff01fe02 00000005 0f 00000003"), "CMD_SET_MODE(3) as captured")
    st = ctx.poll(ctx.status, lambda x: x.mode == VEL, within=5.0)
    if st.mode != VEL:
        raise Fail(f"the captured CMD_SET_MODE(3) frame did not set MODE_MOTION_VEL: status says {st.describe()}")
    s.send_raw(bytes.fromhex("ff01fe02 00000005 0f 00000000"), "CMD_SET_MODE(0)")


def _split_round(ctx: CaseContext, s: Session, frame: bytes, k: int, check: str) -> None:
    gap = min(0.05, ctx.wall(0.02))
    s.send_chunks([frame[:k], frame[k:]], gap=gap, note=f"split at {k}")
    if check:
        reply = s.read_reply(check)
        if check != reply.NAME:
            raise Fail(f"split at {k}: got {reply.NAME}")


@case(
    "6.2/framing/split-every-offset",
    errata=("E-WIRE-002",),
    requirement="guide 6.2 (TCP is a byte stream): a frame split at any offset into two sends is one telegram - "
    "answered, and acted on, exactly as when sent whole",
    telegrams=("CMD_GET_STATUS", "CMD_SET_MODE"),
)
def split_every_offset(ctx: CaseContext) -> None:
    ctx.ready()
    s = ctx.fresh()
    get = _frame("CMD_GET_STATUS")
    for k in range(1, len(get)):
        _split_round(ctx, s, get, k, "CMD_GET_STATUS")
    for k in range(1, len(_frame("CMD_SET_MODE", mode=VEL))):
        mode = VEL if k % 2 else NO
        _split_round(ctx, s, _frame("CMD_SET_MODE", mode=mode), k, "")
        st = _status(s)
        if st.motion_mode != mode:  # type: ignore[attr-defined]
            raise Fail(f"CMD_SET_MODE split at offset {k} did not set mode {mode} (status: {st.motion_mode})")  # type: ignore[attr-defined]
    s.send(build("request", "CMD_SET_MODE", mode=NO))


@case(
    "6.2/framing/split-every-offset-long",
    tier=Tier.EXHAUSTIVE,
    errata=("E-WIRE-002",),
    requirement="guide 6.2: frames with strings and INTs split at every offset (three pieces) decode as one",
    telegrams=("CMD_GET_PLTF_PARAM", "CMD_SET_FRM_PLTF"),
)
def split_long(ctx: CaseContext) -> None:
    ctx.ready()
    pos = ctx.preserve_pose()
    s = ctx.fresh()
    key = s.request(build("request", "CMD_GET_PLTF_PARAM_VEC")).parameters[0].key  # type: ignore[attr-defined]
    frame = _frame("CMD_GET_PLTF_PARAM", key=key)
    for i in range(1, len(frame) - 1):
        for j in range(i + 1, len(frame), 5):
            s.send_chunks([frame[:i], frame[i:j], frame[j:]], note=f"split at {i},{j}")
            if s.read_reply("CMD_GET_PLTF_PARAM").key != key:  # type: ignore[attr-defined]
                raise Fail(f"split at {i},{j}: the reply names another key")
    far = far_frame(pos)
    x = far["x"]
    setf = _frame("CMD_SET_FRM_PLTF", **far)
    for k in range(1, len(setf)):
        s.send_chunks([setf[:k], setf[k:]], note=f"split at {k}")
        got = s.request(build("request", "CMD_GET_POSITION"))
        if abs(got.x - x) > 5:  # type: ignore[attr-defined]
            raise Fail(f"CMD_SET_FRM_PLTF split at {k}: position x {got.x}, expected {x}")  # type: ignore[attr-defined]


@case(
    "6.2/framing/slow-sender",
    errata=("E-WIRE-002",),
    requirement="guide 6.2: a frame sent one byte at a time, with pauses, is one telegram",
    telegrams=("CMD_GET_POSITION", "CMD_SET_MODE"),
)
def slow_sender(ctx: CaseContext) -> None:
    ctx.ready()
    s = ctx.fresh()
    gap = min(0.05, ctx.wall(0.1))
    frame = _frame("CMD_GET_POSITION")
    s.send_chunks([frame[i : i + 1] for i in range(len(frame))], gap=gap, note="byte")
    s.read_reply("CMD_GET_POSITION")
    frame = _frame("CMD_SET_MODE", mode=VEL)
    s.send_chunks([frame[i : i + 1] for i in range(len(frame))], gap=gap, note="byte")
    if _status(s).motion_mode != VEL:  # type: ignore[attr-defined]
        raise Fail("CMD_SET_MODE sent byte by byte did not set the mode")
    s.send(build("request", "CMD_SET_MODE", mode=NO))


@case(
    "6.2/framing/coalesced",
    tier=Tier.SMOKE,
    errata=("E-CMD-013", "E-WIRE-008"),
    requirement='guide 6.2 and field evidence (a client "sends many frames back to back on one connection and '
    'never waits for a reply"): frames sent in one piece, or in pieces that cut across frames, are '
    "executed in order and the GET_* replies come in the order of the requests",
    telegrams=("CMD_SET_MODE", "CMD_GET_STATUS", "CMD_GET_POSITION", "CMD_GET_PLTF_PARAM_VEC"),
)
def coalesced(ctx: CaseContext) -> None:
    ctx.ready()
    s = ctx.fresh()
    stream = b"".join(
        [
            _frame("CMD_SET_MODE", mode=VEL),
            _frame("CMD_GET_STATUS"),
            _frame("CMD_SET_MODE", mode=NO),
            _frame("CMD_GET_STATUS"),
            _frame("CMD_GET_POSITION"),
            _frame("CMD_GET_PLTF_PARAM_VEC"),
        ]
    )
    for chunks in ([stream], [stream[i : i + 7] for i in range(0, len(stream), 7)]):
        s.send_chunks(chunks, note="coalesced")
        first, second = s.read_reply("CMD_GET_STATUS"), s.read_reply("CMD_GET_STATUS")
        if (first.motion_mode, second.motion_mode) != (VEL, NO):  # type: ignore[attr-defined]
            raise Fail(
                f"coalesced frames out of order: the modes read back are {first.motion_mode}, "  # type: ignore[attr-defined]
                f"{second.motion_mode} (expected {VEL}, {NO})"  # type: ignore[attr-defined]
            )
        s.read_reply("CMD_GET_POSITION")
        s.read_reply("CMD_GET_PLTF_PARAM_VEC")
    if ctx.unsolicited:
        raise Fail("the commands among the coalesced frames were answered (only GET_* are)", erratum="E-CMD-013")


def _malformed(
    ctx: CaseContext,
    data: bytes,
    what: str,
    *,
    ignore_reading: int = 1,
    erratum: str = "E-WIRE-006",
    closes_within: float = 2.0,
) -> None:
    """Send malformed ``data`` on a fresh connection: the target closes it (the decision) or, by an alternative
    reading, skips it and goes on; it must not act on it (the runner checks the state afterwards)."""
    ctx.ready()
    ctx.before_abuse()
    s = ctx.fresh()
    s.send_raw(data, what)
    try:
        if s.wait_closed(ctx.wall(closes_within)):
            return
        try:
            _status(s)
        except ConnectionClosed:
            return  # closed after the wait (through a relay on a loaded machine, issue 32): the decision, late
        except Fail:
            raise Fail(f"after {what} the connection stayed open but the target stopped answering") from None
        ctx.deviate(erratum, ignore_reading, f"after {what} the connection stayed open and requests were answered")
    finally:
        s.close()


_WIRE_006 = (
    "erratum E-WIRE-006 (guide 6.1 leaves malformed input open): the target closes that connection only "
    "and changes nothing; it keeps serving and accepts a new client"
)


@case(
    "6.2/framing/no-header",
    abuse=True,
    errata=("E-WIRE-006",),
    requirement='guide 6.2: "every message consists of a header"; a frame without it (the guide\'s own example '
    "00 00 00 05 0f 00 00 00 03) is malformed - " + _WIRE_006,
)
def no_header(ctx: CaseContext) -> None:
    _malformed(ctx, bytes.fromhex("00000005 0f 00000003"), "CMD_SET_MODE(3) without header", ignore_reading=0)


@case(
    "6.2/framing/bad-header",
    abuse=True,
    errata=("E-WIRE-006",),
    requirement="guide 6.2 figure 11: the header is 255, 1, 254, 2; any other four bytes are malformed - " + _WIRE_006,
)
def bad_header(ctx: CaseContext) -> None:
    _malformed(ctx, bytes.fromhex("deadbeef 00000001 12"), "a frame with header deadbeef", ignore_reading=0)


@case(
    "6.2/framing/huge-length",
    abuse=True,
    errata=("E-WIRE-004",),
    requirement="erratum E-WIRE-004: a receiver refuses a frame whose length is over its maximum (16 MiB) before "
    "allocating anything, and closes the connection",
)
def huge_length(ctx: CaseContext) -> None:
    for length in (0xFFFFFFFF, 16 * 1024 * 1024 + 1):
        _malformed(
            ctx,
            bytes.fromhex("ff01fe02") + struct.pack(">I", length) + b"\x12",
            f"a frame of length {length:#x}",
            ignore_reading=0,
            erratum="E-WIRE-004",
        )


@case(
    "6.2/framing/length-zero",
    abuse=True,
    errata=("E-WIRE-006",),
    requirement="guide 6.2: the data start with the command byte, so N >= 1; a frame of length 0 is malformed - "
    + _WIRE_006,
)
def length_zero(ctx: CaseContext) -> None:
    _malformed(ctx, bytes.fromhex("ff01fe02 00000000"), "a frame of length 0")


@case(
    "6.2/framing/unknown-identifier",
    abuse=True,
    errata=("E-WIRE-006",),
    requirement="guide 6.3: the command bytes are those of the tables (and of the field evidence); identifier 200 "
    "is malformed input - " + _WIRE_006,
)
def unknown_identifier(ctx: CaseContext) -> None:
    _malformed(ctx, bytes.fromhex("ff01fe02 00000001 c8"), "an unknown identifier 200")


@case(
    "6.2/framing/short-telegram",
    abuse=True,
    errata=("E-WIRE-006",),
    requirement="guide 6.3 CMD_SET_MODE carries an INT (4 bytes); a shorter telegram is malformed and must not "
    "set any mode - " + _WIRE_006,
)
def short_telegram(ctx: CaseContext) -> None:
    _malformed(ctx, _raw("0f 0003"), "CMD_SET_MODE with a 2-byte mode")


@case(
    "6.2/framing/trailing-bytes",
    abuse=True,
    errata=("E-WIRE-006",),
    requirement="guide 6.2: N counts the data bytes; a CMD_SET_MODE whose frame holds bytes after its INT does "
    "not match its layout and is malformed - " + _WIRE_006,
)
def trailing_bytes(ctx: CaseContext) -> None:
    _malformed(ctx, _raw("0f 00000003 0000"), "CMD_SET_MODE with 2 trailing bytes")


@case(
    "6.2/framing/bad-string-length",
    abuse=True,
    errata=("E-WIRE-006",),
    requirement='guide 6.3 CMD_SET_PLTF_PARAM: "INT Key length, STRING Key"; a negative length, or one that '
    "runs past the frame, is malformed - " + _WIRE_006,
)
def bad_string_length(ctx: CaseContext) -> None:
    _malformed(ctx, _raw("25 ffffffff 00000001 41 00000000"), "CMD_SET_PLTF_PARAM with key length -1")
    _malformed(ctx, _raw("25 000003e8 4142 00000000"), "CMD_SET_PLTF_PARAM with key length 1000 in a 10-byte telegram")


@case(
    "6.2/framing/half-close-partial",
    abuse=True,
    errata=("E-WIRE-006",),
    requirement="guide 6.2: a stream that ends (TCP half-close) inside a frame leaves that frame incomplete: it "
    "is not executed and the target closes the connection - " + _WIRE_006,
)
def half_close_partial(ctx: CaseContext) -> None:
    ctx.ready()
    ctx.before_abuse()
    s = ctx.fresh()
    s.send_raw(_frame("CMD_SET_MODE", mode=VEL)[:6], "first 6 bytes of CMD_SET_MODE(VEL)")
    s.shutdown_write()
    if not s.wait_closed(ctx.close_wait(2.0)):
        raise Fail("the target kept the half-closed connection with an incomplete frame open")


@case(
    "6.2/framing/half-close-complete",
    level=Level.MAY,
    errata=("E-BEH-001",),
    requirement="TCP half-close after a complete request: the request is still answered before the target "
    "closes (the guide says nothing; informative: erratum E-BEH-001 allows a FIN that ends the session)",
    telegrams=("CMD_GET_STATUS",),
)
def half_close_complete(ctx: CaseContext) -> None:
    s = ctx.fresh()
    s.send(build("request", "CMD_GET_STATUS"))
    s.shutdown_write()
    try:
        s.read_reply("CMD_GET_STATUS")
    except ConnectionClosed as exc:  # a MAY: N/A, the reading named (issue 32)
        raise Fail(
            f"the target ends the session at our FIN (erratum E-BEH-001, an alternative reading; zoo behaviour matrix "
            f"row 1): {exc} (the request was followed by our half-close)"
        ) from None
    except Fail as exc:
        raise Fail(f"a GET_STATUS followed by a half-close was not answered: {exc}") from None


@case(
    "6.2/framing/stalled-partial-frame",
    tier=Tier.EXHAUSTIVE,
    level=Level.MAY,
    abuse=True,
    requirement="a partial frame that stalls is eventually given up and its connection closed (the reference "
    "server's decision; the guide says nothing)",
)
def stalled(ctx: CaseContext) -> None:
    ctx.ready()
    ctx.before_abuse()
    s = ctx.fresh()
    s.send_raw(_frame("CMD_GET_STATUS")[:5], "first 5 bytes of a frame")
    if not s.wait_closed(max(10.0, ctx.wall(60.0))):
        raise Fail("a stalled partial frame kept its connection open")


@case(
    "6.2/framing/many-frames",
    tier=Tier.EXHAUSTIVE,
    errata=("E-CMD-013",),
    requirement="field evidence: a client sends many frames back to back; 2000 pipelined GET_POSITION requests "
    "get 2000 replies in order",
    telegrams=("CMD_GET_POSITION",),
)
def many_frames(ctx: CaseContext) -> None:
    s = ctx.fresh()
    s.log.max_entries = 50
    frame = _frame("CMD_GET_POSITION")
    s.send_raw(frame * 2000, "2000 x CMD_GET_POSITION")
    for _ in range(2000):
        s.read_reply("CMD_GET_POSITION")
