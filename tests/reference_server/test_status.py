"""status: the integer conversions of the CMD_GET_STATUS fields."""

from __future__ import annotations

import random

from reference_server.status import _i32, _i32_points


def test_path_points_round_half_to_even_and_saturate() -> None:
    frames = [(0.5, 1.5, 0.0), (-0.5, -2.5, 1.0), (2.4999, -2.5001, 0.0), (3e9, -3e9, 0.0), (2**31 - 0.4, 0.0, 0.0)]
    assert _i32_points(frames) == ((0, 2), (0, -2), (2, -3), (2**31 - 1, -(2**31)), (2**31 - 1, 0))
    assert _i32_points([]) == ()


def test_path_points_equal_the_scalar_conversion() -> None:
    rng = random.Random(4)
    frames = [(rng.uniform(-3e9, 3e9), rng.choice([rng.uniform(-1e5, 1e5), rng.randrange(-50, 50) + 0.5]), 0.0)
              for _ in range(2000)]  # fmt: skip
    got = _i32_points(frames)
    assert got == tuple((_i32(x), _i32(y)) for x, y, _ in frames)
    assert all(type(v) is int for pair in got for v in pair)  # the codec's INT fields take Python ints
