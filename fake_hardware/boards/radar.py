"""The radar board (CAN node 5): 4 velocity sensors (mm/s) from ``velocity_source(now)`` and a status."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from pltf.fake_hardware.boards.base import Board, Builder
from pltf.fake_hardware.candb import Node, Signals
from pltf.fake_hardware.canport import CanPort

VelocitySource = Callable[[float], Sequence[float]]


class RadarBoard(Board):
    def __init__(self, port: CanPort, velocity_source: VelocitySource | None = None) -> None:
        self.velocity_source = velocity_source
        self.velocities = [0.0] * 4
        super().__init__(Node.RADARBOARD, port)

    def cyclic(self) -> dict[str, Builder]:
        return {"Velocity": self._velocity, "Status": self._status}

    def update(self, now: float, dt: float) -> None:
        if self.velocity_source is not None:
            v = list(self.velocity_source(now))[:4]
            self.velocities = v + [0.0] * (4 - len(v))

    def _velocity(self, now: float) -> Signals:
        return {f"Velocity{i + 1}": round(self.velocities[i]) for i in range(4)}

    def _status(self, now: float) -> Signals:
        return {"Status": self.status()}
