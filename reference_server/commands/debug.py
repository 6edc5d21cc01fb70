"""Debug Commands (guide 6.3, 6.4) and the identifiers known only from field code (layouts unknown)."""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from pltf.reference_server import status
from pltf.reference_server.commands.registry import ACCEPTED, Outcome, handles
from pltf.reference_server.enums import Event, MotionMode, MouseButton
from pltf.reference_server.state_chart import State

if TYPE_CHECKING:
    from pltf.reference_server.platform import Platform


@handles("CMD_GET_DEBUG_DATA")
def get_debug_data(p: Platform, t: Any, now: float) -> Outcome:
    return Outcome(reply=status.debug_reply(p))


@handles("CMD_GET_CAMERA")
def get_camera(p: Platform, t: Any, now: float) -> Outcome:
    return Outcome(reply=status.camera_reply())


@handles("CMD_MOUSE_MOVE")
def mouse_move(p: Platform, t: Any, now: float) -> Outcome:
    # guide 6.3: "Set the mouse obstacle": right button down places it, up removes it
    p.mouse_obstacle = (t.x, t.y) if t.button == MouseButton.EV_MOUSE_RBUTTON_DOWN else None
    if p.world is not None:
        p.world.set_mouse_obstacle(p.mouse_obstacle)
    return ACCEPTED


@handles("CMD_SET_LOG_ENABLED", "CMD_SET_POST_PROCESS_FILENAME")
def unused(p: Platform, t: Any, now: float) -> Outcome:
    return p.ignore(f"{t.NAME}: not used at the moment (guide 6.3)")


# guide 6.3 CMD_SET_EVENT: the replay's events; erratum E-MOT-010: they act in motion mode POST_PROCESS_REPLAY
# and state Running only (recording works in every mode)
_REPLAY_EVENTS = frozenset(
    Event[name]
    for name in (
        "EV_START_POST_PROCESS_REPLAY",
        "EV_STOP_POST_PROCESS_REPLAY",
        "EV_BREAK_POST_PROCESS_REPLAY",
        "EV_CONTINUE_POST_PROCESS_REPLAY",
    )
)


@handles("CMD_SET_EVENT")
def set_event(p: Platform, t: Any, now: float) -> Outcome:
    replaying = p.motion_mode == MotionMode.MODE_MOTION_POST_PROCESS_REPLAY and p.chart.state is State.RUNNING
    if t.event in _REPLAY_EVENTS and not replaying:
        return p.ignore(
            f"{t.NAME} {Event(t.event).name}: a replay runs in motion mode "
            f"MODE_MOTION_POST_PROCESS_REPLAY and state Running only, not {p.mode_name()} in "
            f"{p.chart.state.value} (erratum E-MOT-010)"
        )
    if p.world is not None:  # guide 6.3: post-process recording and replay (errata E-MOT-006, E-MOT-010)
        p.log(logging.INFO, f"{t.NAME} {Event(t.event).name}: {p.world.event(t.event, now)}")
        return ACCEPTED
    return p.ignore(f"{t.NAME} {Event(t.event).name}: post-process recording is not simulated")


@handles(
    "CMD_DEBUG1",
    "CMD_DEBUG2",
    "CMD_DEBUG3",
    "CMD_DEBUG4",
    "CMD_GET_MAPIMAGE",
    "CMD_ENABLE_EXT_MAPPING",
    "CMD_DISABLE_EXT_MAPPING",
    "CMD_EXT_WRITE_MAPPING",
    "CMD_EXT_READ_MAPPING",
    "CMD_WRITE_LCD",
    "CMD_STOP_MOTIONTHREAD",
    "CMD_RESTART_MOTIONTHREAD",
    "CMD_SHUTDOWN_HOST",
)
def layout_unknown(p: Platform, t: Any, now: float) -> Outcome:
    return p.ignore(f"{t.NAME}: layout unknown, command not supported")
