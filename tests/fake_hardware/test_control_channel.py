"""pltf.fake_hardware.control_channel: the line protocol, parsed and dispatched without I/O."""

from __future__ import annotations

import json
from typing import Any

import pytest

from pltf.fake_hardware import FaultKind, Hardware, Node, St
from pltf.fake_hardware.control_channel import COMMANDS, MAX_LINE, CommandError, ControlChannel, ControlSession, parse
from tests.fake_hardware.conftest import run


def ask(session: ControlSession, text: str, now: float = 0.0) -> list[dict[str, Any]]:
    out = session.receive_data(text.encode(), now)
    return [json.loads(line) for line in out.decode().splitlines()]


@pytest.fixture
def session(hw: Hardware) -> ControlSession:
    return ControlSession(ControlChannel(hw))


@pytest.mark.parametrize(
    ("line", "verb", "kind", "target", "value"),
    [
        ("unplug us", "inject", FaultKind.UNPLUG, "USBOARD", None),
        ("replug 3", "clear", FaultKind.UNPLUG, "USBOARD", None),
        ("estop press", "inject", FaultKind.EMERGENCY_STOP, None, None),
        ("ESTOP release", "clear", FaultKind.EMERGENCY_STOP, None, None),
        ("overtemp right 95", "inject", FaultKind.OVERTEMP, "MOTOR_RIGHT", 95.0),
        ("overtemp left off", "clear", FaultKind.OVERTEMP, "MOTOR_LEFT", None),
        ("slip motor-left 0.05", "inject", FaultKind.SLIP, "MOTOR_LEFT", 0.05),
        ("can-loss 0.1", "inject", FaultKind.CAN_LOSS, None, 0.1),
        ("can-loss 0.5 controller", "inject", FaultKind.CAN_LOSS, "CONTROLLER", 0.5),
        ("can-loss 0 gyro", "clear", FaultKind.CAN_LOSS, "GYROBOARD", None),
        ("can-delay 0.05 relay", "inject", FaultKind.CAN_DELAY, "RELAYBOARD", 0.05),
        ("bus-off", "inject", FaultKind.BUS_OFF, None, None),
        ("bus-on io", "clear", FaultKind.BUS_OFF, "IOBOARD", None),
        ("serial-corrupt 0.2", "inject", FaultKind.SERIAL_CORRUPT, None, 0.2),
        ("serial-silence on", "inject", FaultKind.SERIAL_SILENCE, None, None),
        ("battery 21000 5", "inject", FaultKind.BATTERY, None, 21000.0),
        ("battery off", "clear", FaultKind.BATTERY, None, None),
        ("clear slip right", "clear", FaultKind.SLIP, "MOTOR_RIGHT", None),
    ],
)
def test_parse(line: str, verb: str, kind: FaultKind, target: str | None, value: float | None) -> None:
    action, when, duration = parse(line, 0.0)
    assert action.verb == verb and action.fault is not None
    assert (action.fault.kind, action.fault.target) == (kind, target)
    if verb == "inject":
        assert action.fault.value == value
    assert when is None and duration is None


@pytest.mark.parametrize(
    "line",
    [
        "",
        "bogus",
        "unplug",
        "unplug mars",
        "overtemp io 90",
        "slip right",
        "estop twice",
        "can-loss lots",
        "serial-silence maybe",
        "clear nothing",
        "status now",
        "at 5 status",
        "replug us for 2",
        "unplug us for -1",
    ],
)
def test_parse_errors(line: str) -> None:
    with pytest.raises(CommandError):
        parse(line, 0.0)


def test_every_command_is_in_help(session: ControlSession) -> None:
    (reply,) = ask(session, "help\n")
    assert reply["ok"] and len(reply["commands"]) == len(COMMANDS)


def test_a_scripted_session(hw: Hardware, session: ControlSession) -> None:
    replies = ask(session, "# a comment\nunplug us for 1.5\nafter 0.5 estop press\nat 1.0 estop release\nfaults\n")
    assert [r["ok"] for r in replies] == [True] * 5
    assert replies[1] == {"ok": True, "injected": {"kind": "unplug", "target": "USBOARD"}, "until": 1.5}
    assert replies[2]["scheduled"] == {"at": 0.5, "action": "inject", "kind": "estop"}
    assert len(replies[4]["active"]) == 1 and len(replies[4]["scheduled"]) == 2
    t, _ = run(hw, 0.0, 0.7)
    (status,) = ask(session, "status\n", t)
    assert status["emergency"] and status["boards"]["us_status"] & St.NODE_TIMEOUT
    assert status["drive_fault"] == "emergency stop"
    t, _ = run(hw, t, 2.0)
    (status,) = ask(session, "status\n", t)
    assert not status["emergency"] and status["boards"]["us_status"] == 0
    (nodes,) = ask(session, "nodes\n", t)
    assert [n["name"] for n in nodes["nodes"]] == [n.name for n in Node]
    assert all(n["connected"] for n in nodes["nodes"])


def test_errors_are_replies_not_exceptions(session: ControlSession) -> None:
    replies = ask(session, "can-loss 3\nunplug\n\xff\n")
    assert [r["ok"] for r in replies] == [False, False, False]
    assert "outside" in replies[0]["error"]
    assert session.receive_data(b"\xff\xfe\n", 0.0) == b'{"ok":false,"error":"not UTF-8"}\n'


def test_lines_are_reassembled_and_overlong_lines_refused(hw: Hardware, session: ControlSession) -> None:
    assert session.receive_data(b"bus-", 0.0) == b""
    (reply,) = ask(session, "off\r\n")
    assert reply["ok"] and hw.controller_port.bus_off
    out = ask(session, "x" * (MAX_LINE + 10))
    assert out == [{"ok": False, "error": f"line longer than {MAX_LINE} bytes"}]
    assert ask(session, "yyy\nbus-on\n") == [{"ok": True, "cleared": True}]  # the rest of the long line is dropped
    assert not hw.controller_port.bus_off


def test_clear_all(hw: Hardware, session: ControlSession) -> None:
    ask(session, "unplug gyro\nslip right 0.2\nbattery 20000\n")
    assert len(hw.faults.active) == 3
    assert ask(session, "clear all\n") == [{"ok": True, "cleared": 3}]
    assert hw.faults.active == {} and hw.ports[Node.GYROBOARD].connected
