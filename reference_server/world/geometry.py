"""The active map as arrays (guide 6.5 Map), and the vectorised distance functions everything else uses.

Rules:
- ``MapGeometry.from_tree`` reads a VALIDATED map tree (spec.documents.validate_document); it never raises on
  a valid map. Units: mm. Segments are rows ``(x0, y0, x1, y1)`` of float64 arrays, circles ``(x, y, r)``.
- What each element is (erratum E-MOT-001): <line>/<linemapped> are walls (physical, seen by the laser, used
  by localization); <auxline>/<auxlinemapped> are physical obstacles the laser sees but localization does not
  use; <circle> is a physical pillar; <reflmark> is a reflective mark on a wall (seen, not physical);
  <workarea> and <prohibit> are planning constraints only; hidden* elements are ignored.
- An area of two points is the axis-aligned rectangle they span (erratum E-MOT-001).
- Corners are the points where two walls meet at 30..150 degrees (seen from anywhere), or where a wall ends on
  another one (a T junction, seen from the side of the wall that ends there).
- No I/O, no clock: pure functions of the tree and of arrays.
- ``segments_clear`` runs in C (``_geometry.c``, built with the package) when it is importable: the same tests
  and floating-point steps, stopping each query at its first obstacle (a map's visibility graph asks millions of
  pairs). ``segments_clear_numpy`` stays: the fallback, and the oracle the tests hold the C loops to.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt
from lxml import etree
from scipy.spatial import cKDTree  # type: ignore[import-untyped]

try:
    from pltf.reference_server.world import _geometry

    HAVE_C = True
except ImportError:  # not built (a source checkout without a compiler): numpy only
    HAVE_C = False

F64 = npt.NDArray[np.float64]
BOOL = npt.NDArray[np.bool_]

_WALLS = ("line", "linemapped")
_AUX = ("auxline", "auxlinemapped")
_CORNER_MIN = math.radians(30.0)
_JOIN_TOL = 1.0  # mm: endpoints closer than this meet


def segments(rows: list[tuple[float, float, float, float]] | F64) -> F64:
    """An (N, 4) float64 array of segments, also for N = 0."""
    return np.asarray(rows, dtype=np.float64).reshape(-1, 4)


def circles(rows: list[tuple[float, float, float]] | F64) -> F64:
    return np.asarray(rows, dtype=np.float64).reshape(-1, 3)


def polygon_edges(polygon: F64) -> F64:
    """The closed polygon's edges as segments."""
    return segments(np.hstack([polygon, np.roll(polygon, -1, axis=0)]))


@dataclass(frozen=True)
class MapGeometry:
    walls: F64 = field(default_factory=lambda: segments([]))
    aux: F64 = field(default_factory=lambda: segments([]))
    circles: F64 = field(default_factory=lambda: circles([]))
    reflectors: F64 = field(default_factory=lambda: segments([]))  # a point reflector has equal endpoints
    workareas: tuple[F64, ...] = ()
    prohibited: tuple[F64, ...] = ()

    @classmethod
    def from_tree(cls, tree: Any) -> MapGeometry:
        root = tree.getroot() if hasattr(tree, "getroot") else tree

        def pts(el: Any, tag: str = "point") -> F64:
            """(N, 2): the x and y of ``el``'s ``tag`` children, by XPath in C (a 300,000-point workarea)."""
            xs, ys = (_ATTR[tag, a](el) for a in "xy")
            if len(xs) != len(ys):
                raise ValueError(f"every <{tag}> needs both x and y (map.xsd)")
            out = np.empty((len(xs), 2), dtype=np.float64)
            out[:, 0] = np.fromiter(map(float, xs), np.float64, len(xs))
            out[:, 1] = np.fromiter(map(float, ys), np.float64, len(ys))
            return out

        def seg_rows(tags: tuple[str, ...]) -> F64:
            # twoPoints elements (map.xsd): every x and y of a tag in one XPath each, in C - an absurd map of
            # 100,000 lines costs the server no Python loop per point
            parts = [_two_points(root, tag) for tag in tags]
            return segments(np.vstack(parts))

        refl = []
        for el in root.iterfind("layer/reflmark"):
            p = pts(el)
            refl.append((*p[0], *p[-1]))
        circ = [(*pts(el, "center")[0], float(el.find("radius").get("r"))) for el in root.iterfind("layer/circle")]
        return cls(
            walls=seg_rows(_WALLS),
            aux=seg_rows(_AUX),
            circles=circles(circ),
            reflectors=segments(refl),
            workareas=tuple(_area(pts(el)) for el in root.iterfind("layer/workarea")),
            prohibited=tuple(_area(pts(el)) for el in root.iterfind("layer/prohibit")),
        )

    @property
    def obstacles(self) -> F64:
        """Every physical segment: walls, then auxiliary lines."""
        return np.vstack([self.walls, self.aux])

    def constraint_edges(self) -> F64:
        """Edges of the workareas and prohibited areas: walls for the planner only."""
        edges = [polygon_edges(p) for p in (*self.workareas, *self.prohibited)]
        return np.vstack(edges) if edges else segments([])

    def allowed(self, x: F64, y: F64) -> BOOL:
        """Points inside some workarea (or anywhere when there is none) and outside every prohibited area."""
        ok = np.ones(np.shape(x), dtype=bool)
        if self.workareas:
            ok &= np.any([inside_polygon(x, y, w) for w in self.workareas], axis=0)
        for p in self.prohibited:
            ok &= ~inside_polygon(x, y, p)
        return ok

    def corners(self) -> F64:
        """Wall corners, (M, 4): x, y and the side they show to (see ``_corners``)."""
        return _corners(self.walls)

    def bounds(self) -> tuple[float, float, float, float]:
        parts = [self.walls[:, 0::2], self.walls[:, 1::2], self.aux[:, 0::2], self.aux[:, 1::2]]
        xs = np.concatenate([parts[0].ravel(), parts[2].ravel(), self.circles[:, 0]])
        ys = np.concatenate([parts[1].ravel(), parts[3].ravel(), self.circles[:, 1]])
        if xs.size == 0:
            return (0.0, 0.0, 0.0, 0.0)
        return float(xs.min()), float(ys.min()), float(xs.max()), float(ys.max())


_ATTR = {(tag, a): etree.XPath(f"{tag}/@{a}", smart_strings=False) for tag in ("point", "center") for a in "xy"}
_QUERIES = (("", "/point/@x"), ("", "/point/@y"), ("count", ""))
_COORDS = {
    tag: tuple(etree.XPath(f"{q}(layer/{tag}{a})", smart_strings=False) for q, a in _QUERIES)
    for tag in (*_WALLS, *_AUX)
}


def _two_points(root: Any, tag: str) -> F64:
    """(N, 4) x0, y0, x1, y1 of the ``tag`` elements (two points each, as the schema has them)."""
    get_x, get_y, get_count = _COORDS[tag]
    xs, ys, count = get_x(root), get_y(root), int(get_count(root))
    if len(xs) != 2 * count or len(ys) != 2 * count:
        raise ValueError(f"every <{tag}> needs exactly two <point x= y=> (map.xsd twoPoints)")
    out = np.empty((count, 4), dtype=np.float64)
    out[:, 0::2] = np.asarray([float(v) for v in xs], dtype=np.float64).reshape(count, 2)
    out[:, 1::2] = np.asarray([float(v) for v in ys], dtype=np.float64).reshape(count, 2)
    return out


def _area(points: F64) -> F64:
    """A polygon's (N, 2) corners; two points are the opposite corners of an axis-parallel rectangle."""
    if len(points) == 2:
        (x0, y0), (x1, y1) = points
        return np.array([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], dtype=np.float64)
    return np.asarray(points, dtype=np.float64)


def _corners(walls: F64) -> F64:
    """(M, 4): x, y and the side it shows to: (0, 0) for two walls meeting at their ends (seen from anywhere),
    the stem's direction for a wall ending on another one (a T, seen from the stem's side only).

    Vectorised (a k-d tree finds the endpoints that meet, a grid the walls an endpoint may end on): a map of
    3000 walls takes milliseconds. Endpoint ``i`` belongs to wall ``i % n``; corners come in endpoint order, one
    within _JOIN_TOL of a corner already listed left out."""
    n = len(walls)
    if n == 0:
        return np.zeros((0, 4))
    ends = np.vstack([walls[:, :2], walls[:, 2:]])
    dirs = walls[:, 2:] - walls[:, :2]
    dirs = np.vstack([dirs, -dirs])  # pointing away from the endpoint into the wall
    norm = np.sqrt(dirs[:, 0] * dirs[:, 0] + dirs[:, 1] * dirs[:, 1])
    owner = np.arange(2 * n) % n
    # endpoints of two different walls that meet; at 30..150 degrees they make a corner
    i, j = _close_pairs(ends)
    other = owner[i] != owner[j]
    i, j = i[other], j[other]
    has_other = np.zeros(2 * n, dtype=bool)
    has_other[i] = has_other[j] = True
    cos = (dirs[i, 0] * dirs[j, 0] + dirs[i, 1] * dirs[j, 1]) / (norm[i] * norm[j] + 1e-12)
    angled = np.abs(cos) < math.cos(_CORNER_MIN)
    corner = np.zeros(2 * n, dtype=bool)
    corner[i[angled]] = corner[j[angled]] = True
    # an endpoint meeting no other one but lying on the inside of another wall: a T junction
    free = np.flatnonzero(~has_other)
    tee = free[_on_other_wall(ends[free], owner[free], walls)]
    side = np.zeros((2 * n, 2))
    side[tee] = dirs[tee] / (norm[tee] + 1e-12)[:, None]
    corner[tee] = True
    found = np.flatnonzero(corner)
    out = np.column_stack([ends[found], side[found]])[_first_of_each_cluster(ends[found])]
    return np.asarray(out, dtype=np.float64).reshape(-1, 4)


def _close_pairs(points: F64) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Index pairs (i < j) of points closer than _JOIN_TOL."""
    if len(points) < 2:
        none = np.zeros(0, dtype=np.int64)
        return none, none
    pairs = np.asarray(cKDTree(points).query_pairs(_JOIN_TOL, output_type="ndarray"), dtype=np.int64).reshape(-1, 2)
    i, j = pairs.min(axis=1), pairs.max(axis=1)
    close = np.hypot(points[j, 0] - points[i, 0], points[j, 1] - points[i, 1]) < _JOIN_TOL
    return i[close], j[close]


_GRID = 2000.0  # mm: cell size of the grid of wall boxes in ``_on_other_wall`` (at the least)
_MAX_CELLS = 1 << 18  # wall-box cells at the most: a map of huge walls gets coarser cells, not terabytes
_ROW = 1 << 32  # cell key = column * _ROW + row (rows offset to stay positive)


def _on_other_wall(points: F64, own: npt.NDArray[np.int64], walls: F64) -> BOOL:
    """For each point: does it lie within _JOIN_TOL of a wall other than its ``own``? Only the walls whose box
    (grown by _JOIN_TOL) covers the point's grid cell are measured."""
    out = np.zeros(len(points), dtype=bool)
    if len(points) == 0:
        return out
    grid = _GRID
    while True:  # coarser cells until the boxes cover few enough (each cell's candidates are measured exactly)
        lo = np.floor((np.minimum(walls[:, :2], walls[:, 2:]) - _JOIN_TOL) / grid).astype(np.int64)
        hi = np.floor((np.maximum(walls[:, :2], walls[:, 2:]) + _JOIN_TOL) / grid).astype(np.int64)
        span = hi - lo + 1
        count = span[:, 0] * span[:, 1]
        if int(count.sum()) <= max(_MAX_CELLS, 4 * len(walls)):
            break
        grid *= 2.0
    wall = np.repeat(np.arange(len(walls)), count)
    k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)  # the cell within the box
    key = (lo[wall, 0] + k % span[wall, 0]) * _ROW + (lo[wall, 1] + k // span[wall, 0] + _ROW // 2)
    order = np.argsort(key, kind="stable")
    key, wall = key[order], wall[order]
    cell = np.floor(points / grid).astype(np.int64)
    pkey = cell[:, 0] * _ROW + cell[:, 1] + _ROW // 2
    first, last = np.searchsorted(key, pkey, "left"), np.searchsorted(key, pkey, "right")
    m = last - first
    point = np.repeat(np.arange(len(points)), m)
    cand = wall[np.arange(int(m.sum())) - np.repeat(np.cumsum(m) - m, m) + np.repeat(first, m)]
    other = cand != own[point]
    point, cand = point[other], cand[other]
    s = walls[cand]
    ex, ey = s[:, 2] - s[:, 0], s[:, 3] - s[:, 1]
    ll = ex * ex + ey * ey
    wx, wy = points[point, 0] - s[:, 0], points[point, 1] - s[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(np.where(ll > 0, (wx * ex + wy * ey) / ll, 0.0), 0.0, 1.0)
    dx, dy = wx - t * ex, wy - t * ey
    out[point[np.sqrt(dx * dx + dy * dy) < _JOIN_TOL]] = True
    return out


def _first_of_each_cluster(points: F64) -> BOOL:
    """Keep a point unless an earlier KEPT point lies within _JOIN_TOL (the order of a list built one by one)."""
    keep = np.ones(len(points), dtype=bool)
    earlier: dict[int, list[int]] = {}
    for a, b in zip(*(idx.tolist() for idx in _close_pairs(points)), strict=True):
        earlier.setdefault(b, []).append(a)
    for b in sorted(earlier):  # only the points with a near neighbour: two per corner at most
        keep[b] = not any(keep[a] for a in earlier[b])
    return keep


# ---------------------------------------------------------------------------------------------- vector maths


def inside_polygon(x: F64, y: F64, polygon: F64) -> BOOL:
    """Even-odd rule for many points against one polygon."""
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    inside = np.zeros(x.shape, dtype=bool)
    px, py = polygon[:, 0], polygon[:, 1]
    qx, qy = np.roll(px, -1), np.roll(py, -1)
    for x0, y0, x1, y1 in zip(px, py, qx, qy, strict=True):
        crosses = (y0 > y) != (y1 > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            xc = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
        inside ^= crosses & (x < xc)
    return inside


def point_segment_distance(px: F64, py: F64, segs: F64) -> F64:
    """(P, S) distances of P points to S segments."""
    x0, y0, x1, y1 = (segs[:, k][None, :] for k in range(4))
    ex, ey = x1 - x0, y1 - y0
    ll = ex * ex + ey * ey
    wx, wy = px[:, None] - x0, py[:, None] - y0
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(np.where(ll > 0, (wx * ex + wy * ey) / ll, 0.0), 0.0, 1.0)
    dx, dy = wx - t * ex, wy - t * ey
    return np.asarray(np.sqrt(dx * dx + dy * dy))


def clearance(px: F64, py: F64, segs: F64, circ: F64) -> F64:
    """Distance of each point to the nearest segment or circle surface (negative inside a circle, inf: none)."""
    best = np.full(np.shape(px), np.inf)
    if len(segs):
        best = np.minimum(best, point_segment_distance(px, py, segs).min(axis=1))
    if len(circ):
        d = np.hypot(px[:, None] - circ[:, 0], py[:, None] - circ[:, 1]) - circ[:, 2]
        best = np.minimum(best, d.min(axis=1))
    return best


def _point_seg_d2(px: F64, py: F64, x0: F64, y0: F64, ex: F64, ey: F64, ll: F64) -> F64:
    wx, wy = px - x0, py - y0
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.clip(np.where(ll > 0, (wx * ex + wy * ey) / ll, 0.0), 0.0, 1.0)
    dx, dy = wx - t * ex, wy - t * ey
    return np.asarray(dx * dx + dy * dy)


def segments_clear(q: F64, segs: F64, circ: F64, radius: float | F64) -> BOOL:
    """For each query segment (Q, 4): does it keep at least ``radius`` from every segment and circle?

    ``radius`` may be one value or one per query. Segment-segment distance: 0 when they cross, else the least
    of the four endpoint-to-segment distances.
    """
    if not HAVE_C:
        return segments_clear_numpy(q, segs, circ, radius)
    q = segments(q)
    rad = np.ascontiguousarray(np.broadcast_to(np.asarray(radius, dtype=np.float64), (len(q),)))
    ok = np.ones(len(q), dtype=bool)
    f64 = np.float64
    _geometry.segments_clear(
        q, np.ascontiguousarray(segs, f64).reshape(-1, 4), np.ascontiguousarray(circ, f64).reshape(-1, 3), rad, ok
    )
    return ok


def segments_clear_numpy(q: F64, segs: F64, circ: F64, radius: float | F64) -> BOOL:
    """``segments_clear`` in numpy."""
    q = segments(q)
    rad = np.broadcast_to(np.asarray(radius, dtype=np.float64), (len(q),))
    ok = np.ones(len(q), dtype=bool)
    if len(q) == 0:
        return ok
    ax, ay, bx, by = (q[:, k][:, None] for k in range(4))
    r2 = (rad * rad)[:, None]
    if len(segs):
        cx, cy, dx, dy = (segs[:, k][None, :] for k in range(4))
        ux, uy, vx, vy = bx - ax, by - ay, dx - cx, dy - cy
        d2 = np.minimum(
            np.minimum(
                _point_seg_d2(ax, ay, cx, cy, vx, vy, vx * vx + vy * vy),
                _point_seg_d2(bx, by, cx, cy, vx, vy, vx * vx + vy * vy),
            ),
            np.minimum(
                _point_seg_d2(cx, cy, ax, ay, ux, uy, ux * ux + uy * uy),
                _point_seg_d2(dx, dy, ax, ay, ux, uy, ux * ux + uy * uy),
            ),
        )
        o1 = ux * (cy - ay) - uy * (cx - ax)
        o2 = ux * (dy - ay) - uy * (dx - ax)
        o3 = vx * (ay - cy) - vy * (ax - cx)
        o4 = vx * (by - cy) - vy * (bx - cx)
        crossing = (o1 * o2 < 0) & (o3 * o4 < 0)
        ok &= ~np.any(crossing | (d2 < r2), axis=1)
    if len(circ):
        ux, uy = bx - ax, by - ay
        d2 = _point_seg_d2(circ[:, 0][None, :], circ[:, 1][None, :], ax, ay, ux, uy, ux * ux + uy * uy)
        rr = np.maximum(rad[:, None] + circ[:, 2][None, :], 0.0)  # a radius may shrink a circle away entirely
        ok &= ~np.any(d2 < rr * rr, axis=1)
    return ok
