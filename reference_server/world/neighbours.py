"""The other bodies of a shared world (a fleet, reference_server/fleet/): what one platform's world asks of them.

Rules:
- A ``World`` alone has no neighbours (``World.neighbours`` is None) and behaves exactly as before.
- In a fleet every world holds a ``Neighbours`` view of the fleet's one index of bodies: its own body is
  placed there after every move (``place``), the footprint follows the geometry parameters (``set_footprint``),
  the physics asks how deep a candidate pose overlaps another body (``depth``), and the sensors ask for the
  other bodies' outlines near a point (``segments_near``), which they cast their rays against like walls.
- Sans-IO, like the world: no clock; the fleet decides when each world moves.
"""

from __future__ import annotations

from typing import Protocol

from pltf.reference_server.world.geometry import F64
from pltf.reference_server.world.physics import Footprint


class Neighbours(Protocol):
    def place(self, x: float, y: float, a: float) -> None:
        """Our body is now at (x, y, a) (the true pose)."""

    def set_footprint(self, footprint: Footprint) -> None:
        """Our body's outline changed (geometry parameters)."""

    def depth(self, x: float, y: float, a: float) -> float:
        """How deep our footprint at (x, y, a) overlaps another body (0: free)."""

    def segments_near(self, x: float, y: float, radius: float) -> F64:
        """(K, 4) outline segments of the other bodies within ``radius`` of (x, y)."""


__all__ = ["Neighbours"]
