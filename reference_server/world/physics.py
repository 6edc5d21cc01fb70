"""The physical world in pymunk: the map's static shapes, obstacles, and the platform's body that cannot pass them.

Rules:
- ``Physics`` owns one ``pymunk.Space``: static segments for walls and auxiliary lines, static circles for
  pillars and obstacles (the CMD_MOUSE_MOVE obstacle among them), and one kinematic body carrying the
  platform's footprint (a box from the Geometry parameters, erratum E-MOT-002).
- ``move(pose, v, w, dt)`` integrates the differential drive exactly (an arc) and asks pymunk whether the
  footprint overlaps anything there. If it does, the platform advances only the free fraction of the step
  (bisection on the arc) and reports contact: driving into a wall is a collision, never a tunnel (a checked
  step is at most ``MAX_STEP``, far less than the footprint; a longer one is split). A pose that already
  overlaps (an obstacle dropped onto the platform, a kidnap) may move only where the overlap does not grow.
- pymunk does the contact tests and holds the spatial index; the poses are ours (exact arc integration).
- In a fleet (``neighbours``, reference_server/world/neighbours.py) the other platforms' bodies count as well:
  ``overlap`` is the deeper of the map's and theirs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import pymunk

from pltf.reference_server.world.geometry import F64

_BISECT = 8  # 1/256 of a step: well under a millimetre
MAX_STEP = 50.0  # mm a single checked step may drive (a control period at MaxTransVel 1500 mm/s: 30 mm)
MAX_TURN = 0.1  # rad a single checked step may turn
WIDTH_OVER_TRACK = 110.0  # mm: body width = DistWheels + this (E-PAR-013: 430 mm track, 540 mm body)


@dataclass(frozen=True)
class Footprint:
    """The body as a box in the platform frame (origin at the wheel axis' midpoint, x forward)."""

    front: float  # mm, x of the front edge
    rear: float  # mm, x of the rear edge (negative)
    half_width: float

    @classmethod
    def from_params(cls, length: float, center_to_axis: float, track: float) -> Footprint:
        # E-PAR-013: the footprint's centre lies at x = -DistPltfCenterToWheelAxis
        return cls(length / 2.0 - center_to_axis, -length / 2.0 - center_to_axis, (track + WIDTH_OVER_TRACK) / 2.0)

    @property
    def corners(self) -> list[tuple[float, float]]:
        f, r, h = self.front, self.rear, self.half_width
        return [(f, -h), (f, h), (r, h), (r, -h)]

    @cached_property
    def radius(self) -> float:
        """The circumscribed radius about the wheel axis: what a turn on the spot sweeps."""
        return max(math.hypot(x, y) for x, y in self.corners)


def arc(x: float, y: float, a: float, v: float, w: float, dt: float) -> tuple[float, float, float]:
    """The unicycle's pose after ``dt`` at constant v, w (exact)."""
    da = w * dt
    if abs(da) < 1e-9:
        return x + v * dt * math.cos(a), y + v * dt * math.sin(a), a + da
    r = v / w
    return x + r * (math.sin(a + da) - math.sin(a)), y - r * (math.cos(a + da) - math.cos(a)), a + da


class Physics:
    def __init__(self, footprint: Footprint) -> None:
        self.space = pymunk.Space()
        self.body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        self.space.add(self.body)
        self.shape: pymunk.Poly | None = None
        self._static: list[pymunk.Shape] = []
        self._obstacles: dict[object, pymunk.Shape] = {}
        self._known: tuple[float, float, float] | None = None  # the last move's end pose, if free
        self.neighbours: Any = None  # the other bodies of a fleet (world.neighbours.Neighbours), or None
        self.footprint = footprint
        self.set_footprint(footprint)

    # ---- building
    def set_footprint(self, footprint: Footprint) -> None:
        if self.shape is not None:
            self.space.remove(self.shape)
        self._known = None
        self.footprint = footprint
        self.shape = pymunk.Poly(self.body, footprint.corners)
        self.space.add(self.shape)

    def set_map(self, segs: F64, circs: F64) -> None:
        """Replace the map's static shapes (walls, auxiliary lines, pillars)."""
        self._known = None
        if self._static:
            self.space.remove(*self._static)
        sb = self.space.static_body
        self._static = [pymunk.Segment(sb, (s[0], s[1]), (s[2], s[3]), 0.0) for s in segs]
        self._static += [pymunk.Circle(sb, float(c[2]), (float(c[0]), float(c[1]))) for c in circs]
        if self._static:
            self.space.add(*self._static)

    def set_obstacle(self, key: object, circle: tuple[float, float, float] | None) -> None:
        """Place, move (same key) or remove (None) a round obstacle."""
        self._known = None
        old = self._obstacles.pop(key, None)
        if old is not None:
            self.space.remove(old)
        if circle is not None:
            x, y, r = circle
            shape = pymunk.Circle(self.space.static_body, r, (x, y))
            self._obstacles[key] = shape
            self.space.add(shape)

    # ---- queries
    def overlap(self, x: float, y: float, a: float) -> float:
        """How deep the footprint at (x, y, a) overlaps anything (0: free)."""
        self.body.position = (x, y)
        self.body.angle = a
        self.space.reindex_shapes_for_body(self.body)
        assert self.shape is not None
        depth = 0.0
        for info in self.space.shape_query(self.shape):
            for p in info.contact_point_set.points:
                depth = max(depth, abs(p.distance), 1e-6)
        if self.neighbours is not None:
            depth = max(depth, self.neighbours.depth(x, y, a))
        return depth

    def move(self, x: float, y: float, a: float, v: float, w: float, dt: float) -> tuple[float, float, float, bool]:
        """The pose after driving (v, w) for ``dt`` as far as the world lets it, and whether it hit something.

        A step longer than ``MAX_STEP`` mm or ``MAX_TURN`` rad (a control loop that fell behind hands over a long
        ``dt``) is driven in equal parts, each checked, so a long step cannot pass through a wall either."""
        parts = math.ceil(max(abs(v * dt) / MAX_STEP, abs(w * dt) / MAX_TURN, 1.0))
        if parts > 1:
            hit = False
            for _ in range(parts):
                x, y, a, hit = self._move(x, y, a, v, w, dt / parts)
                if hit:
                    break
            return x, y, a, hit
        return self._move(x, y, a, v, w, dt)

    def _move(self, x: float, y: float, a: float, v: float, w: float, dt: float) -> tuple[float, float, float, bool]:
        target = arc(x, y, a, v, w, dt)
        known = self._known
        # the pose the last move ended at, free, nothing changed since: no second query (one per period)
        start_depth = 0.0 if known is not None and known == (x, y, a) else self.overlap(x, y, a)
        depth = self.overlap(*target)
        self._known = None
        if depth <= start_depth + 1e-6 and (depth == 0.0 or start_depth > 0.0):
            if depth == 0.0:  # the caller keeps the angle in [-pi, pi): so is the key (World.move)
                self._known = (target[0], target[1], (target[2] + math.pi) % (2 * math.pi) - math.pi)
            return (*target, depth > 0.0)
        lo, hi = 0.0, 1.0  # lo: a free (or no deeper) fraction of the step
        for _ in range(_BISECT):
            mid = 0.5 * (lo + hi)
            if self.overlap(*arc(x, y, a, v, w, dt * mid)) <= start_depth + 1e-6:
                lo = mid
            else:
                hi = mid
        return (*arc(x, y, a, v, w, dt * lo), True)
