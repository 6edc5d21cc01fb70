"""status: the integer conversions of the CMD_GET_STATUS fields, and its cached frame."""

from __future__ import annotations

import random
from pathlib import Path

from pltf.reference_server.cli import build_platform
from pltf.reference_server.status import _i32, _i32_points, status_frame, status_reply
from pltf.reference_server.storage import Storage
from pltf.spec.codec import encode


def test_path_points_round_half_to_even_and_saturate() -> None:
    frames = [(0.5, 1.5, 0.0), (-0.5, -2.5, 1.0), (2.4999, -2.5001, 0.0), (3e9, -3e9, 0.0), (2**31 - 0.4, 0.0, 0.0)]
    assert _i32_points(frames) == ((0, 2), (0, -2), (2, -3), (2**31 - 1, -(2**31)), (2**31 - 1, 0))
    assert _i32_points([]) == ()


def test_path_points_equal_the_scalar_conversion() -> None:
    rng = random.Random(4)
    frames = [
        (rng.uniform(-3e9, 3e9), rng.choice([rng.uniform(-1e5, 1e5), rng.randrange(-50, 50) + 0.5]), 0.0)
        for _ in range(2000)
    ]
    got = _i32_points(frames)
    assert got == tuple((_i32(x), _i32(y)) for x, y, _ in frames)
    assert all(type(v) is int for pair in got for v in pair)  # the codec's INT fields take Python ints


def test_the_cached_status_frame_is_the_codecs_encoding_at_every_time(tmp_path: Path) -> None:
    """status_frame encodes once per epoch and replaces the timestamp: the bytes must be exactly what the codec
    makes of the telegram, at any time (timestamps wrap at 2^31 ms, erratum E-REP-010), before and after the
    platform changes."""
    storage = Storage(tmp_path)
    storage.seed_from_fixtures()
    p = build_platform(storage, 1, hardware=True)
    try:
        p.boot(0.0)
        for now in (0.0, 0.001, 1.234, 99.9, 2**31 / 1000.0 + 5.5):
            telegram, frame = status_frame(p, now)
            assert frame == encode(telegram) == encode(status_reply(p, now))
            assert telegram.timestamp == int(now * 1000.0) % 2**31  # type: ignore[attr-defined]
        for k in range(1, 30):
            p.tick(k * 0.02)  # new epochs: a scan, a pose
            telegram, frame = status_frame(p, k * 0.02 + 0.01)
            assert frame == encode(telegram)
    finally:
        p.close()


def test_the_status_path_is_the_remaining_path_while_driving(tmp_path: Path) -> None:
    """The world hands GET_STATUS its path as an array (``path_xy``); the status must carry exactly the
    remaining path's points, converted one by one, while the platform drives a long path and after it stops."""
    storage = Storage(tmp_path)
    storage.seed_from_fixtures()
    p = build_platform(storage, 1, hardware=False)
    try:
        p.boot(0.0)
        start = p.motion.pose
        p.motion.follow_path([(start.x + 8000.0, start.y, 0.0), (start.x + 8000.0, start.y + 3000.0, 0.0)])  # type: ignore[attr-defined]
        lengths = []
        for k in range(1, 200):
            p.tick(k * 0.02)
            if k % 20 == 0:
                path = status_reply(p, k * 0.02).path  # type: ignore[attr-defined]
                assert path == tuple((_i32(f.x), _i32(f.y)) for f in p.motion.remaining_path())
                lengths.append(len(path))
        assert lengths[0] > 50 and lengths == sorted(lengths, reverse=True)  # a long path, shrinking as it goes
        p.motion.stop()
        p.tick(200 * 0.02)
        assert status_reply(p, 4.0).path == ()  # type: ignore[attr-defined]
    finally:
        p.close()
