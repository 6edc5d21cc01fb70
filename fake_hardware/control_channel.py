"""The fault-control channel: a line protocol, parsed and dispatched without I/O (the socket lives in the server).

Rules:
- One request per line (UTF-8, at most ``MAX_LINE`` bytes), one JSON object per response line:
  ``{"ok": true, ...}`` or ``{"ok": false, "error": "..."}``. The grammar is in fake_hardware/README.md.
- Every command is a row of ``COMMANDS``: a parser from the words to an ``Action``. Faults go through the
  ``FaultInjector`` only; queries only read.
- ``at T`` / ``after DT`` prefixes schedule an action in simulated time; a ``for DT`` suffix clears an injected
  fault after DT. Time comes in as ``now``.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from pltf.fake_hardware.candb import MOTORS, Node
from pltf.fake_hardware.faults import CONTROLLER, Fault, FaultError, FaultKind

if TYPE_CHECKING:
    from pltf.fake_hardware.hardware import Hardware

MAX_LINE = 4096
ALIASES: dict[str, Node] = {
    "io": Node.IOBOARD,
    "ioboard": Node.IOBOARD,
    "motor-right": Node.MOTOR_RIGHT,
    "right": Node.MOTOR_RIGHT,
    "motor_right": Node.MOTOR_RIGHT,
    "motor-left": Node.MOTOR_LEFT,
    "left": Node.MOTOR_LEFT,
    "motor_left": Node.MOTOR_LEFT,
    "us": Node.USBOARD,
    "usboard": Node.USBOARD,
    "ultrasonic": Node.USBOARD,
    "relay": Node.RELAYBOARD,
    "relayboard": Node.RELAYBOARD,
    "radar": Node.RADARBOARD,
    "radarboard": Node.RADARBOARD,
    "gyro": Node.GYROBOARD,
    "gyroboard": Node.GYROBOARD,
}


class CommandError(ValueError):
    pass


@dataclass(frozen=True)
class Action:
    verb: Literal["inject", "clear", "clear-all", "query"]
    fault: Fault | None = None
    query: str = ""


def node(word: str) -> Node:
    w = word.lower()
    if w in ALIASES:
        return ALIASES[w]
    if w.isdigit() and int(w) in Node._value2member_map_:
        return Node(int(w))
    if word.upper() in Node.__members__:
        return Node[word.upper()]
    raise CommandError(f"unknown node {word!r} (try: nodes)")


def _motor(word: str) -> str:
    n = node(word)
    if n not in MOTORS:
        raise CommandError(f"{word!r} is not a motor (right, left)")
    return n.name


def _port(words: list[str]) -> str | None:
    if not words:
        return None
    if words[0].lower() == "controller":
        return CONTROLLER
    return node(words[0]).name


def _number(word: str) -> float:
    try:
        return float(word)
    except ValueError:
        raise CommandError(f"not a number: {word!r}") from None


def _arity(words: list[str], lo: int, hi: int) -> list[str]:
    if not lo <= len(words) <= hi:
        raise CommandError("wrong number of arguments (try: help)")
    return words


def _inject(kind: FaultKind, target: str | None = None, value: float | None = None, ramp: float = 0.0) -> Action:
    return Action("inject", Fault(kind, target, value, ramp))


def _clear(kind: FaultKind, target: str | None = None) -> Action:
    return Action("clear", Fault(kind, target))


def _value_or_clear(kind: FaultKind, target: str | None, word: str) -> Action:
    if word.lower() == "off":
        return _clear(kind, target)
    value = _number(word)
    return _clear(kind, target) if value == 0 and kind != FaultKind.OVERTEMP else _inject(kind, target, value)


def _unplug(w: list[str]) -> Action:
    return _inject(FaultKind.UNPLUG, node(_arity(w, 1, 1)[0]).name)


def _replug(w: list[str]) -> Action:
    return _clear(FaultKind.UNPLUG, node(_arity(w, 1, 1)[0]).name)


def _estop(w: list[str]) -> Action:
    what = _arity(w, 1, 1)[0].lower()
    if what not in ("press", "release"):
        raise CommandError("estop press|release")
    return _inject(FaultKind.EMERGENCY_STOP) if what == "press" else _clear(FaultKind.EMERGENCY_STOP)


def _overtemp(w: list[str]) -> Action:
    _arity(w, 2, 2)
    return _value_or_clear(FaultKind.OVERTEMP, _motor(w[0]), w[1])


def _slip(w: list[str]) -> Action:
    _arity(w, 2, 2)
    return _value_or_clear(FaultKind.SLIP, _motor(w[0]), w[1])


def _can(kind: FaultKind) -> Callable[[list[str]], Action]:
    def parse(w: list[str]) -> Action:
        _arity(w, 1, 2)
        return _value_or_clear(kind, _port(w[1:]), w[0])

    return parse


def _bus_off(w: list[str]) -> Action:
    return _inject(FaultKind.BUS_OFF, _port(_arity(w, 0, 1)))


def _bus_on(w: list[str]) -> Action:
    return _clear(FaultKind.BUS_OFF, _port(_arity(w, 0, 1)))


def _corrupt(w: list[str]) -> Action:
    return _value_or_clear(FaultKind.SERIAL_CORRUPT, None, _arity(w, 1, 1)[0])


def _silence(w: list[str]) -> Action:
    what = _arity(w, 1, 1)[0].lower()
    if what not in ("on", "off"):
        raise CommandError("serial-silence on|off")
    return _inject(FaultKind.SERIAL_SILENCE) if what == "on" else _clear(FaultKind.SERIAL_SILENCE)


def _battery(w: list[str]) -> Action:
    _arity(w, 1, 2)
    if w[0].lower() == "off":
        return _clear(FaultKind.BATTERY)
    return _inject(FaultKind.BATTERY, None, _number(w[0]), _number(w[1]) if len(w) > 1 else 0.0)


def _clear_cmd(w: list[str]) -> Action:
    _arity(w, 0, 2)
    if not w or w[0].lower() == "all":
        return Action("clear-all")
    try:
        kind = FaultKind(w[0].lower())
    except ValueError:
        raise CommandError(f"unknown fault kind {w[0]!r}") from None
    target = None
    if len(w) > 1:
        target = _port(w[1:])
    return _clear(kind, target)


def _query(name: str) -> Callable[[list[str]], Action]:
    def parse(w: list[str]) -> Action:
        _arity(w, 0, 0)
        return Action("query", query=name)

    return parse


COMMANDS: dict[str, tuple[Callable[[list[str]], Action], str]] = {
    "help": (_query("help"), "help"),
    "nodes": (_query("nodes"), "nodes"),
    "faults": (_query("faults"), "faults"),
    "status": (_query("status"), "status"),
    "pose": (_query("pose"), "pose"),
    "unplug": (_unplug, "unplug NODE"),
    "replug": (_replug, "replug NODE"),
    "estop": (_estop, "estop press|release"),
    "overtemp": (_overtemp, "overtemp MOTOR DEGC|off"),
    "slip": (_slip, "slip MOTOR RATIO|off"),
    "can-loss": (_can(FaultKind.CAN_LOSS), "can-loss PROBABILITY|off [NODE|controller]"),
    "can-delay": (_can(FaultKind.CAN_DELAY), "can-delay SECONDS|off [NODE|controller]"),
    "bus-off": (_bus_off, "bus-off [NODE|controller]"),
    "bus-on": (_bus_on, "bus-on [NODE|controller]"),
    "serial-corrupt": (_corrupt, "serial-corrupt PROBABILITY|off"),
    "serial-silence": (_silence, "serial-silence on|off"),
    "battery": (_battery, "battery MILLIVOLTS [RAMP_SECONDS] | battery off"),
    "clear": (_clear_cmd, "clear [all | KIND [NODE|controller]]"),
}


def parse(line: str, now: float) -> tuple[Action, float | None, float | None]:
    """(action, when: simulated time or None for now, duration or None)."""
    words = line.split()
    when = None
    if len(words) >= 2 and words[0].lower() in ("at", "after"):
        t = _number(words[1])
        when = t if words[0].lower() == "at" else now + t
        words = words[2:]
    duration = None
    if len(words) >= 2 and words[-2].lower() == "for":
        duration = _number(words[-1])
        if duration <= 0:
            raise CommandError("for: the duration must be positive")
        words = words[:-2]
    if not words:
        raise CommandError("empty command (try: help)")
    entry = COMMANDS.get(words[0].lower())
    if entry is None:
        raise CommandError(f"unknown command {words[0]!r} (try: help)")
    action = entry[0](words[1:])
    if duration is not None and action.verb != "inject":
        raise CommandError("for: only an injected fault can have a duration")
    if when is not None and action.verb == "query":
        raise CommandError("a query cannot be scheduled")
    return action, when, duration


Query = Callable[[float], dict[str, Any]]


class ControlChannel:
    """``extra``: queries the owner answers (the server's ``pose``: true and estimated pose)."""

    def __init__(self, hw: Hardware, extra: Mapping[str, Query] | None = None) -> None:
        self.hw = hw
        self.extra = dict(extra or {})

    def handle_line(self, line: str, now: float) -> dict[str, Any]:
        try:
            action, when, duration = parse(line, now)
            return {"ok": True, **self._dispatch(action, when, duration, now)}
        except (CommandError, FaultError) as e:
            return {"ok": False, "error": str(e)}

    def _dispatch(self, action: Action, when: float | None, duration: float | None, now: float) -> dict[str, Any]:
        faults = self.hw.faults
        if action.verb == "query":
            if action.query in self.extra:
                return self.extra[action.query](now)
            if action.query not in QUERIES:
                raise CommandError(f"{action.query}: not available on this channel")
            return QUERIES[action.query](self.hw, now)
        if action.verb == "clear-all":
            if when is not None:
                raise CommandError("clear all cannot be scheduled")
            return {"cleared": faults.clear_all(now)}
        assert action.fault is not None
        if when is not None:
            verb: Literal["inject", "clear"] = "inject" if action.verb == "inject" else "clear"
            fault = faults.schedule(when, action.fault, duration, verb)
            return {"scheduled": {"at": when, "action": verb, **fault.describe()}}
        if action.verb == "inject":
            fault = faults.inject(action.fault, now, duration)
            return {"injected": fault.describe(), **({"until": now + duration} if duration else {})}
        f = action.fault
        return {"cleared": faults.clear(f.kind, f.target, now)}


def _help(hw: Hardware, now: float) -> dict[str, Any]:
    return {"commands": [usage for _, usage in COMMANDS.values()], "prefix": ["at T", "after DT"], "suffix": "for DT"}


def _nodes(hw: Hardware, now: float) -> dict[str, Any]:
    return {
        "nodes": [
            {"name": n.name, "id": int(n), "fitted": n in hw.boards, "connected": n in hw.controller.connected}
            for n in Node
        ]
    }


def _faults(hw: Hardware, now: float) -> dict[str, Any]:
    return {"time": now, **hw.faults.describe()}


def _status(hw: Hardware, now: float) -> dict[str, Any]:
    c = hw.controller
    out: dict[str, Any] = {
        "time": now,
        "bus_up": c.bus_up,
        "bus_off": c.bus_off,
        "emergency": c.emergency_active,
        "drive_fault": c.drive_fault(),
        "wheel_travel": list(c.wheel_travel),
        "boards": c.board_status().as_fields(),
    }
    if hw.scan_reader is not None:
        d = hw.scan_reader.decoder
        out["scanner"] = {"ok": hw.scanner_ok, "telegrams": d.telegrams, "crc_errors": d.crc_errors, "lost": d.lost}
    return out


QUERIES: dict[str, Callable[[Hardware, float], dict[str, Any]]] = {
    "help": _help,
    "nodes": _nodes,
    "faults": _faults,
    "status": _status,
}


class ControlSession:
    """One client of the channel: bytes in, response bytes out (one JSON line per request line)."""

    def __init__(self, channel: ControlChannel) -> None:
        self.channel = channel
        self._buf = bytearray()
        self._overlong = False

    def receive_data(self, data: bytes, now: float) -> bytes:
        self._buf += data
        out: list[dict[str, Any]] = []
        while (i := self._buf.find(b"\n")) >= 0:
            raw = bytes(self._buf[:i]).rstrip(b"\r")
            del self._buf[: i + 1]
            if self._overlong:
                self._overlong = False
                continue
            out.append(self._line(raw, now))
        if len(self._buf) > MAX_LINE:
            self._buf.clear()
            self._overlong = True  # drop the rest of this line when its newline comes
            out.append({"ok": False, "error": f"line longer than {MAX_LINE} bytes"})
        return b"".join(json.dumps(r, separators=(",", ":")).encode() + b"\n" for r in out)

    def _line(self, raw: bytes, now: float) -> dict[str, Any]:
        if len(raw) > MAX_LINE:
            return {"ok": False, "error": f"line longer than {MAX_LINE} bytes"}
        try:
            line = raw.decode("utf-8")
        except UnicodeDecodeError:
            return {"ok": False, "error": "not UTF-8"}
        if not line.strip() or line.lstrip().startswith("#"):
            return {"ok": True}
        return self.channel.handle_line(line, now)
