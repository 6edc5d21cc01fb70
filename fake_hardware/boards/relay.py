"""The relay board (CAN node 4, erratum E-HW-016): relays, digital inputs, keypad, analogue inputs,
optosensors and the emergency-stop circuit.

Rules:
- The emergency-stop state is read from the shared ``EmergencyCircuit`` (wiring, not CAN). When it changes the
  board sends its State frame at once instead of waiting for the next cycle (erratum E-HW-009).
- Inputs are attributes the world sets: ``digital_in`` (8 bits), ``keypad`` (8 keys), ``analog_in`` (8 x 10-bit
  counts), ``opto_distance`` (4 x mm). Relays change only by CAN (RelayOut, CMD_SET_DIGOUT on the relay board).
"""

from __future__ import annotations

from typing import Any

from pltf.fake_hardware.boards.base import Board, Builder, EmergencyCircuit, Handler
from pltf.fake_hardware.candb import Node, Signals, St
from pltf.fake_hardware.canport import CanPort


class RelayBoard(Board):
    def __init__(self, port: CanPort, circuit: EmergencyCircuit) -> None:
        self.circuit = circuit
        self.digital_in = 0
        self.relays = 0
        self.keypad = 0
        self.analog_in = [0] * 8
        self.opto_distance = [0] * 4
        self._reported: tuple[bool, bool] | None = None
        super().__init__(Node.RELAYBOARD, port)

    def commands(self) -> dict[str, Handler]:
        return {"RelayOut": self._on_relay}

    def cyclic(self) -> dict[str, Builder]:
        return {"State": self._state, "Analog1_4": self._analog_a, "Analog5_8": self._analog_b, "Opto": self._opto}

    def _on_relay(self, signals: dict[str, Any], now: float) -> None:
        bit = 1 << int(signals["Channel"])
        self.relays = self.relays | bit if signals["Value"] else self.relays & ~bit

    def _state(self, now: float) -> Signals:
        self._reported = (self.circuit.button_pressed, self.circuit.open)
        return {
            "DigIn": self.digital_in,
            "Relays": self.relays,
            "Keypad": self.keypad,
            "EmergencyButton": int(self.circuit.button_pressed),
            "EmergencyCircuitOpen": int(self.circuit.open),
            "Status": self.status(),
        }

    def _analog_a(self, now: float) -> Signals:
        return {f"AnalogIn{i + 1}": self.analog_in[i] for i in range(4)}

    def _analog_b(self, now: float) -> Signals:
        return {f"AnalogIn{i + 1}": self.analog_in[i] for i in range(4, 8)}

    def _opto(self, now: float) -> Signals:
        return {f"Distance{i + 1}": self.opto_distance[i] for i in range(4)}

    def update(self, now: float, dt: float) -> None:
        if self._reported is not None and self._reported != (self.circuit.button_pressed, self.circuit.open):
            self.publish_now("State", now)

    def self_test(self, now: float) -> int:
        return 0x01 if self.circuit.open else 0

    def status_bits(self) -> int:
        return St.EMERGENCY_STOP if self.circuit.open else 0

    def on_shutdown(self) -> None:
        self.relays = 0
