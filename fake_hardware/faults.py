"""Fault injection as data: a ``Fault`` names what breaks, ``FaultInjector`` applies and clears it in simulated time.

Rules:
- One table, ``EFFECTS``: per fault kind, which target it needs and the one function that switches the effect
  on or off on the boards, the ports, the emergency circuit or the scanner. Nothing else changes them.
- A fault is keyed by (kind, target); injecting it again replaces the value. ``duration`` clears it
  automatically; ``schedule`` applies (or clears) it at a later simulated time. ``step(now)`` does both.
- The effects are physical, never a status bit set by hand: an unplugged node's frames vanish and the
  controller notices the silence; over-temperature heats the board, which switches its drive off; and so on.
"""

from __future__ import annotations

import enum
import heapq
import itertools
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from pltf.fake_hardware.boards.ioboard import NOMINAL_BATTERY, IoBoard
from pltf.fake_hardware.boards.motor import MotorBoard
from pltf.fake_hardware.candb import MOTORS, Node
from pltf.fake_hardware.controller import HwEvent

if TYPE_CHECKING:
    from pltf.fake_hardware.canport import CanPort
    from pltf.fake_hardware.hardware import Hardware

CONTROLLER = "CONTROLLER"  # target of bus-off / can-loss / can-delay on the controller's own interface


class FaultKind(enum.StrEnum):
    UNPLUG = "unplug"  # target: node
    EMERGENCY_STOP = "estop"
    OVERTEMP = "overtemp"  # target: motor; value: degC (default 90)
    SLIP = "slip"  # target: motor; value: ratio, the encoder counts (1 + ratio) x the true travel
    CAN_LOSS = "can-loss"  # target: node, CONTROLLER or None (every sender); value: probability
    CAN_DELAY = "can-delay"  # target as CAN_LOSS; value: seconds
    BUS_OFF = "bus-off"  # target: node or CONTROLLER (default)
    SERIAL_CORRUPT = "serial-corrupt"  # value: probability that a telegram is corrupted
    SERIAL_SILENCE = "serial-silence"
    BATTERY = "battery"  # value: mV; ramp: seconds to get there (0: at once)


class FaultError(ValueError):
    """A fault that names a missing target or a value out of range."""


@dataclass(frozen=True)
class Fault:
    kind: FaultKind
    target: str | None = None  # a Node name, CONTROLLER, or None
    value: float | None = None
    ramp: float = 0.0

    @property
    def key(self) -> tuple[FaultKind, str | None]:
        return self.kind, self.target

    def describe(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": str(self.kind)}
        if self.target is not None:
            out["target"] = self.target
        if self.value is not None:
            out["value"] = self.value
        if self.ramp:
            out["ramp"] = self.ramp
        return out


Target = Literal["none", "node", "motor", "port"]  # port: a node, CONTROLLER, or None for the whole channel
Effect = Callable[["Hardware", Fault, bool], None]


def _node(fault: Fault) -> Node:
    return Node[fault.target or ""]


def _port(hw: Hardware, fault: Fault) -> CanPort:
    return hw.controller_port if fault.target in (None, CONTROLLER) else hw.ports[_node(fault)]


def _unplug(hw: Hardware, fault: Fault, on: bool) -> None:
    hw.ports[_node(fault)].connected = not on


def _estop(hw: Hardware, fault: Fault, on: bool) -> None:
    if on:
        hw.circuit.press()
    else:
        hw.circuit.release(reset=True)


def _motor(hw: Hardware, fault: Fault) -> MotorBoard:
    board = hw.boards[_node(fault)]
    assert isinstance(board, MotorBoard)
    return board


def _overtemp(hw: Hardware, fault: Fault, on: bool) -> None:
    _motor(hw, fault).temperature_override = (90.0 if fault.value is None else fault.value) if on else None


def _slip(hw: Hardware, fault: Fault, on: bool) -> None:
    _motor(hw, fault).slip = float(fault.value or 0.0) if on else 0.0


def _loss(hw: Hardware, fault: Fault, on: bool) -> None:
    p = float(fault.value or 0.0) if on else 0.0
    if fault.target is None:
        hw.conditions.loss = p
    else:
        _port(hw, fault).loss = p


def _delay(hw: Hardware, fault: Fault, on: bool) -> None:
    d = float(fault.value or 0.0) if on else 0.0
    if fault.target is None:
        hw.conditions.delay = d
    else:
        _port(hw, fault).delay = d


def _bus_off(hw: Hardware, fault: Fault, on: bool) -> None:
    _port(hw, fault).bus_off = on


def _scanner(hw: Hardware) -> Any:
    if hw.scanner is None:
        raise FaultError("this platform has no simulated laser scanner")
    return hw.scanner


def _corrupt(hw: Hardware, fault: Fault, on: bool) -> None:
    _scanner(hw).corrupt_probability = float(fault.value or 0.0) if on else 0.0


def _silence(hw: Hardware, fault: Fault, on: bool) -> None:
    _scanner(hw).silent = on


def _battery(hw: Hardware, fault: Fault, on: bool) -> None:
    io = hw.boards[Node.IOBOARD]
    assert isinstance(io, IoBoard)
    target = float(fault.value if fault.value is not None else NOMINAL_BATTERY) if on else NOMINAL_BATTERY
    io.battery_rate = abs(target - io.battery) / fault.ramp if on and fault.ramp > 0 else 0.0
    io.battery_target = target


EFFECTS: dict[FaultKind, tuple[Target, tuple[float, float] | None, Effect]] = {
    FaultKind.UNPLUG: ("node", None, _unplug),
    FaultKind.EMERGENCY_STOP: ("none", None, _estop),
    FaultKind.OVERTEMP: ("motor", (-40.0, 200.0), _overtemp),
    FaultKind.SLIP: ("motor", (-0.9, 10.0), _slip),
    FaultKind.CAN_LOSS: ("port", (0.0, 1.0), _loss),
    FaultKind.CAN_DELAY: ("port", (0.0, 60.0), _delay),
    FaultKind.BUS_OFF: ("port", None, _bus_off),
    FaultKind.SERIAL_CORRUPT: ("none", (0.0, 1.0), _corrupt),
    FaultKind.SERIAL_SILENCE: ("none", None, _silence),
    FaultKind.BATTERY: ("none", (0.0, 65_535.0), _battery),
}


@dataclass
class ActiveFault:
    fault: Fault
    since: float
    until: float | None


class FaultInjector:
    def __init__(self, hw: Hardware) -> None:
        self.hw = hw
        self.active: dict[tuple[FaultKind, str | None], ActiveFault] = {}
        self.scheduled: list[tuple[float, int, Literal["inject", "clear"], Fault, float | None]] = []
        self._seq = itertools.count()

    def check(self, fault: Fault) -> Fault:
        """The fault with its target normalised (BUS_OFF defaults to the controller), or FaultError."""
        needs, bounds, _ = EFFECTS[fault.kind]
        target = fault.target
        if fault.kind == FaultKind.BUS_OFF and target is None:
            target = CONTROLLER
        if needs == "none" and target is not None:
            raise FaultError(f"{fault.kind} takes no target")
        if needs in ("node", "motor") or (needs == "port" and target not in (None, CONTROLLER)):
            if target is None or target not in Node.__members__:
                raise FaultError(f"{fault.kind} needs a node, not {target!r}")
            if Node[target] not in self.hw.boards:
                raise FaultError(f"{target} is not fitted on this platform")
            if needs == "motor" and Node[target] not in MOTORS:
                raise FaultError(f"{fault.kind} needs a motor, not {target}")
        if bounds is not None and fault.value is not None and not bounds[0] <= fault.value <= bounds[1]:
            raise FaultError(f"{fault.kind} value {fault.value} outside {bounds[0]}..{bounds[1]}")
        if fault.kind in (FaultKind.SERIAL_CORRUPT, FaultKind.SERIAL_SILENCE):
            _scanner(self.hw)
        return Fault(fault.kind, target, fault.value, fault.ramp)

    def inject(self, fault: Fault, now: float, duration: float | None = None) -> Fault:
        fault = self.check(fault)
        EFFECTS[fault.kind][2](self.hw, fault, True)
        self.active[fault.key] = ActiveFault(fault, now, None if duration is None else now + duration)
        return fault

    def clear(self, kind: FaultKind, target: str | None = None, now: float = 0.0) -> bool:
        """Undo a fault (replug, release the emergency stop, ...); False when it was not active."""
        if kind == FaultKind.BUS_OFF and target is None:
            target = CONTROLLER
        entry = self.active.pop((kind, target), None)
        if entry is None:
            return False
        EFFECTS[kind][2](self.hw, entry.fault, False)
        return True

    def clear_all(self, now: float) -> int:
        keys = list(self.active)
        for kind, target in keys:
            self.clear(kind, target, now)
        return len(keys)

    def schedule(
        self, at: float, fault: Fault, duration: float | None = None, action: Literal["inject", "clear"] = "inject"
    ) -> Fault:
        fault = self.check(fault) if action == "inject" else fault
        heapq.heappush(self.scheduled, (at, next(self._seq), action, fault, duration))
        return fault

    def step(self, now: float) -> list[HwEvent]:
        events: list[HwEvent] = []
        while self.scheduled and self.scheduled[0][0] <= now:
            _, _, action, fault, duration = heapq.heappop(self.scheduled)
            try:
                if action == "inject":
                    self.inject(fault, now, duration)
                elif not self.clear(fault.kind, fault.target, now):
                    continue
            except FaultError as e:  # the platform changed since it was scheduled
                events.append(HwEvent("fault", None, f"scheduled fault {fault.describe()} not applied: {e}"))
                continue
            events.append(HwEvent("fault", None, f"fault {action}: {fault.describe()}"))
        for key, entry in list(self.active.items()):
            if entry.until is not None and entry.until <= now:
                self.clear(*key, now=now)
                events.append(HwEvent("fault", None, f"fault cleared after its duration: {entry.fault.describe()}"))
        return events

    def describe(self) -> dict[str, Any]:
        return {
            "active": [
                {**a.fault.describe(), "since": a.since, **({"until": a.until} if a.until is not None else {})}
                for a in self.active.values()
            ],
            "scheduled": [
                {"at": at, "action": action, **fault.describe(), **({"for": d} if d is not None else {})}
                for at, _, action, fault, d in sorted(self.scheduled)
            ],
        }
