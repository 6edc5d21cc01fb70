"""Guide 4.2 / 4.3: moves where they must have no effect - outside Running (every other state) and in the
motion modes that do not take them. Gated like every motion case: a broken target would move."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

from pltf.conformance_tests.cases._common import MotionMode
from pltf.conformance_tests.cases.motion import _GATE, _local_roadmap
from pltf.conformance_tests.catalogue import Level, add
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.poses import AUTO, JOYHARD, NO, VEL, Pose, _milli, _pose_of, judge_still, pose, rest, still
from pltf.conformance_tests.wire import Pause
from pltf.spec.codec import build
from pltf.spec.telegram import Telegram

_MOVES: dict[str, tuple[int, Callable[[Pose], dict[str, Any]]]] = {
    "CMD_MOVE_VEL": (VEL, lambda p: {"vel_trans": 300, "vel_rot": 0}),
    "CMD_MOVE_VEL_WHEEL": (VEL, lambda p: {"vel_right": 300, "vel_left": 300}),
    "CMD_MOVE_ABS": (AUTO, lambda p: {"x": round(p.ahead(400).x), "y": round(p.ahead(400).y), "angle": _milli(p.th)}),
    "CMD_MOVE_REL": (AUTO, lambda p: {"x": 400, "y": 0, "angle": 0}),
    "CMD_MOVE_PATH": (AUTO, lambda p: {"frames": ((round(p.ahead(400).x), round(p.ahead(400).y), _milli(p.th)),)}),
    "CMD_MOVE_TO_STATION": (AUTO, lambda p: {"station": "ConfB"}),
}


def _only_in_running(ctx: CaseContext, name: str) -> None:
    mode, fields = _MOVES[name]
    if name == "CMD_MOVE_TO_STATION":
        ctx.preserve_document("roadmap")
        p = pose(ctx)
        ctx.send("CMD_SET_ROADMAP", name="conformance_local", xml=_local_roadmap(p).decode())
    for state in (St.NOT_CONNECTED, St.CONNECTED, St.READY, St.BREAKED):
        _, replies = ctx.enter(state, mode, then=[build("request", "CMD_GET_POSITION")])  # pipelined (E-WIRE-008)
        here = _pose_of(replies()[0])
        _still_after(ctx, build("request", name, **fields(here)), here, f"{name} in {state.value}")
        if state is St.BREAKED:
            _still_after(ctx, build("request", "CMD_CONTINUE"), here, f"CMD_CONTINUE after a {name} sent in breaked")
    ctx.ready()


def _still_after(ctx: CaseContext, sent: Telegram, here: Pose, how: str) -> None:
    """``sent``, then (1 simulated s later) the pose is still ``here``: motion.still, in one write with the
    status the next step starts from (pipelined, erratum E-WIRE-008)."""
    ask = [build("request", "CMD_GET_POSITION"), build("request", "CMD_GET_STATUS")]
    reply, _ = ctx.exchange([sent, Pause(1.0 / ctx.config.time_scale), *ask])
    judge_still(_pose_of(reply), here, how)


def _mode_ignores(ctx: CaseContext, mode: int, names: tuple[str, ...]) -> None:
    ctx.ensure(St.RUNNING, mode)
    here = rest(ctx)
    for name in names:
        ctx.send(name, **_MOVES[name][1](here))
    still(ctx, here, f"{', '.join(names)} in {MotionMode(mode).name}")
    ctx.ready()


for _name in _MOVES:
    add(
        f"6.3/{_name}/only-in-running",
        partial(_only_in_running, name=_name),
        **_GATE,
        requirement=f"guide 4.2: \"A movement of the platform is only possible in the state 'Running'\" - {_name} "
        "(in its motion mode) moves nothing in Not connected, Connected, Ready or Breaked, nor after "
        "a CMD_CONTINUE",
        telegrams=(_name,),
    )

add(
    "4.3/MODE_MOTION_NO/moves-ignored",
    partial(_mode_ignores, mode=NO, names=tuple(_MOVES)),
    **_GATE,
    requirement='guide 4.3 Mode No Motion: "All move commands have no effects."',
    telegrams=tuple(_MOVES),
)
add(
    "4.3/MODE_MOTION_AUTOMATIC/velocity-commands-ignored",
    partial(_mode_ignores, mode=AUTO, names=("CMD_MOVE_VEL", "CMD_MOVE_VEL_WHEEL")),
    **_GATE,
    level=Level.SHOULD,
    requirement="guide 4.3: velocities are set with CMD_MOVE_VEL_WHEEL / CMD_MOVE_VEL in the modes Velocity and "
    'Joystick (Software); in Automatic "several move commands are executed" - not these',
    telegrams=("CMD_MOVE_VEL", "CMD_MOVE_VEL_WHEEL"),
)
add(
    "4.3/MODE_MOTION_VEL/path-commands-ignored",
    partial(_mode_ignores, mode=VEL, names=("CMD_MOVE_ABS", "CMD_MOVE_REL", "CMD_MOVE_PATH")),
    **_GATE,
    level=Level.SHOULD,
    requirement='guide 4.3 Mode Velocity: "The desired velocities are set to the platform using the commands '
    'CMD_MOVE_VEL_WHEEL or CMD_MOVE_VEL" - path commands belong to mode Automatic',
    telegrams=("CMD_MOVE_ABS", "CMD_MOVE_REL", "CMD_MOVE_PATH"),
)
add(
    "4.3/MODE_MOTION_JOYHARD/socket-moves-ignored",
    partial(_mode_ignores, mode=JOYHARD, names=("CMD_MOVE_VEL", "CMD_MOVE_VEL_WHEEL", "CMD_MOVE_REL")),
    **_GATE,
    level=Level.SHOULD,
    requirement='guide 4.3 Mode Joystick (Hardware): "The platform is controlled with a wireless remote '
    'controller" - not by socket move commands',
    telegrams=("CMD_MOVE_VEL", "CMD_MOVE_VEL_WHEEL", "CMD_MOVE_REL"),
)
