"""Helpers shared by the case modules: state checks, tolerances and small oracles."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from pltf.conformance_tests import chart
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import Fail, NotApplicable
from pltf.conformance_tests.target import Status
from pltf.spec.model import enum_classes

# The spec's enums are built at import; mypy sees them as plain IntEnum classes without members.
MotionMode: Any = enum_classes()["MotionMode"]
OperationState: Any = enum_classes()["OperationState"]
NO = MotionMode.MODE_MOTION_NO

STATES: tuple[St, ...] = (St.NOT_CONNECTED, St.CONNECTED, St.READY, St.RUNNING, St.BREAKED)

# A frame a case sets with CMD_SET_FRM_PLTF and then reads back: an offset (mm, mm, 1000*deg) from the true pose
# beyond any local scan matcher's capture range. A small offset (a few hundred mm, a few degrees) is pulled back
# towards the truth by the next matching scan while LocalLocalization is on (erratum E-MOT-004: the reference's
# capture range is 400 mm and 12 deg), so reading it back races the target's localization; far off, the matcher
# cannot lock on and the estimate stays where it was put (until a global localization finds the platform).
FAR_OFFSET = (1234, -567, 45000)


def far_frame(pos: Any) -> dict[str, int]:
    """The CMD_SET_FRM_PLTF fields of the frame FAR_OFFSET away from ``pos`` (a GET_POSITION reply)."""
    dx, dy, milli_deg = FAR_OFFSET
    return {"x": pos.x + dx, "y": pos.y + dy, "angle": milli_deg}


def expect_state(
    ctx: CaseContext,
    state: St,
    how: str,
    *,
    mode: int | None = None,
    within: float = 0.0,
    first: Status | None = None,
) -> Status:
    """The status shows ``state`` (op state and initialized flag), and ``mode`` when given. ``first``: the first
    status asked after ``how`` (read already, pipelined with it); else it is asked now."""
    op, init = chart.REPORTED[state], chart.INITIALIZED[state]

    def ok(s: Status) -> bool:
        return s.op == op and s.initialized == init and (mode is None or s.mode == mode)

    s = first or ctx.status()
    if within and not ok(s):
        s = ctx.poll(ctx.status, ok, within=within)
    if not ok(s):
        want = f"{OperationState(op).name}, initialized {init}"
        if mode is not None:
            want += f", {MotionMode(mode).name}"
        raise Fail(f"{how}: expected {want}, status says {s.describe()}")
    return s


def expect_unchanged(ctx: CaseContext, state: St, before: Status, how: str, *, after: Status | None = None) -> Status:
    """After ``how`` (a command that must have no effect): nothing the status shows has changed. ``after``: the
    status asked a settling time after ``how`` (read already, pipelined with it); else the settling and the ask
    happen now."""
    if after is None:
        ctx.settle()
    s = after or ctx.status()
    if (s.op, s.initialized, s.mode) != (before.op, before.initialized, before.mode):
        raise Fail(f"{how} must change nothing: the status went from {before.describe()} to {s.describe()}")
    if state is St.CONNECTED:
        probe_connected(ctx, how)
    return s


def probe_connected(ctx: CaseContext, how: str) -> None:
    """Connected (CAN up) and Not connected look alike in the status; CMD_INIT_PLTF tells them apart."""
    ctx.send("CMD_INIT_PLTF")
    s = ctx.poll(ctx.status, lambda x: x.op == OperationState.ST_OP_READY, within=30.0)
    if s.op != OperationState.ST_OP_READY:
        raise Fail(
            f"after {how} the CAN connection was lost: CMD_INIT_PLTF no longer initializes (status: {s.describe()})"
        )


def no_unsolicited(ctx: CaseContext, what: str) -> None:
    if ctx.unsolicited:
        port, data = ctx.unsolicited[0]
        raise Fail(
            f"{what} was answered (port {port}: {data[:16].hex()}...), but only GET_* requests are "
            "(guide 6.1 'returns data only on request')",
            erratum="E-CMD-013",
        )


def near(value: float, target: float, tol: float) -> bool:
    return abs(value - target) <= tol


def param_table(ctx: CaseContext) -> dict[str, Any]:
    """The target's parameters (CMD_GET_PLTF_PARAM_VEC) by key."""
    reply = ctx.get("CMD_GET_PLTF_PARAM_VEC")
    return {p.key: p for p in reply.parameters}  # type: ignore[attr-defined]


def pick(table: dict[str, Any], names: Iterable[str], what: str) -> str:
    for n in names:
        if n in table:
            return n
    raise NotApplicable(f"the target lists none of the parameters {what} needs ({', '.join(names)})")
