"""The vectorised wall corners (geometry._corners) against the plain O(n^2) loop they replaced, on the office floor
and on random maps with shared endpoints, T junctions, collinear joins, diagonals and near-duplicate points."""

from __future__ import annotations

import random

import numpy as np
import pytest

from benchmarks.corners_loop import corners_by_loop
from pltf.reference_server.world.geometry import (
    F64,
    MapGeometry,
    segments,
)


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
