"""Platform Operation Commands (guide 6.3, 4.2): start, break, continue, stop, motion mode, exit, close.

Rules: the state chart has already allowed the command and fires its transition afterwards; these handlers
only act on the motion and, in MODE_MOTION_PROGRAM, on the program (reference_server/program_api.py).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from reference_server.commands.registry import ACCEPTED, Outcome, handles
from reference_server.enums import MotionMode

if TYPE_CHECKING:
    from reference_server.platform import Platform


def _program_mode(p: Platform) -> bool:
    return bool(p.motion_mode == MotionMode.MODE_MOTION_PROGRAM)


@handles("CMD_START")
def start(p: Platform, t: Any, now: float) -> Outcome:
    p.motion.stop()
    p.log(logging.INFO, f"start motion mode {p._mode_name()}")
    if _program_mode(p):
        p.program.start(now)
    return ACCEPTED


@handles("CMD_BREAK")
def break_(p: Platform, t: Any, now: float) -> Outcome:
    p.motion.hold()
    if _program_mode(p):
        p.program.pause(now)
    return ACCEPTED


@handles("CMD_CONTINUE")
def continue_(p: Platform, t: Any, now: float) -> Outcome:
    p.motion.resume()
    if _program_mode(p):
        p.program.resume(now)
    return ACCEPTED


@handles("CMD_STOP")
def stop(p: Platform, t: Any, now: float) -> Outcome:
    p.motion.stop()
    if _program_mode(p):
        p.program.stop(now)
    return ACCEPTED


@handles("CMD_SET_MODE")
def set_mode(p: Platform, t: Any, now: float) -> Outcome:
    p.motion_mode = t.mode
    p.log(logging.INFO, f"motion mode: {p._mode_name()}")
    return ACCEPTED


@handles("CMD_EXIT")
def exit_(p: Platform, t: Any, now: float) -> Outcome:
    p.leave_operation("exit", now)
    p.shutdown_hardware(now)
    p.chart.shutdown()
    p.log(logging.INFO, "exit: platform control shuts down")
    return Outcome(exit_server=True)


@handles("CMD_CLOSE_SOCKET")
def close_socket(p: Platform, t: Any, now: float) -> Outcome:
    return Outcome(close_connection=True)
