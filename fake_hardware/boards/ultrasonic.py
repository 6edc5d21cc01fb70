"""The ultrasonic board (CAN node 3): 16 distance sensors, 4 analogue inputs, status, active-sensor mask.

Rules:
- Start (CMD_START_ULTRASONIC) sets the active-sensor bit mask (bit n = sensor n+1, erratum E-CMD-005) and starts
  the periodic measurement; Stop ends it. The distance frames are sent only while measuring.
- Distances come from ``range_source(now)`` (16 values in mm, e.g. the world's ray casting); ``None``, inf or
  anything beyond ``MAX_RANGE`` reads as MAX_RANGE ("no echo"); inactive sensors read 0 (erratum E-HW-012).
- A measurement is taken when a distance frame goes out (the DBC's 100 ms cycle), not every step: the frames carry
  exactly what measuring at each step would have put there, for a fifth of the ray casts at 50 Hz.
- The board has 4 analogue inputs (field evidence); the status telegram's 8 are filled by the controller.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

from pltf.fake_hardware.boards.base import Board, Builder, Handler
from pltf.fake_hardware.candb import Node, Signals, St
from pltf.fake_hardware.canport import CanPort

SENSORS = 16
MAX_RANGE = 3000  # mm
RangeSource = Callable[[float], Sequence[float | None]]


class UltrasonicBoard(Board):
    def __init__(self, port: CanPort, range_source: RangeSource | None = None) -> None:
        self.range_source = range_source
        self.active_mask = 0
        self.measuring = False
        self.analog_in = [0] * 4
        self.distances = [0] * SENSORS
        self._measured_at: float | None = None  # the ``now`` of ``distances`` (None: not measuring)
        super().__init__(Node.USBOARD, port)

    def commands(self) -> dict[str, Handler]:
        return {"Start": self._on_start, "Stop": self._on_stop}

    def cyclic(self) -> dict[str, Builder]:
        out: dict[str, Builder] = {}
        for k in range(4):
            out[f"Distances{4 * k + 1}_{4 * k + 4}"] = self._group(k)
        out["Analog1_4"] = self._analog
        out["Status"] = self._status
        return out

    def _group(self, k: int) -> Builder:
        def build(now: float) -> Signals | None:
            if not self.measuring:
                return None
            self._measure(now)
            return {f"Distance{i + 1}": self.distances[i] for i in range(4 * k, 4 * k + 4)}

        return build

    def _on_start(self, signals: dict[str, Any], now: float) -> None:
        self.active_mask = int(signals["ActiveMask"])
        self.measuring = True
        self._measured_at = None  # the new mask applies to the next frame

    def _on_stop(self, signals: dict[str, Any], now: float) -> None:
        self.measuring = False

    def update(self, now: float, dt: float) -> None:
        if not self.measuring:
            self.distances = [0] * SENSORS
            self._measured_at = None

    def _measure(self, now: float) -> None:
        """The 16 distances at ``now`` (once per ``now``: the four distance frames share one measurement)."""
        if self._measured_at == now:
            return
        self._measured_at = now
        ranges = list(self.range_source(now)) if self.range_source else []
        ranges += [None] * (SENSORS - len(ranges))
        out = []
        for i, r in enumerate(ranges[:SENSORS]):
            if not self.active_mask >> i & 1:
                out.append(0)
            elif r is None or math.isnan(r) or r >= MAX_RANGE:
                out.append(MAX_RANGE)
            else:
                out.append(max(1, round(r)))
        self.distances = out

    def _analog(self, now: float) -> Signals:
        return {f"AnalogIn{i + 1}": self.analog_in[i] for i in range(4)}

    def _status(self, now: float) -> Signals:
        return {"Status": self.status(), "ActiveMask": self.active_mask}

    def status_bits(self) -> int:
        return St.MEASURING if self.measuring else 0

    def on_shutdown(self) -> None:
        self.measuring = False
        self.active_mask = 0
