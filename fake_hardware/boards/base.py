"""What every board does: answer probe, self test and shutdown, publish its cyclic messages on time.

Rules:
- A board is a node with one ``CanPort``. Its owner calls ``step(now)`` with simulated time (at least as often as
  the board's fastest cycle, 20 ms for the motors); the board reads what arrived, advances its physics by the
  elapsed time (``update``), then publishes every cyclic message that is due, stamped with ``now``.
- A board is silent until the first Probe (like a CANopen node started by its master), and silent again after
  a Shutdown (erratum E-HW-004). It answers Probe, SelfTest and Shutdown at any time.
- Subclasses override hooks only: ``commands()`` (function -> handler), ``cyclic()`` (function -> builder),
  ``update``, ``self_test`` and ``status_bits``. Message names, ids and periods come from the DBC.
- The emergency-stop circuit is wiring, not CAN: one ``EmergencyCircuit`` is shared by the relay board (which
  reports it) and the motor boards (whose power stage it cuts), erratum E-HW-009.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import can
from cantools.database.can import Message

from pltf.fake_hardware import candb
from pltf.fake_hardware.candb import Node, Signals, St
from pltf.fake_hardware.canport import CanPort

Handler = Callable[[dict[str, Any], float], None]
Builder = Callable[[float], Signals | None]  # None: nothing to send this cycle


@dataclass
class EmergencyCircuit:
    """The safety circuit: a pressed button opens it; it stays open until the button is up AND it is reset."""

    button_pressed: bool = False
    open: bool = False

    def press(self) -> None:
        self.button_pressed = True
        self.open = True

    def release(self, reset: bool = True) -> None:
        """Button up; with ``reset`` the safety system is reset in the same move (guide 4.2)."""
        self.button_pressed = False
        if reset:
            self.reset()

    def reset(self) -> bool:
        if self.button_pressed:
            return False
        self.open = False
        return True


@dataclass
class _Cyclic:
    msg: Message
    period: float
    build: Builder
    next_due: float = 0.0


class Board:
    firmware = 0x0102  # 1.2

    def __init__(self, node: Node, port: CanPort) -> None:
        self.node = node
        self.port = port
        self.started = False  # probed: cyclic transmission on
        self.initialized = False  # passed its last self test
        self.selftest_failed = False
        self.rx_malformed = 0
        self.now: float | None = None
        self._handlers: dict[int, tuple[Message, Handler]] = {}
        for function, handler in {
            "Probe": self._on_probe,
            "SelfTest": self._on_self_test,
            "Shutdown": self._on_shutdown,
            **self.commands(),
        }.items():
            msg = candb.message_for(node, function)
            self._handlers[msg.frame_id] = (msg, handler)
        port.accept(set(self._handlers))  # the board's acceptance filter: only the frames it handles
        self._cyclic: list[_Cyclic] = []
        self._due = 0.0  # the earliest next_due of the cyclic messages
        for function, builder in self.cyclic().items():
            msg = candb.message_for(node, function)
            period = candb.cycle_time(msg)
            assert period is not None, f"{msg.name} has no GenMsgCycleTime"
            self._cyclic.append(_Cyclic(msg, period, builder))

    # ---- hooks
    def commands(self) -> dict[str, Handler]:
        return {}

    def cyclic(self) -> dict[str, Builder]:
        return {}

    def update(self, now: float, dt: float) -> None:
        """Advance the board's physics by ``dt`` simulated seconds."""

    def self_test(self, now: float) -> int:
        """Error bits of a self test (0: passed)."""
        return 0

    def status_bits(self) -> int:
        """Board specific status bits, 0x04-0x80."""
        return 0

    def on_shutdown(self) -> None:
        """Forget what CMD_SHUTDOWN_PLTF makes a board forget."""

    # ---- the loop
    def step(self, now: float) -> None:
        dt = 0.0 if self.now is None else max(0.0, now - self.now)
        self.now = now
        for frame in self.port.poll(now):
            self._receive(frame, now)
        self.update(now, dt)
        if self.started and now >= self._due - 1e-9:  # most steps of a board with 100 ms cycles: nothing due
            due = math.inf
            for c in self._cyclic:
                if now >= c.next_due - 1e-9:
                    if (signals := c.build(now)) is not None:
                        self.port.send(candb.build(c.msg, signals, now), now)
                    c.next_due += c.period
                    if c.next_due <= now:  # late (slow stepping): no burst, resume the period from now
                        c.next_due = now + c.period
                due = min(due, c.next_due)
            self._due = due

    def status(self) -> int:
        bits = self.status_bits()
        if not self.initialized:
            bits |= St.NOT_INITIALIZED
        if self.selftest_failed:
            bits |= St.SELFTEST_FAILED
        return bits

    def send(self, function: str, signals: Signals, now: float) -> None:
        self.port.send(candb.build(candb.message_for(self.node, function), signals, now), now)

    def publish_now(self, function: str, now: float) -> None:
        """Send one cyclic message out of turn (an event such as the emergency circuit opening)."""
        for c in self._cyclic:
            if c.msg.name.endswith("_" + function) and self.started and (signals := c.build(now)) is not None:
                self.port.send(candb.build(c.msg, signals, now), now)

    def _receive(self, frame: can.Message, now: float) -> None:
        if frame.is_error_frame or frame.is_remote_frame:
            return
        entry = self._handlers.get(frame.arbitration_id)
        if entry is None:
            return
        msg, handler = entry
        signals = candb.decode(msg, frame)
        if signals is None:
            self.rx_malformed += 1
            return
        handler(signals, now)

    def _on_probe(self, signals: dict[str, Any], now: float) -> None:
        if not self.started:
            self.started = True
            for c in self._cyclic:
                c.next_due = now
            self._due = now
        self.send(
            "ProbeReply",
            {
                "NodeId": int(self.node),
                "Firmware": self.firmware,
                "Sequence": signals["Sequence"],
                "Status": self.status(),
            },
            now,
        )

    def _on_self_test(self, signals: dict[str, Any], now: float) -> None:
        errors = self.self_test(now)
        self.initialized = errors == 0
        self.selftest_failed = errors != 0
        self.send(
            "SelfTestResult",
            {"Sequence": signals["Sequence"], "Passed": int(errors == 0), "Errors": errors, "Status": self.status()},
            now,
        )

    def _on_shutdown(self, signals: dict[str, Any], now: float) -> None:
        self.started = False
        self.initialized = False
        self.selftest_failed = False
        self.on_shutdown()
