"""Free places of a map for ``pltf serve --fleet N``: the roadmap's stations first, then a grid over the map.

Rules:
- A place is free when a platform turning on the spot there (its footprint's circumscribed ``radius`` plus
  ``MARGIN``) touches no wall, auxiliary line or pillar, lies in a workarea (if the map has any) and outside every
  prohibited area, and keeps ``2 * radius + MARGIN`` from every place chosen before it: the platforms start
  apart and can each turn without touching another.
- Stations come first, in the roadmap's order, at the station's angle; then the points of a grid of pitch
  ``2 * radius + MARGIN`` over the map's bounds, row by row from the lower left, heading along +x.
- Too few free places is a ``FleetError`` naming how many there are.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from pltf.reference_server.fleet.config import FleetError, Pose
from pltf.reference_server.world.geometry import MapGeometry, clearance

MARGIN = 200.0  # mm between two platforms turning on the spot at neighbouring places


def free_places(geometry: MapGeometry, stations: Iterable[Pose], radius: float, count: int) -> list[Pose]:
    """``count`` free places for platforms of footprint ``radius``: stations first, then the grid."""
    pitch = 2.0 * radius + MARGIN
    candidates = [*stations, *_grid(geometry, pitch)]
    if not candidates:
        raise FleetError("the map has no place for a platform")
    xy = np.array([(x, y) for x, y, _ in candidates], dtype=np.float64)
    room = clearance(xy[:, 0], xy[:, 1], geometry.obstacles, geometry.circles)
    ok = (room >= radius + MARGIN / 2) & geometry.allowed(xy[:, 0], xy[:, 1])
    chosen: list[Pose] = []
    taken = np.zeros((0, 2))
    for k in np.flatnonzero(ok).tolist():
        if len(taken) and float(np.hypot(*(taken - xy[k]).T).min()) < pitch:
            continue
        chosen.append(candidates[k])
        taken = np.vstack([taken, xy[k]])
        if len(chosen) == count:
            return chosen
    raise FleetError(f"the map has free places for {len(chosen)} platforms, not {count}")


def _grid(geometry: MapGeometry, pitch: float) -> list[Pose]:
    x0, y0, x1, y1 = geometry.bounds()
    xs = np.arange(x0 + pitch / 2, x1, pitch)
    ys = np.arange(y0 + pitch / 2, y1, pitch)
    return [(float(x), float(y), 0.0) for y in ys for x in xs]
