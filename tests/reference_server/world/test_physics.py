"""The platform's body in pymunk: exact arcs, walls that stop it (a collision, never a tunnel)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pltf.reference_server.world.geometry import circles, segments
from pltf.reference_server.world.physics import Footprint, Physics, arc

FOOTPRINT = Footprint.from_params(650.0, 100.0, 430.0)  # the defaults (E-PAR-013)


def test_footprint_from_the_geometry_parameters() -> None:
    assert (FOOTPRINT.front, FOOTPRINT.rear, FOOTPRINT.half_width) == (225.0, -425.0, 270.0)
    assert FOOTPRINT.radius == pytest.approx(math.hypot(425, 270))


def test_arc_integration_is_exact() -> None:
    x, y, a = 0.0, 0.0, 0.0
    for _ in range(100):  # a quarter circle of radius 1000 mm in 100 steps
        x, y, a = arc(x, y, a, 1000 * math.pi / 2, math.pi / 2, 0.01)
    assert (x, y, a) == pytest.approx((1000.0, 1000.0, math.pi / 2))
    assert arc(0, 0, 0.3, 100, 0.0, 2.0) == pytest.approx((200 * math.cos(0.3), 200 * math.sin(0.3), 0.3))


def test_driving_into_a_wall_stops_at_it() -> None:
    ph = Physics(FOOTPRINT)
    ph.set_map(segments([(1000, -2000, 1000, 2000)]), circles([]))
    x, y, a = 0.0, 0.0, 0.0
    hit = False
    for _ in range(200):
        x, y, a, hit = ph.move(x, y, a, 1500.0, 0.0, 0.02)  # 30 mm per step, far faster than allowed
    assert hit
    assert 1000 - FOOTPRINT.front - 1.0 <= x < 1000 - FOOTPRINT.front  # touching, not through
    assert ph.overlap(x, y, a) == 0.0
    x2, _, _, hit = ph.move(x, y, a, -500.0, 0.0, 0.02)  # backing off is free
    assert not hit and x2 < x


def test_a_fast_body_never_tunnels_through_a_thin_wall() -> None:
    ph = Physics(FOOTPRINT)
    ph.set_map(segments([(500, -100, 500, 100)]), circles([]))  # a 200 mm stub
    for y in np.linspace(-300, 300, 13):
        x, yy, a = 0.0, float(y), 0.0
        for _ in range(100):
            x, yy, a, _ = ph.move(x, yy, a, 3000.0, 0.0, 0.02)
        # either blocked in front of the stub, or passed beside it: never overlapping it
        assert x < 500 - FOOTPRINT.front + 1 or abs(y) > FOOTPRINT.half_width


def test_obstacles_come_and_go_and_a_pose_inside_one_may_only_get_out() -> None:
    ph = Physics(FOOTPRINT)
    ph.set_obstacle("box", (250.0, 0.0, 100.0))  # dropped onto the platform's front edge
    assert ph.overlap(0.0, 0.0, 0.0) > 0
    x, _, _, hit = ph.move(0.0, 0.0, 0.0, -500.0, 0.0, 0.02)
    assert hit and x == pytest.approx(-10.0)  # backing out (the overlap shrinks) is allowed
    x, _, _, hit = ph.move(0.0, 0.0, 0.0, 500.0, 0.0, 0.02)
    assert hit and x == 0.0  # pushing on is not
    ph.set_obstacle("box", None)
    assert ph.overlap(0.0, 0.0, 0.0) == 0.0
    ph.set_footprint(Footprint.from_params(300.0, 0.0, 200.0))
    ph.set_obstacle("post", (400.0, 0.0, 100.0))
    assert ph.overlap(0.0, 0.0, 0.0) == 0.0 and ph.overlap(200.0, 0.0, 0.0) > 0


def test_a_long_step_is_split_and_does_not_tunnel() -> None:
    ph = Physics(FOOTPRINT)
    ph.set_map(segments([(1000, -2000, 1000, 2000)]), circles([]))
    x, _, _, hit = ph.move(0.0, 0.0, 0.0, 1000.0, 0.0, 10.0)  # a control loop 10 s behind: 10 m in one call
    assert hit and 1000 - FOOTPRINT.front - 1.0 <= x <= 1000 - FOOTPRINT.front  # touching, not through
    _, _, a, hit = ph.move(0.0, 0.0, 0.0, 0.0, 1.0, 10.0)  # 10 rad on the spot, nothing near: all of it
    assert not hit and a == pytest.approx(10.0)
