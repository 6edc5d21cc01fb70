"""A motor control board (CAN node 1 right, 2 left): velocity setpoints in, encoder ticks out.

Rules:
- The drive follows the last setpoint (mm/s at the wheel surface) within ``acc_limit`` while it is enabled:
  initialized, brake released, power on (emergency circuit closed), not over-temperature, and a setpoint
  arrived within ``setpoint_timeout`` (watchdog, erratum E-HW-008). Otherwise it brakes to 0 at
  ``brake_decel`` (brake engaged or power cut) or ramps to 0 at ``acc_limit``.
- ``wheel_velocity`` is what the world simulation reads. The world may report back how far the wheel really
  rolled in the last interval (``report_wheel_travel``); without a report the board assumes it rolled as driven.
  The encoder counts the true travel times ``1 + slip`` (the fault "encoder slip", erratum E-HW-007).
- Encoder: ``ticks_per_rev`` per wheel revolution (default 4096 per motor revolution x gear 20 = 81920),
  absolute int32 that wraps, starting at ``tick_offset``.
- Temperature: first-order model heated by the current; above ``trip_temp`` the board switches the drive off
  until it cools below ``recover_temp`` (erratum E-HW-020). ``temperature_override`` is the fault.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from pltf.fake_hardware.boards.base import Board, Builder, EmergencyCircuit, Handler
from pltf.fake_hardware.candb import MOTORS, Node, Signals, St
from pltf.fake_hardware.canport import CanPort

INT32 = 1 << 32


@dataclass(frozen=True)
class MotorParams:
    wheel_radius: float = 130.0  # mm: the true radius (parameter RadiusWheel's default)
    ticks_per_rev: int = 4096 * 20  # encoder ticks per wheel revolution
    acc_limit: float = 2000.0  # mm/s^2
    brake_decel: float = 5000.0  # mm/s^2
    setpoint_timeout: float = 0.25  # s
    ambient: float = 25.0  # degC
    thermal_tau: float = 300.0  # s
    heat_per_a2: float = 0.004  # degC/s per A^2 (5 A continuous: +30 degC)
    trip_temp: float = 80.0  # degC
    recover_temp: float = 70.0  # degC
    idle_current: float = 0.3  # A
    current_per_acc: float = 0.002  # A per mm/s^2
    stall_current: float = 8.0  # A

    @property
    def ticks_per_mm(self) -> float:
        return self.ticks_per_rev / (2 * math.pi * self.wheel_radius)


class MotorBoard(Board):
    def __init__(
        self,
        node: Node,
        port: CanPort,
        circuit: EmergencyCircuit,
        params: MotorParams | None = None,
        tick_offset: int = 0,
    ) -> None:
        if node not in MOTORS:
            raise ValueError(f"{node!r} is not a motor node")
        self.params = params or MotorParams()
        self.circuit = circuit
        self.setpoint = 0.0
        self.brake_released = False  # power-up: brake engaged (E-HW-005)
        self.velocity = 0.0  # mm/s, wheel surface
        self.current = 0.0  # A
        self.temperature = self.params.ambient
        self.temperature_override: float | None = None
        self.overtemp = False
        self.stalled = False
        self.slip = 0.0
        self.true_travel = 0.0  # mm rolled on the ground since power-up
        self.encoder_travel = 0.0  # mm the encoder has counted
        self.tick_offset = tick_offset
        self._last_setpoint_at: float | None = None
        self._world_travel: float | None = None
        self._counter = 0
        super().__init__(node, port)

    # ---- the world's side
    @property
    def wheel_velocity(self) -> float:
        """Surface velocity of the wheel in mm/s (what the world moves the platform with)."""
        return self.velocity

    def report_wheel_travel(self, delta_mm: float) -> None:
        """The distance the wheel really rolled since the last step (from the world simulation)."""
        self._world_travel = (self._world_travel or 0.0) + delta_mm

    @property
    def ticks(self) -> int:
        raw = round(self.encoder_travel * self.params.ticks_per_mm) + self.tick_offset
        return (raw + (1 << 31)) % INT32 - (1 << 31)

    # ---- CAN
    def commands(self) -> dict[str, Handler]:
        return {"Setpoint": self._on_setpoint, "Brake": self._on_brake}

    def cyclic(self) -> dict[str, Builder]:
        return {"Encoder": self._encoder, "State": self._state}

    def _on_setpoint(self, signals: dict[str, Any], now: float) -> None:
        self.setpoint = float(signals["Velocity"])
        self._last_setpoint_at = now

    def _on_brake(self, signals: dict[str, Any], now: float) -> None:
        self.brake_released = bool(signals["Release"])

    def _encoder(self, now: float) -> Signals:
        self._counter = (self._counter + 1) & 0xFF
        return {
            "Ticks": self.ticks,
            "Velocity": round(self.velocity),
            "Status": self.status(),
            "Counter": self._counter,
        }

    def _state(self, now: float) -> Signals:
        return {
            "Current": self.current,
            "Temperature": self.measured_temperature,
            "Setpoint": round(self.setpoint if self.enabled else 0.0),
            "Status": self.status(),
        }

    # ---- physics
    @property
    def power_on(self) -> bool:
        return not self.circuit.open

    @property
    def brake_engaged(self) -> bool:
        return not self.brake_released or not self.power_on  # the brakes are fail-safe: no power, brake on

    @property
    def setpoint_timed_out(self) -> bool:
        at = self._last_setpoint_at
        return at is None or self.now is None or self.now - at > self.params.setpoint_timeout

    @property
    def enabled(self) -> bool:
        return (
            self.initialized
            and self.power_on
            and not self.brake_engaged
            and not self.overtemp
            and not self.setpoint_timed_out
        )

    def update(self, now: float, dt: float) -> None:
        p = self.params
        v_old = self.velocity
        if self.enabled:
            target, acc = self.setpoint, p.acc_limit
        else:
            target, acc = 0.0, p.brake_decel if self.brake_engaged else p.acc_limit
        step = acc * dt
        self.velocity = v_old + max(-step, min(step, target - v_old))
        driven = 0.5 * (v_old + self.velocity) * dt
        travel = driven if self._world_travel is None else self._world_travel
        self._world_travel = None
        self.stalled = abs(v_old) > 50.0 and abs(travel) < 0.1 * abs(driven)
        self.true_travel += travel
        self.encoder_travel += travel * (1.0 + self.slip)
        a = 0.0 if dt <= 0.0 else abs(self.velocity - v_old) / dt
        moving = abs(self.velocity) > 1.0
        self.current = (
            (p.idle_current if moving else 0.0) + p.current_per_acc * a + (p.stall_current if self.stalled else 0.0)
        )
        if self.velocity < 0:
            self.current = -self.current
        self.temperature += dt * (p.heat_per_a2 * self.current**2 - (self.temperature - p.ambient) / p.thermal_tau)
        temp = self.measured_temperature
        if temp >= p.trip_temp:
            self.overtemp = True
        elif temp <= p.recover_temp:
            self.overtemp = False

    @property
    def measured_temperature(self) -> float:
        return self.temperature if self.temperature_override is None else self.temperature_override

    def self_test(self, now: float) -> int:
        errors = 0
        if self.measured_temperature >= self.params.trip_temp:
            errors |= 0x02
        if not self.power_on:
            errors |= 0x04
        return errors

    def status_bits(self) -> int:
        bits = 0
        if not self.power_on:
            bits |= St.EMERGENCY_STOP
        if self.overtemp:
            bits |= St.OVER_TEMPERATURE
        if self.brake_engaged:
            bits |= St.BRAKE_ENGAGED
        if self.initialized and self.setpoint_timed_out:
            bits |= St.SETPOINT_TIMEOUT
        if self.stalled:
            bits |= St.STALL
        return bits

    def on_shutdown(self) -> None:
        self.setpoint = 0.0
        self.brake_released = False
        self._last_setpoint_at = None
