"""The laser's fan caster against the dense reference caster and against geometry known by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pltf.reference_server.world import raycast
from pltf.reference_server.world.raycast import Fan, Scene, cast_fan, cast_fan_numpy, cast_rays, cast_rays_numpy
from pltf.reference_server.world.sensors import LASER_FAN


def _random_scene(rng: np.random.Generator, n: int = 120) -> Scene:
    c = rng.uniform(0, 20000, (n, 2))
    a = rng.uniform(0, math.pi, n)
    half = rng.uniform(100, 3000, n) / 2
    segs = np.column_stack(
        [c[:, 0] - half * np.cos(a), c[:, 1] - half * np.sin(a), c[:, 0] + half * np.cos(a), c[:, 1] + half * np.sin(a)]
    )
    circs = np.column_stack([rng.uniform(0, 20000, (15, 2)), rng.uniform(50, 800, 15)])
    return Scene.make(segs, circs)


def test_fan_equals_dense_casting_everywhere() -> None:
    rng = np.random.default_rng(11)
    fan = Fan(541, math.radians(-135), math.radians(0.5), 12000.0)
    for _ in range(60):
        scene = _random_scene(rng)
        x, y, h = rng.uniform(0, 20000), rng.uniform(0, 20000), rng.uniform(-7, 7)
        r1, h1 = cast_fan(x, y, h, scene, fan)
        angles = np.asarray(h + fan.start + fan.step * np.arange(fan.count), dtype=np.float64)
        r2, h2 = cast_rays(np.full(fan.count, x), np.full(fan.count, y), angles, scene, fan.max_range)
        np.testing.assert_allclose(np.nan_to_num(r1, posinf=-1.0), np.nan_to_num(r2, posinf=-1.0), atol=1e-6)
        same = np.isfinite(r1)
        assert (h1[same] == h2[same]).mean() > 0.99  # ties at shared endpoints may pick either segment
        assert (h1[~same] == -1).all()


def test_the_c_loops_are_built() -> None:
    """``make`` builds the extension: without it the server falls back to numpy and misses its speed."""
    assert raycast.HAVE_C


@pytest.mark.parametrize("seed", range(8))
def test_c_loops_equal_numpy_bit_for_bit(seed: int) -> None:
    """The C loops take numpy's floating-point steps: the same ranges and the same hit ids, to the last bit
    (ties included), for segments, circles, an origin inside a circle, degenerate and crossing segments."""
    rng = np.random.default_rng(seed)
    for _ in range(25):
        scene = _random_scene(rng, n=int(rng.integers(0, 80)))
        extra = np.array([[5000.0, 5000, 5000, 5000], [0, 0, 20000, 20000], [0, 20000, 20000, 0]])
        scene = Scene.make(np.vstack([scene.segs, extra]), np.vstack([scene.circs, [[10000.0, 10000, 3000]]]))
        x, y, h = rng.uniform(0, 20000), rng.uniform(0, 20000), rng.uniform(-7, 7)
        fan = Fan(int(rng.integers(1, 800)), rng.uniform(-math.pi, 0), rng.uniform(0.001, 0.05), rng.uniform(1, 3e4))
        for got, want in zip(cast_fan(x, y, h, scene, fan), cast_fan_numpy(x, y, h, scene, fan), strict=True):
            np.testing.assert_array_equal(got, want)
        n = int(rng.integers(1, 60))
        ox, oy, ang = rng.uniform(0, 20000, n), rng.uniform(0, 20000, n), rng.uniform(-7, 7, n)
        for got, want in zip(
            cast_rays(ox, oy, ang, scene, 8000.0), cast_rays_numpy(ox, oy, ang, scene, 8000.0), strict=True
        ):
            np.testing.assert_array_equal(got, want)


def test_the_c_loops_refuse_buffers_shorter_than_the_call() -> None:
    """A buffer too short for the call is a ValueError, not a read or write past its end."""
    from pltf.reference_server.world import _raycast

    scene = Scene.make(np.array([[1000.0, -500, 1000, 500]]))
    with pytest.raises(ValueError, match="oy"):
        _raycast.rays(
            np.zeros(8),
            np.zeros(2),
            np.ones(8),
            np.zeros(8),
            scene.segs,
            scene.circs,
            100.0,
            np.empty(8),
            np.empty(8, dtype=np.int64),
        )
    with pytest.raises(ValueError, match="ranges"):
        _raycast.fan(
            0.0,
            0.0,
            -1.0,
            0.0,
            0.01,
            100.0,
            200,
            scene.segs,
            scene.circs,
            np.ones(200),
            np.ones(200),
            np.empty(10),
            np.empty(200, dtype=np.int64),
        )


def test_empty_scene_in_c() -> None:
    ranges, hits = cast_fan(0.0, 0.0, 0.0, Scene.make(), LASER_FAN)
    assert not np.isfinite(ranges).any() and (hits == -1).all()
    ranges, hits = cast_rays(np.zeros(3), np.zeros(3), np.zeros(3), Scene.make(), 100.0)
    assert not np.isfinite(ranges).any() and (hits == -1).all()


def test_a_wall_ahead_and_the_blind_zone_behind() -> None:
    scene = Scene.make(np.array([[2000.0, -5000, 2000, 5000], [-1000, -5000, -1000, 5000]]))
    ranges, hits = cast_fan(0.0, 0.0, 0.0, scene, LASER_FAN)
    assert ranges[270] == pytest.approx(2000.0)  # the middle beam looks straight ahead
    assert ranges[0] == pytest.approx(1000.0 / math.cos(math.radians(45)))  # -135 deg: the wall behind
    assert hits[270] == 0 and hits[0] == 1
    assert np.isinf(ranges[90])  # -90 deg: parallel to both walls


def test_a_segment_across_the_blind_zone_is_seen_at_both_edges() -> None:
    scene = Scene.make(np.array([[-1000.0, 3000, -1000, -3000]]))  # behind, spanning +-180 deg
    ranges, _ = cast_fan(0.0, 0.0, 0.0, scene, LASER_FAN)
    seen = np.flatnonzero(np.isfinite(ranges))
    assert seen.min() == 0 and seen.max() == 540
    assert ranges[0] == pytest.approx(1000 / math.cos(math.radians(45)))


def test_circles_max_range_and_an_origin_inside_a_circle() -> None:
    scene = Scene.make(None, np.array([[3000.0, 0, 500], [0, 0, 100]]))
    ranges, hits = cast_fan(0.0, 0.0, 0.0, scene, LASER_FAN)
    assert ranges[270] == pytest.approx(2500.0)
    assert hits[270] == 0  # circles' ids follow the segments' (there are none)
    short = Fan(LASER_FAN.count, LASER_FAN.start, LASER_FAN.step, 2000.0)
    assert not np.isfinite(cast_fan(0.0, 0.0, 0.0, scene, short)[0]).any()
