"""CAN Communication Commands (guide 6.3): connect, shutdown, init, the boards' commands, raw CAN.

Rules: with a hardware plug-in (reference_server/hardware_link.py) every command goes over the CAN bus to the
boards of fake_hardware/ (errata E-HW-003 ff.); without one the platform has no CAN nodes: the board commands
are accepted, logged and without effect, CMD_GET_CAN_MESSAGES answers an empty list. A command for a board
that is not connected sends nothing and is logged (erratum E-HW-024). The board commands (brake, digital out,
ultrasonic) are one table, ``BOARD_COMMANDS``, and one handler, ``board_command``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from pltf.fake_hardware import MOTORS, CanController, ControllerError, Node
from pltf.reference_server import status
from pltf.reference_server.commands.registry import ACCEPTED, Outcome, handles

if TYPE_CHECKING:
    from pltf.reference_server.hardware_link import HardwareLink
    from pltf.reference_server.platform import Platform


@handles("CMD_CONNECT_TO_PLTF")
def connect(p: Platform, t: Any, now: float) -> Outcome:
    # guide 6.3: "causes an initialization of the CAN-field bus and a test of the CAN communication to the
    # several CAN nodes" - the bus is up at once; the probe's result is logged when it is done (E-HW-003)
    if p.hardware is None:
        p.log(logging.INFO, "CAN bus connected (simulated platform: no CAN nodes answer)")
        return ACCEPTED
    txn = p.hardware.connect(now)
    p.log(logging.INFO, f"CAN bus connected: probing {len(txn.pending) + len(txn.answers)} CAN nodes")
    return ACCEPTED


@handles("CMD_SHUTDOWN_PLTF")
def shutdown(p: Platform, t: Any, now: float) -> Outcome:
    # guide 6.3: "Used to shutdown the CAN communication"
    p.leave_operation("CAN shutdown", now)
    p.shutdown_hardware(now)
    p.log(logging.INFO, "CAN bus shut down, motion stopped")
    return ACCEPTED


@handles("CMD_INIT_PLTF")
def init(p: Platform, t: Any, now: float) -> Outcome:
    # guide 6.3: "The command initializes all CAN-hardware components and executes a platform self test."
    if p.hardware is None:
        p.log(logging.INFO, "platform initialized, self test passed")
        return ACCEPTED
    txn = p.hardware.init(now)
    if txn is None or not txn.done:  # erratum E-HW-024: the transition fires when the self test is done
        p.awaiting = t.NAME
        what = "waits for the CAN probe" if txn is None else "waits for the boards' answers"
        p.log(logging.INFO, f"self test {what}")
        return Outcome(pending=f"self test {what}")
    if not txn.ok:  # erratum E-HW-005: the platform stays not initialized
        failed = ", ".join(f"{r.node.name} 0x{r.errors:X}" for r in txn.results.values() if not r.passed)
        p.log(logging.WARNING, f"platform not initialized: the self test failed ({failed})")
        return Outcome(failed=f"self test failed: {failed}")
    return ACCEPTED


@dataclass(frozen=True)
class BoardCommand:
    """What one board command has of its own; ``board_command`` does the rest for all of them."""

    node: Callable[[Any], Node | None]  # the board the telegram addresses; None: it names none (refused)
    send: Callable[[CanController, Any, float], None]  # the controller call (raises ControllerError)
    done: Callable[[Any, Node], str]  # the log line once sent
    invalid: Callable[[Any], str] = lambda t: ""  # why ``node`` gave None
    no_bus: Callable[[Any], str] = lambda t: f"{t.NAME}: the board is not present on the CAN bus"


_DIGOUT_BOARDS = {0: Node.IOBOARD, 1: Node.RELAYBOARD}
_MOTORS = {int(m): m for m in MOTORS}

BOARD_COMMANDS: dict[str, BoardCommand] = {
    # guide 6.3 CMD_SET_BRAKE: "0: Brake enabled 1: Brake disabled" (erratum E-CMD-015)
    "CMD_SET_BRAKE": BoardCommand(
        node=lambda t: _MOTORS.get(t.motor),
        send=lambda c, t, now: c.set_brake(t.motor, t.state == 1, now),
        done=lambda t, _: f"brake of motor {t.motor} {'released' if t.state == 1 else 'engaged'}",
        invalid=lambda t: f"no motor {t.motor}",
        no_bus=lambda t: f"brake {t.state} set for motor {t.motor}: no motor board on the CAN bus",
    ),
    # guide 6.3 CMD_SET_DIGOUT: "Board Type: TYPE_IOBOARD = 0, TYPE_RELAYBOARD = 1" (errata E-CMD-004, E-HW-010)
    "CMD_SET_DIGOUT": BoardCommand(
        node=lambda t: _DIGOUT_BOARDS.get(t.board),
        send=lambda c, t, now: c.set_digout(t.board, t.channel, bool(t.value), now),
        done=lambda t, node: f"digital out: {node.name} channel {t.channel} = {t.value}",
        invalid=lambda t: f"no board type {t.board}",
    ),
    # guide 6.3: "Start the ultrasonic sensor measurement" - a bit mask of the active sensors (E-CMD-005)
    "CMD_START_ULTRASONIC": BoardCommand(
        node=lambda t: Node.USBOARD,
        send=lambda c, t, now: c.start_ultrasonic(t.active_channels, now),
        done=lambda t, _: f"ultrasonic measurement started, sensors 0x{t.active_channels:04X}",
    ),
    "CMD_STOP_ULTRASONIC": BoardCommand(
        node=lambda t: Node.USBOARD,
        send=lambda c, t, now: c.stop_ultrasonic(now),
        done=lambda t, _: "ultrasonic measurement stopped",
    ),
}


@handles(*BOARD_COMMANDS)
def board_command(p: Platform, t: Any, now: float) -> Outcome:
    """Send a board command over the bus; refused when the telegram names no board or the controller rejects
    its arguments, ignored without hardware or when the board is not connected (erratum E-HW-024)."""
    command = BOARD_COMMANDS[t.NAME]
    hw: HardwareLink | None = p.hardware
    if hw is None:
        return p.ignore(command.no_bus(t))
    node = command.node(t)
    if node is None:
        return p.refuse(f"{t.NAME} refused: {command.invalid(t)}")
    if not hw.connected(node):
        return p.ignore(f"{t.NAME}: {node.name} is not connected, nothing sent")
    try:
        command.send(hw.controller, t, now)
    except ControllerError as exc:
        return p.refuse(f"{t.NAME} refused: {exc}")
    p.log(logging.INFO, command.done(t, node))
    return ACCEPTED


@handles("CMD_SEND_CAN_MESSAGE")
def send_can_message(p: Platform, t: Any, now: float) -> Outcome:
    # guide 6.3: "Send a CAN-Message" - a standard frame with 8 data bytes (erratum E-HW-013)
    if p.hardware is None:
        return p.ignore(f"{t.NAME}: the board is not present on the CAN bus")
    data = bytes(t.data)
    try:
        sent = p.hardware.controller.send_can_message(t.can_id, data, now)
    except ControllerError as exc:
        return p.refuse(f"{t.NAME} refused: {exc}")
    p.log(logging.INFO, f"CAN message 0x{t.can_id:03X} [{data.hex(' ')}] {'sent' if sent else 'lost'}")
    return ACCEPTED


@handles("CMD_ADD_CAN_LISTENING_ID", "CMD_REMOVE_CAN_LISTENING_ID")
def can_listen(p: Platform, t: Any, now: float) -> Outcome:
    # guide 6.3: "Add a CAN-ID to the receive list. All messages with CAN-IDs of the list will be buffered"
    add = t.NAME == "CMD_ADD_CAN_LISTENING_ID"
    if add:
        p.can_listening.add(t.can_id)
    else:
        p.can_listening.discard(t.can_id)
    if p.hardware is not None:
        c = p.hardware.controller
        (c.add_listening_id if add else c.remove_listening_id)(t.can_id)
    p.log(
        logging.INFO, f"CAN listening id 0x{t.can_id:03X} {'added' if add else 'removed'} ({len(p.can_listening)} ids)"
    )
    return ACCEPTED


@handles("CMD_GET_CAN_MESSAGES")
def get_can_messages(p: Platform, t: Any, now: float) -> Outcome:
    # guide 6.3: "0: The message is kept, 1: The received message will be deleted" (errata E-REP-001, E-HW-013)
    if p.hardware is None:
        return Outcome(reply=status.reply("CMD_GET_CAN_MESSAGES", messages=()))  # no CAN node sends anything
    records = p.hardware.controller.get_can_messages(delete=t.delete == 1)
    messages = tuple((r.timestamp, r.can_id, tuple(r.data)) for r in records)
    return Outcome(reply=status.reply("CMD_GET_CAN_MESSAGES", messages=messages))
