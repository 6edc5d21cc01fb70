"""The vectorised wall corners (geometry._corners) against the plain O(n^2) loop they replaced, on the office floor
and on random maps with shared endpoints, T junctions, collinear joins, diagonals and near-duplicate points."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest

from pltf.reference_server.world.geometry import (
    _CORNER_MIN,
    _JOIN_TOL,
    F64,
    MapGeometry,
    point_segment_distance,
    segments,
)


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


def assert_same_corners(got: F64, want: F64) -> None:
    """The same corners in the same order: positions exactly (they are copied endpoints), the unit side directions
    to 1e-12 - numpy's vectorised hypot/norm may round the last bit differently on another CPU (CI saw 1.1e-16)."""
    assert got.shape == want.shape
    np.testing.assert_array_equal(got[:, :2], want[:, :2])
    np.testing.assert_allclose(got[:, 2:], want[:, 2:], rtol=0, atol=1e-12)


def random_walls(seed: int, n: int) -> F64:
    """Walls on a 500 mm lattice (so many share endpoints or end on each other), some diagonal, some nudged by
    less than the join tolerance, some collinear continuations, a few of zero length."""
    rng = random.Random(seed)
    rows = []
    for _ in range(n):
        x, y = rng.randrange(0, 40) * 500.0, rng.randrange(0, 40) * 500.0
        kind = rng.random()
        if kind < 0.4:
            rows.append((x, y, x + rng.randrange(1, 8) * 500.0, y))
        elif kind < 0.8:
            rows.append((x, y, x, y + rng.randrange(1, 8) * 500.0))
        elif kind < 0.95:
            rows.append((x, y, x + rng.randrange(-6, 7) * 500.0, y + rng.randrange(1, 7) * 500.0))
        else:
            rows.append((x, y, x, y))
        if rng.random() < 0.2:
            x0, y0, x1, y1 = rows[-1]
            rows[-1] = (x0 + rng.uniform(-0.9, 0.9), y0 + rng.uniform(-0.9, 0.9), x1, y1)
    return segments(rows)


def test_office_corners_as_before(office: MapGeometry) -> None:
    assert_same_corners(office.corners(), corners_by_loop(office.walls))


@pytest.mark.parametrize("seed", range(6))
def test_random_maps_as_before(seed: int) -> None:
    walls = random_walls(seed, 400)
    got, want = MapGeometry(walls=walls).corners(), corners_by_loop(walls)
    assert len(want) > 50  # plenty of corners and T junctions to compare
    assert_same_corners(got, want)


@pytest.mark.parametrize(
    "rows",
    [[], [(0.0, 0.0, 1000.0, 0.0)], [(0.0, 0.0, 0.0, 0.0)], [(0.0, 0.0, 1000.0, 0.0), (0.0, 0.0, 0.0, 800.0)]],
)
def test_degenerate_maps(rows: list[tuple[float, float, float, float]]) -> None:
    walls = segments(rows)
    assert_same_corners(MapGeometry(walls=walls).corners(), corners_by_loop(walls))
