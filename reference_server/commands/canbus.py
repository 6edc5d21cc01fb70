"""CAN Communication Commands (guide 6.3): connect, shutdown, init, the boards' commands, raw CAN."""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from reference_server import status
from reference_server.commands.registry import ACCEPTED, Outcome, handles

if TYPE_CHECKING:
    from reference_server.platform import Platform


@handles("CMD_CONNECT_TO_PLTF")
def connect(p: Platform, t: Any, now: float) -> Outcome:
    p.log(logging.INFO, "CAN bus connected (simulated platform: no CAN nodes answer)")
    return ACCEPTED


@handles("CMD_SHUTDOWN_PLTF")
def shutdown(p: Platform, t: Any, now: float) -> Outcome:
    p.leave_operation("CAN shutdown", now)
    p.log(logging.INFO, "CAN bus shut down, motion stopped")
    return ACCEPTED


@handles("CMD_INIT_PLTF")
def init(p: Platform, t: Any, now: float) -> Outcome:
    p.log(logging.INFO, "platform initialized, self test passed")
    return ACCEPTED


@handles("CMD_SET_BRAKE")
def set_brake(p: Platform, t: Any, now: float) -> Outcome:
    return p._ignore(f"brake {t.state} set for motor {t.motor}: no motor board on the CAN bus")


@handles("CMD_SET_DIGOUT", "CMD_START_ULTRASONIC", "CMD_STOP_ULTRASONIC", "CMD_SEND_CAN_MESSAGE")
def absent_board(p: Platform, t: Any, now: float) -> Outcome:
    return p._ignore(f"{t.NAME}: the board is not present on the CAN bus")


@handles("CMD_ADD_CAN_LISTENING_ID", "CMD_REMOVE_CAN_LISTENING_ID")
def can_listen(p: Platform, t: Any, now: float) -> Outcome:
    if t.NAME == "CMD_ADD_CAN_LISTENING_ID":
        p.can_listening.add(t.can_id)
    else:
        p.can_listening.discard(t.can_id)
    p.log(logging.INFO, f"CAN listening ids: {sorted(p.can_listening)}")
    return ACCEPTED


@handles("CMD_GET_CAN_MESSAGES")
def get_can_messages(p: Platform, t: Any, now: float) -> Outcome:
    return Outcome(reply=status.reply("CMD_GET_CAN_MESSAGES", messages=()))  # no CAN node sends anything yet
