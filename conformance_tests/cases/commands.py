"""Guide 4.2 / 6.1 / 6.3: every other command in every state - no state change, no reply, connection kept.

The chart commands (state.py), GET_* requests (replies.py), documents (documents.py), moves (motion.py) and
CMD_CLOSE_SOCKET / CMD_EXIT (ports.py, final.py) are checked where their effect is. Each command here is sent
with harmless values - the current pose, a parameter's current value, an output's current level - so that in
every state the only thing that may differ is what the state chart says: nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

from pltf.conformance_tests.cases._common import STATES, no_unsolicited
from pltf.conformance_tests.catalogue import Level, add
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.context import CaseContext, Then
from pltf.conformance_tests.outcome import ConnectionClosed, Fail
from pltf.conformance_tests.target import Status
from pltf.spec.codec import build
from pltf.spec.model import enum_classes

# The spec's enums are built at import; mypy sees them as plain IntEnum classes (by name) without members.
_E: dict[str, Any] = enum_classes()
Fields = Callable[[CaseContext], dict[str, Any]]


def _pose(ctx: CaseContext) -> dict[str, Any]:
    import math

    p = ctx.position()
    return {"x": p.x, "y": p.y, "angle": round(math.degrees(p.angle) * 1000)}  # type: ignore[attr-defined]


def _param(ctx: CaseContext) -> dict[str, Any]:
    reply = ctx.get("CMD_GET_PLTF_PARAM_VEC")
    entry = next((p for p in reply.parameters if p.key == "ViewPlanObstEnabled"), reply.parameters[0])  # type: ignore[attr-defined]
    return {"key": entry.key, "value": entry.value}


def _digout(ctx: CaseContext) -> dict[str, Any]:
    mask = ctx.current_status().telegram.io_digital_out  # type: ignore[attr-defined]
    return {"board": 0, "channel": 15, "value": (mask >> 15) & 1}


def _head(ctx: CaseContext) -> dict[str, Any]:
    return {"angle": ctx.current_status().telegram.head_position}  # type: ignore[attr-defined]


_READ_IN_STATE = (_pose, _param, _digout, _head)  # the values these send are read in each state


def _const(**fields: Any) -> Fields:
    return lambda ctx: dict(fields)


# name -> (fields, flags)
COMMANDS: dict[str, tuple[Fields, dict[str, bool]]] = {
    "CMD_SET_BRAKE": (_const(motor=1, state=0), {"switches_outputs": True}),
    "CMD_SET_DIGOUT": (_digout, {"switches_outputs": True}),
    "CMD_START_ULTRASONIC": (_const(active_channels=0xFFFF), {"switches_outputs": True}),
    "CMD_STOP_ULTRASONIC": (_const(), {"switches_outputs": True}),
    "CMD_ADD_CAN_LISTENING_ID": (_const(can_id=0x7FF), {}),
    "CMD_REMOVE_CAN_LISTENING_ID": (_const(can_id=0x7FF), {}),
    "CMD_SEND_CAN_MESSAGE": (_const(can_id=0x7F0, data=(0,) * 8), {"switches_outputs": True}),
    "CMD_MAPPING_START": (_const(), {}),
    "CMD_MAPPING_RESET": (_const(), {}),
    "CMD_MAPPING_STOP": (_const(), {}),
    "CMD_SET_FRM_PLTF": (_pose, {}),
    "CMD_SET_PLTF_PARAM": (_param, {}),
    "CMD_SPEAK_TEXT": (_const(text=""), {}),
    "CMD_PLAY_SOUND": (_const(filename=""), {}),
    "CMD_GRAB_IMAGE": (_const(filename="conformance"), {}),
    "CMD_SET_POS_HEAD_DRIVE": (_head, {"switches_outputs": True}),
    "CMD_SET_VEL_HEAD_DRIVE": (_const(velocity=0), {"switches_outputs": True}),
    "CMD_SET_POS_PAN_TILT_CAMERA": (_const(position=""), {"switches_outputs": True}),
    "CMD_MOUSE_MOVE": (_const(x=0, y=0, button=_E["MouseButton"].EV_MOUSE_RBUTTON_UP), {}),
    "CMD_SET_LOG_ENABLED": (_const(), {}),
    "CMD_SET_POST_PROCESS_FILENAME": (_const(), {}),
    "CMD_SET_EVENT": (_const(event=_E["Event"].EV_STOP_POST_PROCESS_RECORDING), {}),
}
# Identifiers whose layout is unknown (field evidence, erratum E-CMD-012): sent with no payload.
UNKNOWN_LAYOUT: dict[str, dict[str, bool]] = {
    "CMD_DEBUG1": {},
    "CMD_DEBUG2": {},
    "CMD_DEBUG3": {},
    "CMD_DEBUG4": {},
    "CMD_GET_MAPIMAGE": {},
    "CMD_ENABLE_EXT_MAPPING": {},
    "CMD_DISABLE_EXT_MAPPING": {},
    "CMD_EXT_WRITE_MAPPING": {},
    "CMD_EXT_READ_MAPPING": {},
    "CMD_WRITE_LCD": {"switches_outputs": True},
    "CMD_STOP_MOTIONTHREAD": {"moves_platform": True},
    "CMD_RESTART_MOTIONTHREAD": {"moves_platform": True},
}

_AFTER: dict[str, Callable[[CaseContext], None]] = {
    "CMD_MAPPING_START": lambda ctx: ctx.send("CMD_MAPPING_STOP"),
    "CMD_ADD_CAN_LISTENING_ID": lambda ctx: ctx.send("CMD_REMOVE_CAN_LISTENING_ID", can_id=0x7FF),
    # all sensors measuring is the safe end state of a real platform (the previous mask cannot be read)
    "CMD_STOP_ULTRASONIC": lambda ctx: ctx.send("CMD_START_ULTRASONIC", active_channels=0xFFFF),
}


def _every_state(ctx: CaseContext, name: str, fields: Fields | None) -> None:
    ctx.ready()
    if name in ("CMD_MAPPING_START", "CMD_MAPPING_RESET", "CMD_MAPPING_STOP"):
        ctx.preserve_document("map")
    if name == "CMD_SET_FRM_PLTF":
        ctx.preserve_pose()
    if name in _AFTER:
        ctx.on_exit(f"undo {name}", lambda: _AFTER[name](ctx))
    for state in STATES:
        before, rest = _in_state(ctx, state, name, fields)
        try:
            (reply,) = rest()
        except ConnectionClosed:
            if fields is not None:
                raise
            ctx.deviate("E-CMD-012", 0, f"{name} closed the connection (refused as unknown) in {state.value}")
            ctx.reset_session()
            continue
        after = Status.of(reply)
        if (after.op, after.initialized, after.mode) != (before.op, before.initialized, before.mode):
            raise Fail(f"{name} in {state.value} changed the platform: {before.describe()} -> {after.describe()}")
    no_unsolicited(ctx, name)
    ctx.ready()


def _in_state(ctx: CaseContext, state: St, name: str, fields: Fields | None) -> tuple[Status, Then]:
    """The status in ``state``, and the reply to the CMD_GET_STATUS asked after ``name`` was sent there. Values
    read in the state (the pose, a parameter, an output) are read there first; constant ones go in one write with
    the way to the state (pipelined, CaseContext.enter)."""
    ask = build("request", "CMD_GET_STATUS")
    if fields is None or fields not in _READ_IN_STATE:
        values = fields(ctx) if fields is not None else {"payload": b""}
        return ctx.enter(state, then=[build("request", name, **values), ask])
    before = ctx.ensure(state)
    values = fields(ctx)
    return before, lambda: ctx.exchange([build("request", name, **values), ask])


_RULE = (
    'guide 4.2: "All commands ... will cause a state transition depending on the state chart" - {name} is '
    "not a command of the chart: in every state it changes neither the operation state nor the motion mode; "
    "guide 6.1: it is not answered"
)

for _name, (_fields, _flags) in COMMANDS.items():
    add(
        f"6.3/{_name}/every-state",
        partial(_every_state, name=_name, fields=_fields),
        group="commands",
        requirement=_RULE.format(name=_name),
        telegrams=(_name,),
        **_flags,
    )

for _name, _flags in UNKNOWN_LAYOUT.items():
    add(
        f"6.3/{_name}/every-state",
        partial(_every_state, name=_name, fields=None),
        group="commands",
        errata=("E-CMD-012",),
        level=Level.MUST,
        requirement=f"guide 4.2 / 6.1 and erratum E-CMD-012: {_name} (id known from field code, layout unknown) "
        "changes no operation state and is not answered, in every state; the decision is that it is "
        "accepted and the connection stays open (closing it is an accepted reading)",
        telegrams=(_name,),
        **_flags,
    )
