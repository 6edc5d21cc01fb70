"""reference_server/hardware_link.py: the serial scanner's scan as the status telegram's points."""

from __future__ import annotations

import math
import random

import pytest

from pltf.fake_hardware.serial_scanner import ANGLE_STEP, POINTS, START_ANGLE
from pltf.reference_server.hardware_link import NO_ECHO, scan_to_platform

I16 = 32767


def one_by_one(ranges: tuple[int, ...], mount_x: float) -> tuple[tuple[int, int], ...]:
    """The rule beam by beam: an echo (0 < r < NO_ECHO) at the beam's angle, rounded half to even, saturated."""

    def clip(v: float) -> int:
        return max(-I16, min(I16, round(v)))

    out = []
    for i, r in enumerate(ranges):
        if 0 < r < NO_ECHO:
            a = START_ANGLE + i * ANGLE_STEP
            out.append((clip(mount_x + r * math.cos(a)), clip(r * math.sin(a))))
    return tuple(out)


@pytest.mark.parametrize("seed", range(20))
def test_the_points_are_the_beam_by_beam_rule_exactly(seed: int) -> None:
    rng = random.Random(seed)
    choices = [0, NO_ECHO, NO_ECHO + 10, 1, 5, 10]
    ranges = tuple(rng.choice(choices) if rng.random() < 0.2 else rng.randrange(1, NO_ECHO) for _ in range(POINTS))
    mount_x = rng.choice([0.0, 0.5, 120.0, 287.5, -33.5])
    assert scan_to_platform(ranges, mount_x) == one_by_one(ranges, mount_x)


def test_beams_without_echo_are_left_out_and_far_ones_saturate() -> None:
    ranges = (0,) * 270 + (NO_ECHO - 1,) + (NO_ECHO,) * 270
    (point,) = scan_to_platform(ranges, 0.0)
    assert point == one_by_one(ranges, 0.0)[0]
    assert abs(point[0]) == I16 or abs(point[1]) == I16  # the beam straight ahead at 81.9 m: x saturates


def test_a_short_scan_and_an_empty_one() -> None:
    assert scan_to_platform((), 100.0) == ()
    assert scan_to_platform((1000, 0, 1000), 0.0) == one_by_one((1000, 0, 1000), 0.0)
