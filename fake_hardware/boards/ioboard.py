"""The IO board (CAN node 0): 16 digital inputs, 16 digital outputs, 8 analogue inputs, the battery voltage.

Rules:
- Inputs are plain attributes the world (or a test) sets: ``digital_in`` (bit mask), ``analog_in`` (8 ADC counts,
  10 bit, erratum E-HW-017). Outputs change only by CAN (DigOut, CMD_SET_DIGOUT).
- The battery voltage (mV) moves towards ``battery_target`` at ``battery_rate`` mV/s (the fault "battery drop"
  sets both); below ``low_battery`` the status says LOW_BATTERY and the self test fails (error 0x01).
"""

from __future__ import annotations

from typing import Any

from pltf.fake_hardware.boards.base import Board, Builder, Handler
from pltf.fake_hardware.candb import Node, Signals, St
from pltf.fake_hardware.canport import CanPort

NOMINAL_BATTERY = 25_600.0  # mV, a charged 24 V lead battery
LOW_BATTERY = 23_000.0  # mV


class IoBoard(Board):
    def __init__(self, port: CanPort) -> None:
        self.digital_in = 0
        self.digital_out = 0
        self.analog_in = [0] * 8
        self.battery = NOMINAL_BATTERY
        self.battery_target = NOMINAL_BATTERY
        self.battery_rate = 0.0  # mV/s; 0: jump to the target
        self.low_battery = LOW_BATTERY
        super().__init__(Node.IOBOARD, port)

    def commands(self) -> dict[str, Handler]:
        return {"DigOut": self._on_digout}

    def cyclic(self) -> dict[str, Builder]:
        return {
            "Digital": self._digital,
            "Analog1_4": self._analog_a,
            "Analog5_8": self._analog_b,
            "Battery": self._battery,
        }

    def _on_digout(self, signals: dict[str, Any], now: float) -> None:
        bit = 1 << int(signals["Channel"])
        self.digital_out = self.digital_out | bit if signals["Value"] else self.digital_out & ~bit

    def _digital(self, now: float) -> Signals:
        return {"DigIn": self.digital_in, "DigOut": self.digital_out, "Status": self.status()}

    def _analog_a(self, now: float) -> Signals:
        return {f"AnalogIn{i + 1}": self.analog_in[i] for i in range(4)}

    def _analog_b(self, now: float) -> Signals:
        return {f"AnalogIn{i + 1}": self.analog_in[i] for i in range(4, 8)}

    def _battery(self, now: float) -> Signals:
        return {"Voltage": round(self.battery), "Status": self.status()}

    def update(self, now: float, dt: float) -> None:
        gap = self.battery_target - self.battery
        if self.battery_rate <= 0.0:
            self.battery = self.battery_target
        else:
            step = self.battery_rate * dt
            self.battery += max(-step, min(step, gap))

    def self_test(self, now: float) -> int:
        return 0x01 if self.battery < self.low_battery else 0

    def status_bits(self) -> int:
        return St.LOW_BATTERY if self.battery < self.low_battery else 0

    def on_shutdown(self) -> None:
        self.digital_out = 0
