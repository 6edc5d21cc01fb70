"""Platform Operation Commands (guide 6.3, 4.2): start, break, continue, stop, motion mode, exit, close.

Rules: the state chart has already allowed the command and fires its transition afterwards; these handlers
only act on the motion and, in MODE_MOTION_PROGRAM, on the program (reference_server/program_api.py).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from pltf.reference_server.commands.registry import ACCEPTED, Outcome, handles
from pltf.reference_server.enums import MotionMode

if TYPE_CHECKING:
    from pltf.reference_server.platform import Platform


def _program_mode(p: Platform) -> bool:
    return bool(p.motion_mode == MotionMode.MODE_MOTION_PROGRAM)


# guide 4.3 Mode Program / 6.3: what each operation command does to the motion, then to the program in
# MODE_MOTION_PROGRAM (reference_server/program_api.py)
_OPERATIONS = {
    "CMD_START": ("stop", "start"),
    "CMD_BREAK": ("hold", "pause"),
    "CMD_CONTINUE": ("resume", "resume"),
    "CMD_STOP": ("stop", "stop"),
}


@handles(*_OPERATIONS)
def operate(p: Platform, t: Any, now: float) -> Outcome:
    motion_op, program_op = _OPERATIONS[t.NAME]
    getattr(p.motion, motion_op)()
    if t.NAME == "CMD_START":
        p.log(logging.INFO, f"start motion mode {p.mode_name()}")
    if _program_mode(p):
        getattr(p.program, program_op)(now)
    return ACCEPTED


@handles("CMD_SET_MODE")
def set_mode(p: Platform, t: Any, now: float) -> Outcome:
    p.motion_mode = t.mode
    p.log(logging.INFO, f"motion mode: {p.mode_name()}")
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
