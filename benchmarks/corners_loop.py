"""The wall corners endpoint by endpoint: the O(n^2) loop that ``geometry._corners`` (vectorised) replaced. It is the
baseline of ``benchmarks/bench_motion.py corners`` and the oracle of tests/reference_server/world/test_corners.py
(here, so that the benchmarks import nothing from tests/)."""

from __future__ import annotations

import math

import numpy as np

from pltf.reference_server.world.geometry import _CORNER_MIN, _JOIN_TOL, F64, point_segment_distance


def corners_by_loop(walls: F64) -> F64:
    """The original implementation, endpoint by endpoint (the oracle)."""
    ends = np.vstack([walls[:, :2], walls[:, 2:]])
    if ends.size == 0:
        return np.zeros((0, 4))
    dirs = walls[:, 2:] - walls[:, :2]
    dirs = np.vstack([dirs, -dirs])
    out: list[tuple[float, float, float, float]] = []
    n = len(walls)
    for i, (px, py) in enumerate(ends):
        d = np.hypot(ends[:, 0] - px, ends[:, 1] - py)
        others = np.nonzero((d < _JOIN_TOL) & (np.arange(2 * n) % n != i % n))[0]
        side = None
        for j in others:
            a, b = dirs[i], dirs[j]
            cos = float(np.dot(a, b) / (np.linalg.norm(a) * np.linalg.norm(b) + 1e-12))
            if abs(cos) < math.cos(_CORNER_MIN):
                side = (0.0, 0.0)
        if side is None and len(others) == 0:
            dist = point_segment_distance(np.array([px]), np.array([py]), walls)[0]
            dist[i % n] = np.inf
            if bool(np.any(dist < _JOIN_TOL)):
                u = dirs[i] / (np.linalg.norm(dirs[i]) + 1e-12)
                side = (float(u[0]), float(u[1]))
        if side is not None and not any(math.hypot(px - x, py - y) < _JOIN_TOL for x, y, *_ in out):
            out.append((float(px), float(py), *side))
    return np.asarray(out, dtype=np.float64).reshape(-1, 4)
