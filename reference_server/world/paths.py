"""Geometric paths for the interpolator: legs that drive along a sampled curve or turn on the spot.

Rules (erratum E-MOT-007):
- A path is a list of legs. ``Drive`` is a curve sampled every ``DS`` mm (x, y, tangent angle, arc length,
  curvature), always driven forwards; ``Turn`` rotates on the spot from one angle to another.
- A polyline (a planned path, a MOVE_PATH, a roadmap route) gets a circular fillet at each vertex whose cut
  into the corner is at most ``CUT`` mm (so it never leaves the planner's margin), shortened to half the
  adjacent segments; a vertex whose fillet would be tighter than ``MIN_RADIUS`` is a turn on the spot.
- The direct path of MOVE_ABS/REL without planning is a cubic Bezier curve (guide 5.9 StartTurnEnabled) from
  the pose along its heading to the target; with StartTurnEnabled (or a target behind the platform) it turns
  towards the target first and drives straight.
- A path holds at most ``MAX_SAMPLES`` samples (erratum E-MOT-014): one longer than ``DS * MAX_SAMPLES`` (1 km)
  is sampled more coarsely, evenly along its length, so that a target at the INT limits (2147 km away) costs
  milliseconds, not minutes and gigabytes.
- The end: with EndTurnEnabled a turn on the spot to the target angle; without it the last piece is a Bezier
  that arrives in the target direction (guide 5.9 "Otherwise the platform will drive a curve"), if the caller
  finds it free, else the turn.
"""

from __future__ import annotations

import bisect
import itertools
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from pltf.reference_server.world.geometry import F64

DS = 20.0  # mm between samples
MAX_SAMPLES = 50_000  # per path (E-MOT-014): beyond DS * MAX_SAMPLES the samples spread out
SMOOTH = 7  # samples over which the curvature is averaged
CUT = 30.0  # mm: how far a fillet may cut into a corner
MIN_RADIUS = 120.0  # mm
STRAIGHT = math.radians(1.0)  # bends below this are ignored
TURN_FIRST = math.radians(10.0)  # heading error above which a path starts with a turn on the spot
CURVE_MAX = math.radians(90.0)  # the largest change of direction an end curve makes (EndTurnEnabled false)

Point = tuple[float, float]


def wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True)
class Drive:
    x: F64
    y: F64
    theta: F64
    s: F64  # arc length from the leg's start
    kappa: F64  # curvature 1/mm (left positive)

    @property
    def length(self) -> float:
        return float(self.s[-1])

    @cached_property
    def _lists(self) -> tuple[list[float], list[float], list[float], list[float], list[float]]:
        """The samples as Python lists: ``at`` runs twice per control period, numpy scalars would cost more."""
        return self.s.tolist(), self.x.tolist(), self.y.tolist(), self.theta.tolist(), self.kappa.tolist()

    def at(self, s: float) -> tuple[float, float, float, float]:
        """x, y, theta, kappa at arc length ``s`` (linear between samples)."""
        ss, xs, ys, th, ka = self._lists
        s = min(max(s, 0.0), ss[-1])
        i = bisect.bisect_right(ss, s) - 1
        i = min(max(i, 0), len(ss) - 2)
        seg = ss[i + 1] - ss[i]
        f = 0.0 if seg <= 0 else (s - ss[i]) / seg
        t = th[i] + f * wrap(th[i + 1] - th[i])
        return xs[i] + f * (xs[i + 1] - xs[i]), ys[i] + f * (ys[i + 1] - ys[i]), wrap(t), ka[i]


@dataclass(frozen=True)
class Turn:
    x: float
    y: float
    start: float
    end: float  # start + the signed rotation (may exceed pi in neither direction: the short way)


Leg = Drive | Turn


def _sampled(xs: F64, ys: F64) -> Drive | None:
    d = np.hypot(np.diff(xs), np.diff(ys))
    keep = np.concatenate([[True], d > 1e-6])
    xs, ys = xs[keep], ys[keep]
    if len(xs) < 2:
        return None
    d = np.hypot(np.diff(xs), np.diff(ys))
    s = np.concatenate([[0.0], np.cumsum(d)])
    th = np.arctan2(np.diff(ys), np.diff(xs))
    th = np.concatenate([th, th[-1:]])
    dth = np.diff(np.unwrap(th))
    kappa = np.concatenate([dth / np.maximum(d, 1e-9), [0.0]])
    # the curvature feeds the reference's rotation: averaged over SMOOTH samples, so the rotation changes no
    # faster than a platform can follow at the speed a fillet allows (a jump would need infinite acceleration)
    if len(kappa) >= SMOOTH:
        kappa = np.convolve(kappa, np.full(SMOOTH, 1.0 / SMOOTH), mode="same")
    return Drive(xs, ys, th, s, kappa)


def line(a: Point, b: Point) -> Drive | None:
    n = max(2, min(MAX_SAMPLES, math.ceil(math.dist(a, b) / DS)) + 1)
    return _sampled(np.linspace(a[0], b[0], n), np.linspace(a[1], b[1], n))


def bezier(p0: Point, h0: float, p3: Point, h3: float) -> Drive | None:
    """A cubic from p0 leaving in direction h0 to p3 arriving in direction h3 (handles of a third of the chord)."""
    d = math.dist(p0, p3) / 3.0
    p1 = (p0[0] + d * math.cos(h0), p0[1] + d * math.sin(h0))
    p2 = (p3[0] - d * math.cos(h3), p3[1] - d * math.sin(h3))
    n = max(8, min(MAX_SAMPLES, math.ceil(3.0 * d / DS) * 2 + 1))
    t = np.linspace(0.0, 1.0, n)[:, None]
    pts = (
        (1 - t) ** 3 * np.array(p0)
        + 3 * (1 - t) ** 2 * t * np.array(p1)
        + 3 * (1 - t) * t**2 * np.array(p2)
        + t**3 * np.array(p3)
    )
    return _sampled(pts[:, 0], pts[:, 1])


def _turn(x: float, y: float, a: float, b: float, tol: float) -> list[Leg]:
    delta = wrap(b - a)
    return [Turn(x, y, a, a + delta)] if abs(delta) > tol else []


def polyline(points: list[Point], heading: float, tol_angle: float) -> list[Leg]:
    """Legs along ``points`` (the first is the platform's position) with fillets or turns at the vertices."""
    pts = [points[0]]
    for p in points[1:]:
        if math.dist(p, pts[-1]) > 1.0:
            pts.append(p)
    if len(pts) < 2:
        return []
    spacing = max(DS, sum(math.dist(a, b) for a, b in itertools.pairwise(pts)) / MAX_SAMPLES)
    legs: list[Leg] = []
    first = math.atan2(pts[1][1] - pts[0][1], pts[1][0] - pts[0][0])
    legs += _turn(*pts[0], heading, first, max(tol_angle, TURN_FIRST))
    xs: list[F64] = [np.array([pts[0][0]])]
    ys: list[F64] = [np.array([pts[0][1]])]

    def flush() -> None:
        drive = _sampled(np.concatenate(xs), np.concatenate(ys))
        if drive is not None:
            legs.append(drive)

    for i in range(1, len(pts) - 1):
        a, b, c = pts[i - 1], pts[i], pts[i + 1]
        h_in = math.atan2(b[1] - a[1], b[0] - a[0])
        h_out = math.atan2(c[1] - b[1], c[0] - b[0])
        phi = wrap(h_out - h_in)
        if abs(phi) < STRAIGHT:
            continue
        half = abs(phi) / 2.0
        radius = CUT / (1.0 / math.cos(half) - 1.0) if half < math.pi / 2 - 1e-6 else 0.0
        tangent = min(0.5 * math.dist(a, b), 0.5 * math.dist(b, c))
        radius = min(radius, tangent / math.tan(half)) if half < math.pi / 2 - 1e-6 else 0.0
        if radius < MIN_RADIUS:
            _append_line(xs, ys, b, spacing)
            flush()
            legs.append(Turn(b[0], b[1], h_in, h_in + phi))
            xs[:], ys[:] = [np.array([b[0]])], [np.array([b[1]])]
            continue
        t = radius * math.tan(half)
        p_in = (b[0] - t * math.cos(h_in), b[1] - t * math.sin(h_in))
        _append_line(xs, ys, p_in, spacing)
        side = 1.0 if phi > 0 else -1.0
        cx, cy = p_in[0] - side * radius * math.sin(h_in), p_in[1] + side * radius * math.cos(h_in)
        ang = h_in - side * math.pi / 2 + phi * _steps(radius * abs(phi), spacing, 2)
        xs.append(cx + radius * np.cos(ang))
        ys.append(cy + radius * np.sin(ang))
    _append_line(xs, ys, pts[-1], spacing)
    flush()
    return legs


def _steps(length: float, spacing: float, least: int) -> F64:
    """The fractions k/n, k = 1..n, of ``length`` sampled every ``spacing`` mm (n >= ``least``)."""
    n = max(least, math.ceil(length / spacing))
    return np.arange(1, n + 1) / n


def _append_line(xs: list[F64], ys: list[F64], p: Point, spacing: float) -> None:
    """Samples from the last one (the end of ``xs``/``ys``' last chunk) straight to ``p``."""
    x0, y0 = float(xs[-1][-1]), float(ys[-1][-1])
    f = _steps(math.hypot(p[0] - x0, p[1] - y0), spacing, 1)
    xs.append(x0 + (p[0] - x0) * f)
    ys.append(y0 + (p[1] - y0) * f)


def direct(pose: tuple[float, float, float], target: Point, start_turn: bool, tol_angle: float) -> list[Leg]:
    """MOVE_ABS/REL without planning: a Bezier from the pose along its heading, or turn first and go straight."""
    x, y, a = pose
    bearing = math.atan2(target[1] - y, target[0] - x)
    if math.dist((x, y), target) < 1.0:
        return []
    if start_turn or abs(wrap(bearing - a)) > math.pi / 2:
        return polyline([(x, y), target], a, tol_angle)
    drive = bezier((x, y), a, target, bearing)
    return [drive] if drive is not None else []


def end_curve(legs: list[Leg], end_angle: float) -> Drive | None:
    """The last Drive leg's final piece replaced by a Bezier arriving at ``end_angle`` (or None: no curve).

    Only for a change of direction up to ``CURVE_MAX``: reversing in a curve would be a loop."""
    last = legs[-1] if legs else None
    if not isinstance(last, Drive) or last.length < 2 * DS or abs(wrap(end_angle - last.theta[-1])) > CURVE_MAX:
        return None
    keep = int(np.searchsorted(last.s, last.length - min(last.length, 3000.0)))
    p0 = (float(last.x[keep]), float(last.y[keep]))
    p3 = (float(last.x[-1]), float(last.y[-1]))
    curve = bezier(p0, float(last.theta[keep]), p3, end_angle)
    if curve is None:
        return None
    head = _sampled(last.x[: keep + 1], last.y[: keep + 1]) if keep > 0 else None
    if head is None:
        return curve
    return _sampled(np.concatenate([head.x, curve.x[1:]]), np.concatenate([head.y, curve.y[1:]]))


NO_POINTS: F64 = np.empty((0, 2))


def sample_points(legs: list[Leg], step: float = 100.0) -> F64:
    """Points (x, y) along the legs every ``step`` mm (the status telegram's interpolated path), at most as many
    as a path of ``DS * MAX_SAMPLES`` mm has (E-MOT-014). An (n, 2) array: the status converts it to INTs in
    one numpy pass, with no Python object per point."""
    parts: list[F64] = []
    total = sum(len(leg.s) for leg in legs if isinstance(leg, Drive))
    thin = math.ceil(total * step / (DS * MAX_SAMPLES))
    for leg in legs:
        if isinstance(leg, Turn):
            if not parts:
                parts.append(np.array([[leg.x, leg.y]], dtype=np.float64))
            continue
        k = max(1, round(step * (len(leg.s) - 1) / max(leg.length, 1e-9)), thin)  # at the leg's own spacing
        parts.append(np.column_stack((leg.x[::k], leg.y[::k])))
        parts.append(np.array([[leg.x[-1], leg.y[-1]]], dtype=np.float64))
    return np.concatenate(parts) if parts else NO_POINTS
