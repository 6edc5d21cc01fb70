"""The fleet's bodies (erratum E-FLEET-002): one pymunk space of every footprint, one array of their outlines.

Rules:
- One kinematic body per platform in ONE ``pymunk.Space`` (its spatial index): ``depth`` moves the asking
  platform's body to a candidate pose and asks the space what its footprint overlaps; a shape filter with the
  platform's own group keeps it from meeting itself. After every move the world puts the body where it ended
  (``place``), so the next platform to move meets it there (the fleet moves them one after the other in a
  fixed order each control period: the same seeds give the same trajectories).
- The outlines (four segments a body) come from one (N, 4, 2) array of the footprints' corners and one (N, 3)
  array of the poses: a sensing platform takes the others within a radius in one numpy pass (``near``).
- ``member(i)`` is the ``world.neighbours.Neighbours`` view of platform i that its world holds.
"""

from __future__ import annotations

import numpy as np
import pymunk

from pltf.reference_server.world.geometry import F64
from pltf.reference_server.world.physics import Footprint

_NO_SEGMENTS = np.zeros((0, 4))
_NEXT = np.array([1, 2, 3, 0])  # each corner's successor: a body's four edges


class Bodies:
    def __init__(self, count: int) -> None:
        self.space = pymunk.Space()
        self.poses = np.zeros((count, 3))
        self.corners = np.zeros((count, 4, 2))
        self.reach = np.zeros(count)  # circumscribed radius of each footprint
        self.live = np.zeros(count, dtype=bool)  # placed and not retired
        self._bodies: list[pymunk.Body] = []
        self._shapes: list[pymunk.Poly | None] = []
        for _ in range(count):
            body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            self.space.add(body)
            self._bodies.append(body)
            self._shapes.append(None)

    def __len__(self) -> int:
        return len(self._bodies)

    def member(self, index: int) -> Member:
        return Member(self, index)

    # ---- one body
    def set_footprint(self, i: int, footprint: Footprint) -> None:
        old = self._shapes[i]
        if old is not None:
            self.space.remove(old)
        shape = pymunk.Poly(self._bodies[i], footprint.corners)
        shape.filter = pymunk.ShapeFilter(group=i + 1)
        self.space.add(shape)
        self._shapes[i] = shape
        self.corners[i] = footprint.corners
        self.reach[i] = footprint.radius

    def place(self, i: int, x: float, y: float, a: float) -> None:
        self.poses[i] = (x, y, a)
        self.live[i] = True
        self._put(i, x, y, a)

    def retire(self, i: int) -> None:
        """Platform i left the world (its server exited): nothing meets or sees it any more."""
        self.live[i] = False
        shape = self._shapes[i]
        if shape is not None:
            self.space.remove(shape)
            self._shapes[i] = None

    def _put(self, i: int, x: float, y: float, a: float) -> None:
        body = self._bodies[i]
        body.position = (x, y)
        body.angle = a
        self.space.reindex_shapes_for_body(body)

    def depth(self, i: int, x: float, y: float, a: float) -> float:
        """How deep platform i's footprint at (x, y, a) overlaps another body; its body stays where it was."""
        shape = self._shapes[i]
        if shape is None:
            return 0.0
        self._put(i, x, y, a)
        depth = 0.0
        for info in self.space.shape_query(shape):
            for p in info.contact_point_set.points:
                depth = max(depth, abs(p.distance), 1e-6)
        self._put(i, *self.poses[i])
        return depth

    def near(self, i: int, x: float, y: float, radius: float) -> F64:
        """(K, 4) outline segments of the live bodies other than i that come within ``radius`` of (x, y)."""
        poses = self.poses
        dist = np.hypot(poses[:, 0] - x, poses[:, 1] - y) - self.reach
        pick = self.live & (dist <= radius)
        pick[i] = False
        idx = np.flatnonzero(pick)
        if len(idx) == 0:
            return _NO_SEGMENTS
        p, corners = poses[idx], self.corners[idx]  # one gather each
        px, py, pa = p[:, 0, None], p[:, 1, None], p[:, 2, None]
        c, s = np.cos(pa), np.sin(pa)
        cx, cy = corners[:, :, 0], corners[:, :, 1]
        wx, wy = px + c * cx - s * cy, py + s * cx + c * cy  # (K, 4) corners in the world
        return np.stack([wx, wy, wx[:, _NEXT], wy[:, _NEXT]], axis=2).reshape(-1, 4)

    def overlapping(self) -> list[tuple[int, int]]:
        """Pairs of live bodies whose footprints overlap now (none, unless something is wrong)."""
        pairs = []
        index = {id(shape): i for i, shape in enumerate(self._shapes)}
        for i, shape in enumerate(self._shapes):
            if shape is None or not self.live[i]:
                continue
            for info in self.space.shape_query(shape):
                j = index.get(id(info.shape), -1)
                if j > i and any(abs(p.distance) > 1e-6 for p in info.contact_point_set.points):
                    pairs.append((i, j))
        return pairs


class Member:
    """Platform ``index``'s view of the bodies (world.neighbours.Neighbours)."""

    __slots__ = ("bodies", "index")

    def __init__(self, bodies: Bodies, index: int) -> None:
        self.bodies, self.index = bodies, index

    def place(self, x: float, y: float, a: float) -> None:
        self.bodies.place(self.index, x, y, a)

    def set_footprint(self, footprint: Footprint) -> None:
        self.bodies.set_footprint(self.index, footprint)

    def depth(self, x: float, y: float, a: float) -> float:
        return self.bodies.depth(self.index, x, y, a)

    def segments_near(self, x: float, y: float, radius: float) -> F64:
        return self.bodies.near(self.index, x, y, radius)
