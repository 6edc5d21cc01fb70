"""Guide 6.4: every reply telegram, in every state, decoded strictly; what the replies say agrees."""

from __future__ import annotations

import math
from functools import partial

from pltf.conformance_tests.cases._common import STATES, no_unsolicited
from pltf.conformance_tests.catalogue import Level, Tier, add, case
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import Fail, Inconclusive, ReplyTimeout
from pltf.conformance_tests.target import Status
from pltf.spec.codec import REPLIES, build
from pltf.spec.errata import errata_for
from pltf.spec.telegram import Telegram

ANSWERED = [cls.NAME for cls in REPLIES if cls.DEF.answered]
_SMOKE = {"CMD_GET_STATUS", "CMD_GET_POSITION"}


def _strict(ctx: CaseContext, name: str) -> None:
    for state in STATES:
        try:
            before, reply, after = _in_state(ctx, state, name)
        except ReplyTimeout:
            if name != "CMD_GET_CAMERA":
                raise
            ctx.deviate("E-REP-020", 0, f"CMD_GET_CAMERA was not answered in {state.value}")
            ctx.reset_session()
            continue
        if name != reply.NAME:
            raise Fail(f"{name} in {state.value} was answered with {reply.NAME}")
        after = after or ctx.status()
        if (after.op, after.mode) != (before.op, before.mode):
            raise Fail(f"{name} changed the platform: {before.describe()} -> {after.describe()}")
    no_unsolicited(ctx, name)
    ctx.ready()


def _in_state(ctx: CaseContext, state: St, name: str) -> tuple[Status, Telegram, Status | None]:
    """The status in ``state``, the reply to ``name`` asked there and the status asked after it. Pipelined
    (CaseContext.enter) but for CMD_GET_CAMERA, which a target may leave unanswered (E-REP-020): its status
    (None here) is asked once the reply came."""
    ask = build("request", "CMD_GET_STATUS")
    if name == "CMD_GET_CAMERA":
        before = ctx.ensure(state)
        return before, ctx.session().request(build("request", name)), None
    if name == "CMD_GET_PLTF_PARAM":  # the key is the first one the vector lists there
        before, rest = ctx.enter(state, then=[build("request", "CMD_GET_PLTF_PARAM_VEC")])
        key = rest()[0].parameters[0].key  # type: ignore[attr-defined]
        reply, after = ctx.exchange([build("request", name, key=key), ask])
        return before, reply, Status.of(after)
    fields = {"delete": 0} if name == "CMD_GET_CAN_MESSAGES" else {}
    before, rest = ctx.enter(state, then=[build("request", name, **fields), ask])
    reply, after = rest()
    return before, reply, Status.of(after)


for _name in ANSWERED:
    _errata = tuple(e.id for e in errata_for(_name) if e.id.startswith(("E-REP", "E-WIRE")))
    add(
        f"6.4/{_name}/strict-decode",
        partial(_strict, name=_name),
        requirement=(
            f"guide 6.4 '{_name}': the reply telegram has exactly the layout of its table - no trailing "
            "bytes, counts consistent with the data, enum values and constants as printed - in every "
            "operation state (guide 6.1: data are returned on request)"
            + (f"; errata {', '.join(_errata)} decide the garbled rows" if _errata else "")
        ),
        level=Level.MUST,
        tier=Tier.SMOKE if _name in _SMOKE else Tier.STANDARD,
        errata=_errata,
        group="replies",
        telegrams=(_name,),
    )


@case(
    "6.4/CMD_GET_POSITION/agrees-with-status",
    errata=("E-REP-012",),
    requirement="guide 6.4: CMD_GET_POSITION's estimated position and angle are the estimated platform frame of "
    "CMD_GET_STATUS (erratum E-REP-012: mm, angle in rad; the status angle is [deg*1000])",
    telegrams=("CMD_GET_POSITION", "CMD_GET_STATUS"),
)
def position_agrees(ctx: CaseContext) -> None:
    ctx.ready()
    p0 = ctx.preserve_pose()
    ctx.send("CMD_SET_FRM_PLTF", x=p0.x, y=p0.y, angle=30000)  # type: ignore[attr-defined]  # 0 deg would hide units
    pos, st = ctx.position(), ctx.status().telegram
    if abs(pos.x - st.est_x) > 10 or abs(pos.y - st.est_y) > 10:  # type: ignore[attr-defined]  # two requests: noise
        raise Fail(f"GET_POSITION ({pos.x}, {pos.y}) vs GET_STATUS estimate ({st.est_x}, {st.est_y})")  # type: ignore[attr-defined]
    deg = st.est_angle / 1000.0  # type: ignore[attr-defined]

    def off(a: float, b: float) -> float:
        return abs((a - b + 180.0) % 360.0 - 180.0)

    if off(math.degrees(pos.angle), deg) <= 0.5:  # type: ignore[attr-defined]
        return
    if off(pos.angle, deg) <= 0.5:  # type: ignore[attr-defined]
        ctx.deviate("E-REP-012", 0, f"GET_POSITION angle {pos.angle} is in degrees")  # type: ignore[attr-defined]
        return
    raise Fail(f"GET_POSITION angle {pos.angle} rad does not match the status angle {deg} deg")  # type: ignore[attr-defined]


@case(
    "6.4/CMD_GET_STATUS/timestamp-advances",
    errata=("E-REP-010",),
    timing=True,
    requirement="guide 6.4 CMD_GET_STATUS 'INT Message time stamp'; erratum E-REP-010: milliseconds since start",
    telegrams=("CMD_GET_STATUS",),
)
def timestamp_advances(ctx: CaseContext) -> None:
    import time

    t1 = ctx.status().telegram.timestamp  # type: ignore[attr-defined]
    w0 = time.monotonic()
    ctx.sleep(2.0)
    t2 = ctx.status().telegram.timestamp  # type: ignore[attr-defined]
    elapsed = (time.monotonic() - w0) * ctx.config.time_scale
    if abs((t2 - t1) - elapsed * 1000) <= 0.25 * elapsed * 1000 + 100:
        return
    if abs((t2 - t1) - elapsed) <= 0.25 * elapsed + 1:
        ctx.deviate("E-REP-010", 0, f"the time stamp advanced by {t2 - t1} in {elapsed:.2f} s (seconds)")
        return
    if abs((t2 - t1) - elapsed * 1000) <= 0.5 * elapsed * 1000 + 100:  # a loaded machine, or a slow clock?
        raise Inconclusive(f"the time stamp advanced by {t2 - t1} ms in {elapsed:.2f} simulated s")
    raise Fail(
        f"the time stamp advanced by {t2 - t1} in {elapsed:.2f} simulated s (expected about {elapsed * 1000:.0f} ms)"
    )


@case(
    "6.4/CMD_GET_STATUS/at-rest",
    level=Level.SHOULD,
    requirement="guide 6.4: in Ready the 'current commanded velocities' are 0 and CMD_GET_POSITION reports no motion",
    telegrams=("CMD_GET_STATUS", "CMD_GET_POSITION"),
)
def at_rest(ctx: CaseContext) -> None:
    ctx.ready()
    ctx.sleep(1.0)
    st, pos = ctx.status().telegram, ctx.position()
    if abs(st.vel_trans) > 5 or abs(st.vel_rot) > 10:  # type: ignore[attr-defined]  # measured (E-MOT-005)
        raise Fail(f"commanded velocities in Ready: {st.vel_trans} mm/s, {st.vel_rot} mrad/s")  # type: ignore[attr-defined]
    if abs(pos.vel_trans) > 5 or abs(pos.vel_rot) > 0.01:  # type: ignore[attr-defined]
        raise Fail(f"GET_POSITION velocities in Ready: {pos.vel_trans} mm/s, {pos.vel_rot} rad/s")  # type: ignore[attr-defined]
