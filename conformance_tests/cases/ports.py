"""Guide 6.1 / 4.2: the two ports, one client per port, replies only on request, reconnection."""

from __future__ import annotations

import time

from pltf.conformance_tests.cases._common import STATES, far_frame
from pltf.conformance_tests.catalogue import Level, Tier, case
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import ConnectionClosed, Fail, NotApplicable, TargetFailure
from pltf.spec.codec import build

_PORTS = (
    'guide 6.1: "a socket server is established on the platform PC and listens for clients on the socket '
    'ports 10000 and 10002. For each port one client is able to connect to the platform."'
)


def _need_second_port(ctx: CaseContext) -> None:
    if ctx.config.second_port is None:
        raise NotApplicable("no --second-port given: the second port is not checked")


@case("6.1/ports/both-serve", tier=Tier.SMOKE, requirement=_PORTS, telegrams=("CMD_GET_STATUS",))
def both_serve(ctx: CaseContext) -> None:
    _need_second_port(ctx)
    ctx.status("A")
    ctx.status("B")


@case(
    "6.1/ports/same-platform",
    requirement=_PORTS + " Both ports control the one platform: a change made through "
    "one port is seen through the other",
    telegrams=("CMD_SET_FRM_PLTF", "CMD_GET_POSITION"),
)
def same_platform(ctx: CaseContext) -> None:
    _need_second_port(ctx)
    ctx.ready()
    pos = ctx.preserve_pose()
    frame = far_frame(pos)
    x = frame["x"]
    ctx.send("CMD_SET_FRM_PLTF", label="A", **frame)
    seen = ctx.poll(lambda: ctx.position("B"), lambda p: abs(p.x - x) <= 5, within=2.0)  # type: ignore[attr-defined]
    if abs(seen.x - x) > 5:  # type: ignore[attr-defined]
        raise Fail(f"CMD_SET_FRM_PLTF(x={x}) on port A: port B still reports x={seen.x}")  # type: ignore[attr-defined]


def _second_client(ctx: CaseContext, label: str) -> None:
    first = ctx.session(label)
    try:
        second = ctx.extra(label + "2")
        closed = second.wait_closed(ctx.newcomer_wait(1.0))
    except ConnectionClosed as exc:
        if "reset" not in str(exc).lower():
            raise
        closed = True  # reset as soon as the handshake ended: closed at once, with RST instead of FIN
    try:
        first.request(build("request", "CMD_GET_STATUS"))
    except TargetFailure as exc:
        raise Fail(f"port {label}: a second client disturbed the first one ({exc})", erratum="E-WIRE-007") from None
    if closed:
        return
    second.send(build("request", "CMD_GET_STATUS"))
    try:
        second.read_reply("CMD_GET_STATUS", timeout=ctx.newcomer_wait(1.0))
    except TargetFailure:
        ctx.deviate("E-WIRE-007", 0, f"port {label}: the second client was neither closed nor served (backlog)")
        return
    raise Fail(
        f"port {label}: a second client was served while the first was connected - the guide allows one "
        "client per port",
        erratum="E-WIRE-007",
    )


@case(
    "6.1/ports/second-client-turned-away",
    errata=("E-WIRE-007",),
    requirement=_PORTS + " Erratum E-WIRE-007: a second client on a busy port is closed at once; the first client "
    "is unaffected",
    telegrams=("CMD_GET_STATUS",),
)
def second_client(ctx: CaseContext) -> None:
    _second_client(ctx, "A")
    if ctx.config.second_port is not None:
        _second_client(ctx, "B")


@case(
    "6.1/ports/reconnect",
    tier=Tier.SMOKE,
    requirement=_PORTS + " After a client leaves, the port takes the next one",
    telegrams=("CMD_GET_STATUS",),
)
def reconnect(ctx: CaseContext) -> None:
    for _ in range(5):
        s = ctx.fresh()
        s.request(build("request", "CMD_GET_STATUS"))
        s.close()


@case(
    "6.1/ports/many-reconnects",
    tier=Tier.EXHAUSTIVE,
    requirement=_PORTS + " 300 connect/request/disconnect cycles leave the target serving",
    telegrams=("CMD_GET_STATUS",),
)
def many_reconnects(ctx: CaseContext) -> None:
    ctx.log.max_entries = 100
    for _ in range(300):
        s = ctx.fresh()
        s.close()
    ctx.status()


@case(
    "6.1/ports/abuse-leaves-other-port",
    abuse=True,
    errata=("E-WIRE-006",),
    requirement="erratum E-WIRE-006: malformed input closes that connection only - the client of the other port "
    "is not disturbed",
    telegrams=("CMD_GET_STATUS",),
)
def abuse_other_port(ctx: CaseContext) -> None:
    _need_second_port(ctx)
    ctx.ready()
    ctx.before_abuse()
    other = ctx.session("B")
    s = ctx.fresh()
    s.send_raw(bytes.fromhex("deadbeef 00000001 12"), "bad header")
    s.wait_closed(ctx.wall(1.0))
    try:
        other.request(build("request", "CMD_GET_STATUS"))
    except TargetFailure as exc:
        raise Fail(f"bad input on port A disturbed the client on port B: {exc}") from None


@case(
    "6.1/replies/only-on-request",
    tier=Tier.SMOKE,
    errata=("E-CMD-013",),
    requirement='guide 6.1: "This interface accepts commands and returns data only on request." Commands other '
    "than the GET_* requests are never answered (erratum E-CMD-013)",
    telegrams=("CMD_SET_MODE", "CMD_STOP", "CMD_SET_LOG_ENABLED", "CMD_MOUSE_MOVE"),
)
def only_on_request(ctx: CaseContext) -> None:
    ctx.ready()
    s = ctx.session()
    for t in (
        build("request", "CMD_SET_MODE", mode=0),
        build("request", "CMD_STOP"),
        build("request", "CMD_SET_LOG_ENABLED"),
        build("request", "CMD_SET_POST_PROCESS_FILENAME"),
        build("request", "CMD_MOUSE_MOVE", x=0, y=0, button=5),
    ):
        s.send(t)
    ctx.quiet(0.5)
    s.request(build("request", "CMD_GET_STATUS"))
    if ctx.unsolicited:
        raise Fail("commands were answered", erratum="E-CMD-013")


@case(
    "6.1/replies/in-order",
    requirement="guide 6.1/6.4: each GET_* request gets its reply telegram, in the order "
    "of the requests, on the connection that asked",
    telegrams=("CMD_GET_STATUS", "CMD_GET_POSITION"),
)
def replies_in_order(ctx: CaseContext) -> None:
    s = ctx.session()
    names = ["CMD_GET_POSITION", "CMD_GET_STATUS", "CMD_GET_CAMERA", "CMD_GET_POSITION", "CMD_GET_PLTF_PARAM_VEC"]
    for n in names:
        s.send(build("request", n))
    for n in names:
        s.read_reply(n)
    if ctx.unsolicited:
        port, data = ctx.unsolicited[0]
        raise Fail(f"a reply came out of order or unasked: identifier {data[0]} on port {port}")


@case(
    "6.3/CMD_CLOSE_SOCKET/closes",
    requirement='guide 6.3 CMD_CLOSE_SOCKET: "Close the socket connection."',
    telegrams=("CMD_CLOSE_SOCKET",),
)
def close_socket(ctx: CaseContext) -> None:
    for state in STATES:
        before = ctx.ensure(state)
        s = ctx.fresh()
        s.send(build("request", "CMD_CLOSE_SOCKET"))
        if not s.wait_closed(ctx.close_wait(2.0)):
            raise Fail(f"CMD_CLOSE_SOCKET in {state.value}: the connection stayed open")
        ctx.session()  # a new client: the CMD_GET_STATUS that probes it is the status after
        after = ctx.current_status()
        if (after.op, after.mode) != (before.op, before.mode):
            raise Fail(f"CMD_CLOSE_SOCKET changed the platform: {before.describe()} -> {after.describe()}")
    ctx.ready()


@case(
    "6.1/ports/connect-latency",
    tier=Tier.EXHAUSTIVE,
    level=Level.MAY,
    requirement="informative: a new client is served within 1 s of the previous one leaving",
)
def connect_latency(ctx: CaseContext) -> None:
    s = ctx.fresh()
    s.close()
    t0 = time.monotonic()
    ctx.fresh()
    if time.monotonic() - t0 > 1.0:
        raise Fail(f"the port took {time.monotonic() - t0:.2f} s to take a new client")
