"""Global path planning (guide 4.1 "A global planner finds the shortest path"): a visibility graph.

Rules (erratum E-MOT-006):
- Configuration space: the platform is a disc of radius ``radius`` (the footprint's circumscribed radius about
  the wheel axis plus a margin), so any heading is free wherever the centre is free and a turn on the spot is
  always safe. Obstacles: walls, auxiliary lines, pillars, and the edges of the workareas and prohibited
  areas (the platform keeps its disc inside the workarea and out of prohibited areas).
- Each inflated obstacle is bounded by an octagon circumscribing its disc (one face normal along a segment),
  a convex polygon of 8 vertices; vertices slightly pushed out so they keep more than ``radius``. The graph's
  nodes are the vertices that are free and allowed; its edges the pairs that see each other (segment keeps
  ``radius`` from everything) and are tangent at both ends (the reduced visibility graph: only such edges
  can be on a shortest path). Built once per map and per radius ("lookup data"): ``Planner.shared`` hands
  every caller with an equal map (same walls, lines, circles, areas) and radius the same planner while one is
  alive, so a fleet whose platforms load one map builds its graph once, not once per platform (a planner is
  never changed after it is built; ``plan`` only reads it).
- ``plan`` adds the start, the goal and the octagons of obstacles seen on the way (circles), drops the static
  edges those obstacles block, and runs Dijkstra (scipy). Start and goal whose disc touches something but
  whose real footprint is free connect with their own clearance instead of ``radius``.
- Results: a list of points from start to goal, or a ``PlannerState`` code (guide 6.4).
"""

from __future__ import annotations

import enum
import hashlib
import math
import weakref
from dataclasses import dataclass

import numpy as np
from scipy.sparse import csr_matrix  # type: ignore[import-untyped]
from scipy.sparse.csgraph import dijkstra  # type: ignore[import-untyped]

from pltf.reference_server.world.geometry import F64, MapGeometry, circles, clearance, segments, segments_clear

_K = 8
_PUSH = 1.002  # vertices a little outside the inflated obstacle
_COS = math.cos(math.pi / _K)


class PlannerState(enum.IntEnum):
    """guide 6.4 CMD_GET_STATUS Planner state."""

    STANDBY = 0
    PLANNING = 1
    NO_PATH = 2
    PATH_FOUND = 3
    COLLISION_START = 4
    COLLISION_TARGET = 5


@dataclass(frozen=True)
class Plan:
    state: PlannerState
    points: tuple[tuple[float, float], ...] = ()


def _octagons(segs: F64, circs: F64, radius: float) -> tuple[F64, F64, F64]:
    """Vertices (V, 2) of the inflated obstacles' octagons and each vertex's polygon neighbours (prev, next)."""
    rv = radius / _COS * _PUSH
    polys = []
    if len(segs):
        ux, uy = segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]
        ln = np.hypot(ux, uy)
        heading = np.where(ln > 0, np.arctan2(uy, ux), 0.0)
        # end B (x1, y1): -67.5 .. 67.5 degrees; end A: 112.5 .. 247.5 degrees (counter-clockwise order)
        offs = np.radians([-67.5, -22.5, 22.5, 67.5, 112.5, 157.5, 202.5, 247.5])
        at_b = np.arange(_K) < 4
        ex = np.where(at_b, segs[:, 2][:, None], segs[:, 0][:, None])
        ey = np.where(at_b, segs[:, 3][:, None], segs[:, 1][:, None])
        ang = heading[:, None] + offs[None, :]
        polys.append(np.stack([ex + rv * np.cos(ang), ey + rv * np.sin(ang)], axis=-1))
    if len(circs):
        rc = (radius + circs[:, 2]) / _COS * _PUSH
        ang = np.radians(22.5 + 45.0 * np.arange(_K))[None, :]
        polys.append(
            np.stack(
                [circs[:, 0][:, None] + rc[:, None] * np.cos(ang), circs[:, 1][:, None] + rc[:, None] * np.sin(ang)],
                axis=-1,
            )
        )
    if not polys:
        empty = np.zeros((0, 2))
        return empty, empty, empty
    p = np.concatenate(polys)  # (P, 8, 2)
    return p.reshape(-1, 2), np.roll(p, 1, axis=1).reshape(-1, 2), np.roll(p, -1, axis=1).reshape(-1, 2)


def _tangent(v: F64, prev: F64, nxt: F64, w: F64) -> np.ndarray:
    """For each pair (row of v with row of w): the line v-w has both polygon neighbours of v on one side."""
    dx, dy = w[..., 0] - v[..., 0], w[..., 1] - v[..., 1]
    s1 = dx * (prev[..., 1] - v[..., 1]) - dy * (prev[..., 0] - v[..., 0])
    s2 = dx * (nxt[..., 1] - v[..., 1]) - dy * (nxt[..., 0] - v[..., 0])
    return np.asarray(s1 * s2 >= -1e-6)


def _inward(v: F64, prev: F64, nxt: F64, w: F64) -> np.ndarray:
    """w lies in the interior angle of the (counter-clockwise) octagon at v: the line v-w enters the octagon.

    The octagon over-approximates the inflated obstacle, so a start or goal may lie inside it yet be free;
    such a line is then no reason to prune (unlike a line that only touches v on its way past)."""
    a = (v[..., 0] - prev[..., 0]) * (w[..., 1] - prev[..., 1]) - (v[..., 1] - prev[..., 1]) * (
        w[..., 0] - prev[..., 0]
    )
    b = (nxt[..., 0] - v[..., 0]) * (w[..., 1] - v[..., 1]) - (nxt[..., 1] - v[..., 1]) * (w[..., 0] - v[..., 0])
    return np.asarray((a > 0) & (b > 0))


def _fingerprint(geometry: MapGeometry, radius: float) -> tuple[bytes, float]:
    """What a planner is built from: the map's physical and area arrays (bytes, with their shapes) and the radius."""
    h = hashlib.blake2b(digest_size=20)
    for a in (geometry.walls, geometry.aux, geometry.circles, geometry.reflectors):
        h.update(repr(a.shape).encode())
        h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    for group in (geometry.workareas, geometry.prohibited):
        h.update(b"|%d" % len(group))
        for a in group:
            h.update(repr(a.shape).encode())
            h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    return h.digest(), float(radius)


_SHARED: weakref.WeakValueDictionary[tuple[bytes, float], Planner] = weakref.WeakValueDictionary()


class Planner:
    @classmethod
    def shared(cls, geometry: MapGeometry, radius: float) -> Planner:
        """A planner for ``geometry`` and ``radius``: the one already built for an equal map and radius while
        anything holds it, else a new one (see the module rules)."""
        key = _fingerprint(geometry, radius)
        planner = _SHARED.get(key)
        if planner is None:
            planner = cls(geometry, radius)
            _SHARED[key] = planner
        return planner

    def __init__(self, geometry: MapGeometry, radius: float) -> None:
        self.geometry = geometry
        self.radius = radius
        self.walls = np.vstack([geometry.obstacles, geometry.constraint_edges()])
        self.circs = geometry.circles
        nodes, prev, nxt = _octagons(self.walls, self.circs, radius)
        keep = self._free(nodes, self.walls, self.circs)
        self.nodes, self.prev, self.next = nodes[keep], prev[keep], nxt[keep]
        self.edges = self._visibility()

    def _free(self, pts: F64, walls: F64, circs: F64) -> np.ndarray:
        if len(pts) == 0:
            return np.zeros(0, dtype=bool)
        ok = np.asarray(self.geometry.allowed(pts[:, 0], pts[:, 1]))
        return ok & (clearance(pts[:, 0], pts[:, 1], walls, circs) >= self.radius)

    def _visibility(self) -> F64:
        """Rows (i, j, length) of the static graph's edges, i < j."""
        n = len(self.nodes)
        rows = []
        for i in range(n - 1):
            j = np.arange(i + 1, n)
            vi = np.broadcast_to(self.nodes[i], (len(j), 2))
            ok = _tangent(vi, self.prev[i], self.next[i], self.nodes[j])
            ok &= _tangent(self.nodes[j], self.prev[j], self.next[j], vi)
            j = j[ok]
            if len(j) == 0:
                continue
            q = np.column_stack([np.broadcast_to(self.nodes[i], (len(j), 2)), self.nodes[j]])
            j = j[segments_clear(q, self.walls, self.circs, self.radius)]
            d = np.hypot(self.nodes[j, 0] - self.nodes[i, 0], self.nodes[j, 1] - self.nodes[i, 1])
            rows.append(np.column_stack([np.full(len(j), i), j, d]))
        return np.vstack(rows) if rows else np.zeros((0, 3))

    # ---- queries
    def plan(
        self,
        start: tuple[float, float],
        goal: tuple[float, float],
        start_clear: float | None = None,
        goal_clear: float | None = None,
        obstacles: F64 | None = None,
    ) -> Plan:
        """Shortest path; ``*_clear``: the radius start/goal may connect with (their real clearance, <= radius)."""
        obs = circles([]) if obstacles is None else circles(obstacles)
        circs = np.vstack([self.circs, obs])
        r_s = self.radius if start_clear is None else min(self.radius, start_clear)
        r_g = self.radius if goal_clear is None else min(self.radius, goal_clear)
        sg = np.array([start, goal], dtype=np.float64)
        allowed = self.geometry.allowed(sg[:, 0], sg[:, 1])
        if not allowed[0]:
            return Plan(PlannerState.COLLISION_START)
        if not allowed[1]:
            return Plan(PlannerState.COLLISION_TARGET)
        if segments_clear(np.array([[*start, *goal]]), self.walls, circs, min(r_s, r_g))[0]:
            return Plan(PlannerState.PATH_FOUND, (start, goal))
        nodes, prev, nxt, edges = self.nodes, self.prev, self.next, self.edges
        if len(obs):
            nodes, prev, nxt, edges = self._with_obstacles(obs, circs)
        n = len(nodes)
        rows = [edges]
        inside = self.radius / _COS * _PUSH  # a point with less clearance may lie inside an octagon
        for idx, (p, r, c) in enumerate(((start, r_s, start_clear), (goal, r_g, goal_clear))):
            if n == 0:
                break
            pt = np.broadcast_to(np.asarray(p, dtype=np.float64), (n, 2))
            ok = _tangent(nodes, prev, nxt, pt)
            if c is not None and c < inside:
                ok |= _inward(nodes, prev, nxt, pt)
            j = np.flatnonzero(ok)
            q = np.column_stack([pt[j], nodes[j]])
            j = j[segments_clear(q, self.walls, circs, r)]
            d = np.hypot(nodes[j, 0] - p[0], nodes[j, 1] - p[1])
            rows.append(np.column_stack([np.full(len(j), n + idx), j, d]))
        e = np.vstack(rows)
        graph = csr_matrix((e[:, 2], (e[:, 0].astype(np.int64), e[:, 1].astype(np.int64))), shape=(n + 2, n + 2))
        dist, pred = dijkstra(graph, directed=False, indices=n, return_predecessors=True)
        if not math.isfinite(float(dist[n + 1])):
            return Plan(PlannerState.NO_PATH)
        path = [goal]
        k = int(pred[n + 1])
        while k != n:
            path.append((float(nodes[k, 0]), float(nodes[k, 1])))
            k = int(pred[k])
        path.append(start)
        return Plan(PlannerState.PATH_FOUND, tuple(reversed(path)))

    def _with_obstacles(self, obs: F64, circs: F64) -> tuple[F64, F64, F64, F64]:
        """The graph with the obstacles' octagons added and the static edges they block removed."""
        e = self.edges
        if len(e):
            i, j = e[:, 0].astype(np.int64), e[:, 1].astype(np.int64)
            q = np.column_stack([self.nodes[i], self.nodes[j]])
            e = e[segments_clear(q, segments([]), obs, self.radius)]
        new, prev, nxt = _octagons(segments([]), obs, self.radius)
        keep = self._free(new, self.walls, circs)
        new, prev, nxt = new[keep], prev[keep], nxt[keep]
        n0 = len(self.nodes)
        nodes = np.vstack([self.nodes, new])
        all_prev, all_next = np.vstack([self.prev, prev]), np.vstack([self.next, nxt])
        rows = [e]
        for k in range(len(new)):
            a = n0 + k
            j = np.arange(a)
            va = np.broadcast_to(new[k], (a, 2))
            ok = _tangent(va, prev[k], nxt[k], nodes[:a]) & _tangent(nodes[:a], all_prev[:a], all_next[:a], va)
            j = j[ok]
            q = np.column_stack([np.broadcast_to(new[k], (len(j), 2)), nodes[j]])
            j = j[segments_clear(q, self.walls, circs, self.radius)]
            d = np.hypot(nodes[j, 0] - new[k, 0], nodes[j, 1] - new[k, 1])
            rows.append(np.column_stack([np.full(len(j), a), j, d]))
        return nodes, all_prev, all_next, np.vstack(rows)
