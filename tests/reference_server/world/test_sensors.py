"""The laser (ranges, noise, observations for the status telegram), the ultrasonic ring, the mouse obstacle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pltf.reference_server.world import MapGeometry
from pltf.reference_server.world.sensors import LASER_FAN, LASER_SIGMA
from tests.reference_server.world.conftest import CORRIDOR_WEST, geometry_of, make_sim, room


def test_ranges_in_a_room_with_seeded_noise() -> None:
    sim = make_sim(geometry_of(room(10000, 8000)), (5000.0, 4000.0, 0.0))
    w = sim.world
    w.sense(0.0, force=True)
    assert w.last_scan is not None
    ahead = w.last_scan.ranges[LASER_FAN.count // 2]
    assert ahead == pytest.approx(10000 - 5000 - w.footprint.front, abs=5 * (LASER_SIGMA + 5))
    errors = []
    for k in range(50):
        w.sense(0.1 * (k + 1))
        errors.append(w.last_scan.ranges[LASER_FAN.count // 2] - (10000 - 5225))
    assert 0.5 * LASER_SIGMA < float(np.std(errors)) < 2.0 * (LASER_SIGMA + 5)
    # every beam hits a wall in a closed room; the scan points lie on the walls
    pts = w.perception.world
    assert len(pts) == LASER_FAN.count
    assert np.all(
        (np.abs(pts[:, 0]) < 60)
        | (np.abs(pts[:, 0] - 10000) < 60)
        | (np.abs(pts[:, 1]) < 60)
        | (np.abs(pts[:, 1] - 8000) < 60)
    )


def test_the_same_seed_gives_the_same_scan() -> None:
    scans = []
    for _ in range(2):
        sim = make_sim(geometry_of(room(10000, 8000)), (5000.0, 4000.0, 0.3), seed=7)
        sim.world.sense(0.0, force=True)
        scans.append(sim.world.last_scan.ranges)  # type: ignore[union-attr]
    np.testing.assert_array_equal(scans[0], scans[1])


def test_observations_in_the_office(office: MapGeometry) -> None:
    sim = make_sim(office, CORRIDOR_WEST)
    sim.world.sense(0.0, force=True)
    obs = sim.world.observation()
    assert len(obs.scan) > 500 and all(abs(v) <= 32767 for p in obs.scan for v in p)
    # the reflectors at x 3000 on both corridor walls, 2 m ahead and 1.2 m to the sides (platform frame)
    assert any(abs(x - 2000) < 60 and abs(y - 1200) < 60 for x, y in obs.reflectors)
    assert any(abs(x - 2000) < 60 and abs(y + 1200) < 60 for x, y in obs.reflectors)
    # the corridor's walls are seen as lines parallel to x, target before source (E-REP-003)
    assert any(abs(ty - 1200) < 60 and abs(sy - 1200) < 60 and abs(tx - sx) > 1000 for tx, ty, sx, sy in obs.lines)
    # the T junctions along the corridor show to the rooms, not to the corridor
    assert not any(abs(y) in range(1100, 1300) for _, y in obs.corners)
    assert obs.circles == ()


def test_the_mouse_obstacle_is_seen_as_a_circle(office: MapGeometry) -> None:
    sim = make_sim(office, CORRIDOR_WEST)
    sim.world.set_mouse_obstacle((3000.0, 10000.0))
    sim.world.sense(0.0, force=True)
    assert sim.world.last_scan.ranges[LASER_FAN.count // 2] == pytest.approx(3000 - 200 - 1225, abs=60)  # type: ignore[union-attr]
    assert sim.world.observation().circles == ((2000, 0, 200),)
    sim.world.set_mouse_obstacle(None)
    sim.world.sense(0.1, force=True)
    assert sim.world.observation().circles == ()


def test_ultrasonic_sees_the_corridor_walls(office: MapGeometry) -> None:
    sim = make_sim(office, (3000.0, 10000.0, 0.0))  # between doors: walls on both sides
    us = sim.world.ultrasonic()
    assert len(us) == 16
    left, right = us[4:8], us[12:16]  # E-PAR-017: 05-08 left side, 13-16 right side
    assert all(900 < d < 960 for d in left) and all(900 < d < 960 for d in right)
    assert all(math.isinf(d) for d in us[:4])  # nothing within 3 m ahead along the corridor
    assert sim.world.us_ranges(0.0)[0] is None
    assert len(sim.world.scan_ranges(0.0)) == 541
