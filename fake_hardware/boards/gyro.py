"""The gyro board (CAN node 6): 3 accelerations, the integrated yaw angle, temperature, status.

Rules:
- ``motion_source(now)`` gives (ax, ay, az in m/s^2, yaw rate in rad/s), e.g. from the world simulation; without
  one the board lies still (0, 0, 9.81, 0). The angle integrates the yaw rate plus ``drift`` (rad/s).
- The self test zeroes the angle (the board calibrates at CMD_INIT_PLTF) and fails with error 0x02 when the
  yaw rate is not near zero (erratum E-HW-019).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from pltf.fake_hardware.boards.base import Board, Builder
from pltf.fake_hardware.candb import Node, Signals
from pltf.fake_hardware.canport import CanPort

MotionSource = Callable[[float], tuple[float, float, float, float]]
STILL = (0.0, 0.0, 9.81, 0.0)


class GyroBoard(Board):
    def __init__(self, port: CanPort, motion_source: MotionSource | None = None) -> None:
        self.motion_source = motion_source
        self.accel = STILL[:3]
        self.yaw_rate = 0.0
        self.angle = 0.0  # rad, wrapped to (-pi, pi]
        self.drift = 0.0
        self.temperature = 35.0  # degC
        super().__init__(Node.GYROBOARD, port)

    def cyclic(self) -> dict[str, Builder]:
        return {"Accel": self._accel, "Angle": self._angle}

    def update(self, now: float, dt: float) -> None:
        ax, ay, az, rate = self.motion_source(now) if self.motion_source else STILL
        self.accel = (ax, ay, az)
        self.yaw_rate = rate
        self.angle = math.remainder(self.angle + (rate + self.drift) * dt, 2 * math.pi)

    def _accel(self, now: float) -> Signals:
        return {"AccelX": self.accel[0], "AccelY": self.accel[1], "AccelZ": self.accel[2]}

    def _angle(self, now: float) -> Signals:
        return {"Angle": self.angle, "Temperature": self.temperature, "Status": self.status()}

    def self_test(self, now: float) -> int:
        self.angle = 0.0
        return 0x02 if abs(self.yaw_rate) > 0.01 else 0
