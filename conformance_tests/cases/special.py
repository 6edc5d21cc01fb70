"""Guide 6.3 platform data, special-function and debug commands whose effect a GET_* reply shows."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from pltf.conformance_tests.cases._common import FAR_OFFSET, no_unsolicited
from pltf.conformance_tests.catalogue import Level, Tier, case
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import Fail, NotApplicable
from pltf.spec.model import enum_classes
from pltf.spec.telegram import Telegram

# The spec's enums are built at import; mypy sees them as plain IntEnum classes without members.
_E: dict[str, Any] = enum_classes()


def _near(x: int, y: int) -> Callable[[Telegram], bool]:
    def near(p: Any) -> bool:  # a GET_POSITION reply: its fields come from the spec, unknown to mypy
        return bool(abs(p.x - x) <= 20 and abs(p.y - y) <= 20)

    return near


def _field_is(name: str, value: int) -> Callable[[Telegram], bool]:
    return lambda t: bool(getattr(t, name) == value)


@case(
    "6.3/CMD_SET_FRM_PLTF/sets-estimate",
    tier=Tier.SMOKE,
    errata=("E-WIRE-005",),
    requirement='guide 6.3 CMD_SET_FRM_PLTF: "Set the estimated frame of the mobile platform to a desired frame '
    'in global coordinates" (X, Y [mm], angle [1000*deg]); GET_POSITION and GET_STATUS report it',
    telegrams=("CMD_SET_FRM_PLTF", "CMD_GET_POSITION", "CMD_GET_STATUS"),
)
def sets_estimate(ctx: CaseContext) -> None:
    ctx.ready()
    p0 = ctx.preserve_pose()
    for dx, dy, milli_deg in (FAR_OFFSET, (-321, 789, -135500)):  # both beyond the capture range (FAR_OFFSET)
        x, y = p0.x + dx, p0.y + dy  # type: ignore[attr-defined]
        ctx.send("CMD_SET_FRM_PLTF", x=x, y=y, angle=milli_deg)
        got = ctx.poll(ctx.position, _near(x, y), within=1.0)
        d = math.degrees(got.angle) - milli_deg / 1000.0  # type: ignore[attr-defined]
        d = (d + 180.0) % 360.0 - 180.0
        if abs(got.x - x) > 20 or abs(got.y - y) > 20 or abs(d) > 1.0:  # type: ignore[attr-defined]
            raise Fail(
                f"CMD_SET_FRM_PLTF({x}, {y}, {milli_deg}): GET_POSITION reports ({got.x}, {got.y}, "  # type: ignore[attr-defined]
                f"{math.degrees(got.angle):.2f} deg)"  # type: ignore[attr-defined]
            )
        st = ctx.status().telegram
        if abs(st.est_x - x) > 20 or abs(st.est_y - y) > 20:  # type: ignore[attr-defined]
            raise Fail(f"CMD_SET_FRM_PLTF({x}, {y}): GET_STATUS estimate ({st.est_x}, {st.est_y})")  # type: ignore[attr-defined]


@case(
    "6.3/CMD_MAPPING_START/debug-mapping-mode",
    level=Level.SHOULD,
    requirement='guide 6.3 CMD_MAPPING_START "Start mapping mode", CMD_MAPPING_STOP "Stop mapping mode"; 6.4 '
    "CMD_GET_DEBUG_DATA 'Mapping mode: Indicates if the platform is in the mapping mode'",
    telegrams=("CMD_MAPPING_START", "CMD_MAPPING_STOP", "CMD_MAPPING_RESET", "CMD_GET_DEBUG_DATA"),
)
def mapping_mode(ctx: CaseContext) -> None:
    ctx.ready()
    ctx.preserve_document("map")
    ctx.on_exit("stop mapping", lambda: ctx.send("CMD_MAPPING_STOP"))
    for command, flag in (("CMD_MAPPING_START", 1), ("CMD_MAPPING_RESET", 1), ("CMD_MAPPING_STOP", 0)):
        ctx.send(command)
        got = ctx.poll(lambda: ctx.get("CMD_GET_DEBUG_DATA"), _field_is("mapping_mode", flag), within=2.0)
        if got.mapping_mode != flag:  # type: ignore[attr-defined]
            raise Fail(f"after {command} the debug data say mapping mode {got.mapping_mode}")  # type: ignore[attr-defined]
        if command == "CMD_MAPPING_RESET" and got.mapped_segments:  # type: ignore[attr-defined]
            raise Fail(f"after CMD_MAPPING_RESET {len(got.mapped_segments)} mapped segments remain")  # type: ignore[attr-defined]


@case(
    "6.3/CMD_SET_POS_HEAD_DRIVE/turns-head",
    level=Level.MAY,
    switches_outputs=True,
    requirement='guide 6.3 CMD_SET_POS_HEAD_DRIVE "Set the position of the head drive" [deg]; 6.4 \'Position of '
    "head drive' (optional hardware)",
    telegrams=("CMD_SET_POS_HEAD_DRIVE", "CMD_SET_VEL_HEAD_DRIVE"),
)
def turns_head(ctx: CaseContext) -> None:
    ctx.ready()
    old = ctx.status().telegram.head_position  # type: ignore[attr-defined]
    ctx.on_exit("turn the head back", lambda: ctx.send("CMD_SET_POS_HEAD_DRIVE", angle=old))
    ctx.send("CMD_SET_VEL_HEAD_DRIVE", velocity=3000)
    target = old + 20 if old <= 0 else old - 20
    ctx.send("CMD_SET_POS_HEAD_DRIVE", angle=target)
    got = ctx.poll(lambda: ctx.status().telegram.head_position, lambda h: abs(h - target) <= 2, within=5.0)  # type: ignore[attr-defined]
    if got == old:
        raise NotApplicable("the head position did not change: no head drive on this target")
    if abs(got - target) > 2:
        raise Fail(f"head drive set to {target} deg, reports {got} deg")


@case(
    "6.3/CMD_SET_EVENT/every-event",
    moves_platform=True,
    requirement="guide 6.3 CMD_SET_EVENT: post-process recording and replay events 1..6 - accepted silently, no "
    "operation state change (replay may move the platform, hence the gate)",
    telegrams=("CMD_SET_EVENT",),
)
def every_event(ctx: CaseContext) -> None:
    before = ctx.ready()
    for value in sorted(_E["Event"]._value2member_map_):
        ctx.send("CMD_SET_EVENT", event=value)
    ctx.send("CMD_SET_EVENT", event=_E["Event"].EV_STOP_POST_PROCESS_REPLAY)
    ctx.send("CMD_SET_EVENT", event=_E["Event"].EV_STOP_POST_PROCESS_RECORDING)
    after = ctx.status()
    if (after.op, after.mode) != (before.op, before.mode):
        raise Fail(f"CMD_SET_EVENT changed the platform: {before.describe()} -> {after.describe()}")
    no_unsolicited(ctx, "CMD_SET_EVENT")


@case(
    "6.3/CMD_MOUSE_MOVE/both-buttons",
    requirement='guide 6.3 CMD_MOUSE_MOVE "Set the mouse obstacle" with EV_MOUSE_RBUTTON_DOWN = 2 and '
    "EV_MOUSE_RBUTTON_UP = 5 - accepted silently",
    telegrams=("CMD_MOUSE_MOVE",),
)
def mouse(ctx: CaseContext) -> None:
    before = ctx.ready()
    p = ctx.position()
    ctx.send("CMD_MOUSE_MOVE", x=p.x + 3000, y=p.y, button=_E["MouseButton"].EV_MOUSE_RBUTTON_DOWN)  # type: ignore[attr-defined]
    ctx.send("CMD_MOUSE_MOVE", x=p.x + 3000, y=p.y, button=_E["MouseButton"].EV_MOUSE_RBUTTON_UP)  # type: ignore[attr-defined]
    after = ctx.status()
    if (after.op, after.mode) != (before.op, before.mode):
        raise Fail(f"CMD_MOUSE_MOVE changed the platform: {before.describe()} -> {after.describe()}")
    no_unsolicited(ctx, "CMD_MOUSE_MOVE")
