"""Simulated sensors: the S300-like laser scanner, the ultrasonic ring, and what the platform "observes".

Rules (erratum E-MOT-003):
- The laser sits at the front edge of the footprint on the platform's x axis, facing forward: 541 beams from
  -135 to +135 degrees in 0.5 degree steps (like fake_hardware.serial_scanner), range 30 m, Gaussian range
  noise of ``LASER_SIGMA`` mm plus 0.1 % of the range from a seeded numpy generator.
- It sees everything physical: walls, auxiliary lines, pillars, obstacles (the CMD_MOUSE_MOVE obstacle too).
- Observations for the status telegram, all in the platform frame (x forward from the wheel axis' midpoint):
  scan points (INT16, beams without echo left out); lines = the visible part of each straight obstacle hit by
  at least ``LINE_BEAMS`` beams and at least MinLineLenAux long, from the first beam's hit (source) to the
  last one's (target); circles hit by at least ``CIRCLE_BEAMS`` beams, centre and radius; reflectors and
  corners of the map within ``FEATURE_RANGE`` and the field of view with a free line of sight.
- Ultrasonic: 16 sensors at USSensorNNPosX/PosY/Angle (E-PAR-017), each a 25 degree cone sampled by 5 rays,
  range 3 m (fake_hardware.boards.ultrasonic.MAX_RANGE); inf = no echo.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from pltf.reference_server.world.geometry import F64
from pltf.reference_server.world.raycast import I64, Fan, Scene, beam_offsets, cast_fan, cast_rays

LASER_FAN = Fan(541, math.radians(-135.0), math.radians(0.5), 30000.0)
LASER_SIGMA = 10.0  # mm
FEATURE_RANGE = 15000.0  # mm: reflectors and corners further away are not reported
MATCH_RANGE = 10000.0  # mm: longer beams graze walls, a small heading error moves their echo by metres
LINE_BEAMS = 5
CIRCLE_BEAMS = 3
US_SENSORS = 16
US_HALF_CONE = math.radians(12.5)
US_RAYS = 5
US_RANGE = 3000.0
US_SIGMA = 10.0
US_RAY_OFFSETS = np.linspace(-US_HALF_CONE, US_HALF_CONE, US_RAYS)  # the rays of one cone
_INT16 = 32767

Params = Callable[[str], Any]


@dataclass(frozen=True)
class Scan:
    """One laser scan: the laser's world pose, noisy ranges (inf: no echo), the hit ids of the scene."""

    x: float
    y: float
    angle: float
    ranges: F64
    hits: I64


@dataclass(frozen=True)
class Observation:
    """The status telegram's observed groups, in the platform frame, mm (ints)."""

    scan: tuple[tuple[int, int], ...] = ()
    reflectors: tuple[tuple[int, int], ...] = ()
    lines: tuple[tuple[int, int, int, int], ...] = ()
    circles: tuple[tuple[int, int, int], ...] = ()
    corners: tuple[tuple[int, int], ...] = ()


def laser_pose(x: float, y: float, a: float, mount_x: float) -> tuple[float, float, float]:
    return x + mount_x * math.cos(a), y + mount_x * math.sin(a), a


def scan(pose: tuple[float, float, float], mount_x: float, scene: Scene, noise: np.random.Generator) -> Scan:
    lx, ly, la = laser_pose(*pose, mount_x)
    ranges, hits = cast_fan(lx, ly, la, scene, LASER_FAN)
    finite = np.isfinite(ranges)
    sigma = LASER_SIGMA + 0.001 * np.where(finite, ranges, 0.0)
    noisy = np.where(finite, np.maximum(ranges + noise.standard_normal(len(ranges)) * sigma, 1.0), np.inf)
    return Scan(lx, ly, la, noisy, hits)


def expected_ranges(pose: tuple[float, float, float], mount_x: float, scene: Scene) -> F64:
    """The ranges a scan from ``pose`` would show on ``scene`` (no noise): for the scan matcher."""
    lx, ly, la = laser_pose(*pose, mount_x)
    return cast_fan(lx, ly, la, scene, LASER_FAN, want_hits=False)[0]


def match_score(measured: F64, expected: F64) -> float:
    """Share of the beams with an echo in both, expected within MATCH_RANGE, whose ranges agree (100 mm + 3 %)."""
    both = np.isfinite(measured) & (expected <= MATCH_RANGE)
    n = int(both.sum())
    if n < 20:
        return 0.0
    tol = 100.0 + 0.03 * expected[both]
    return float(np.mean(np.abs(measured[both] - expected[both]) <= tol))


def points_platform(s: Scan, mount_x: float) -> F64:
    """(N, 2) scan points with an echo, in the platform frame."""
    cos_b, sin_b = beam_offsets(LASER_FAN)  # the beams' angles are fixed: their cos and sin computed once
    ok = np.isfinite(s.ranges)
    r = s.ranges[ok]
    return np.column_stack([mount_x + r * cos_b[ok], r * sin_b[ok]])


def _to_platform(px: F64, py: F64, pose: tuple[float, float, float]) -> tuple[F64, F64]:
    x, y, a = pose
    c, s = math.cos(a), math.sin(a)
    dx, dy = px - x, py - y
    return c * dx + s * dy, -s * dx + c * dy


def _visible(pts: F64, s: Scan, scene: Scene, sides: F64 | None = None) -> F64:
    """The points within the field of view and FEATURE_RANGE that a ray from the laser reaches (+- 50 mm);
    ``sides``: per point a direction it must be seen from (the laser on its non-negative side; (0, 0): any)."""
    if len(pts) == 0:
        return pts
    dx, dy = pts[:, 0] - s.x, pts[:, 1] - s.y
    dist = np.hypot(dx, dy)
    bearing = (np.arctan2(dy, dx) - s.angle + math.pi) % (2 * math.pi) - math.pi
    fov = LASER_FAN.start + LASER_FAN.step * (LASER_FAN.count - 1)  # +135 degrees
    cand = (dist <= FEATURE_RANGE) & (np.abs(bearing) <= fov) & (dist > 1.0)
    if sides is not None:
        cand &= -(dx * sides[:, 0] + dy * sides[:, 1]) >= 0.0
    if not cand.any():
        return pts[:0]
    idx = np.flatnonzero(cand)
    n = len(idx)
    ranges, _ = cast_rays(np.full(n, s.x), np.full(n, s.y), np.arctan2(dy[idx], dx[idx]), scene, FEATURE_RANGE + 100)
    seen = ranges >= dist[idx] - 50.0
    return pts[idx[seen]]


def _ints(rows: Any) -> tuple[Any, ...]:
    return tuple(tuple(round(float(v)) for v in row) for row in rows)


def observe(
    s: Scan,
    pose: tuple[float, float, float],
    mount_x: float,
    scene: Scene,
    reflectors: F64,
    corners: F64,
    min_line: float,
) -> Observation:
    """The status telegram's observation groups for scan ``s`` taken at the true ``pose``."""
    pts = np.clip(np.rint(points_platform(s, mount_x)), -_INT16, _INT16).astype(np.int64)
    n_seg = len(scene.segs)
    beams = np.flatnonzero((s.hits >= 0) & np.isfinite(s.ranges))
    ids = s.hits[beams]
    order = np.argsort(ids, kind="stable")
    ids, beams = ids[order], beams[order]
    uniq, start, count = np.unique(ids, return_index=True, return_counts=True)
    beta = s.angle + LASER_FAN.start + LASER_FAN.step * beams
    hx, hy = s.x + s.ranges[beams] * np.cos(beta), s.y + s.ranges[beams] * np.sin(beta)
    lines = []
    circs = []
    for uid, st, cnt in zip(uniq.tolist(), start.tolist(), count.tolist(), strict=True):
        if uid < n_seg and cnt >= LINE_BEAMS:
            a, b = st, st + cnt - 1
            if math.hypot(hx[b] - hx[a], hy[b] - hy[a]) >= min_line:
                (tx, sx), (ty, sy) = _to_platform(np.array([hx[b], hx[a]]), np.array([hy[b], hy[a]]), pose)
                lines.append((tx, ty, sx, sy))  # target before source (erratum E-REP-003)
        elif uid >= n_seg and cnt >= CIRCLE_BEAMS:
            cx, cy, r = scene.circs[uid - n_seg]
            px, py = _to_platform(np.array([cx]), np.array([cy]), pose)
            circs.append((px[0], py[0], r))
    refl_pts = 0.5 * (reflectors[:, :2] + reflectors[:, 2:]) if len(reflectors) else np.zeros((0, 2))
    refl = _visible(refl_pts, s, scene)
    corn = _visible(corners[:, :2], s, scene, corners[:, 2:])
    rx, ry = _to_platform(refl[:, 0], refl[:, 1], pose)
    cx, cy = _to_platform(corn[:, 0], corn[:, 1], pose)
    return Observation(
        scan=tuple(map(tuple, pts.tolist())),
        reflectors=_ints(zip(rx, ry, strict=True)),
        lines=_ints(lines),
        circles=_ints(circs),
        corners=_ints(zip(cx, cy, strict=True)),
    )


# ---------------------------------------------------------------------------------------------- ultrasonic


_US_NAMES = tuple(f"USSensor{i:02d}{k}" for i in range(1, US_SENSORS + 1) for k in ("PosX", "PosY", "Angle"))
_US_MOUNTS: dict[tuple[Any, ...], F64] = {}  # parameter values -> mounts (a platform has one set; tests a few)
NEAR_MIN = 64  # scene elements below which the ultrasonic rays test all of them (culling costs more)


def ultrasonic_mounts(params: Params) -> F64:
    """(16, 3): x, y (mm, platform frame) and angle (rad) of each sensor from the USSensorNN parameters (read
    every time; the array built only when a value changed)."""
    key = tuple(map(params, _US_NAMES))
    mounts = _US_MOUNTS.get(key)
    if mounts is None:
        if len(_US_MOUNTS) >= 16:
            _US_MOUNTS.clear()
        v = [float(x) for x in key]
        mounts = np.asarray([(v[k], v[k + 1], math.radians(v[k + 2])) for k in range(0, len(v), 3)], dtype=np.float64)
        mounts.flags.writeable = False  # shared
        _US_MOUNTS[key] = mounts
    return mounts


def ultrasonic(pose: tuple[float, float, float], mounts: F64, scene: Scene, eps: F64) -> list[float]:
    """16 distances (mm, inf: no echo within 3 m): the nearest echo within each sensor's cone, plus ``eps``
    (16 standard normal draws) times US_SIGMA."""
    x, y, a = pose
    c, s = math.cos(a), math.sin(a)
    ox = x + c * mounts[:, 0] - s * mounts[:, 1]
    oy = y + s * mounts[:, 0] + c * mounts[:, 1]
    angles = (a + mounts[:, 2])[:, None] + US_RAY_OFFSETS[None, :]
    near = scene if scene.size < NEAR_MIN else _near(scene, x, y, US_RANGE + 1000.0)  # the same ranges either way
    ranges, _ = cast_rays(np.repeat(ox, US_RAYS), np.repeat(oy, US_RAYS), angles.ravel(), near, US_RANGE)
    best = ranges.reshape(US_SENSORS, US_RAYS).min(axis=1)
    noisy = best + eps * US_SIGMA
    return [float(v) if math.isfinite(v) else math.inf for v in np.maximum(noisy, 1.0)]


def _near(scene: Scene, x: float, y: float, radius: float) -> Scene:
    """The part of the scene whose bounding boxes come within ``radius`` of (x, y)."""
    s = scene.segs
    keep = (
        (np.minimum(s[:, 0], s[:, 2]) <= x + radius)
        & (np.maximum(s[:, 0], s[:, 2]) >= x - radius)
        & (np.minimum(s[:, 1], s[:, 3]) <= y + radius)
        & (np.maximum(s[:, 1], s[:, 3]) >= y - radius)
    )
    c = scene.circs
    keep_c = np.hypot(c[:, 0] - x, c[:, 1] - y) - c[:, 2] <= radius
    return Scene.make(s[keep], c[keep_c])
