"""Scenarios over TCP on the fixture office floor (fixtures/maps/office.map, roadmap office.rm), free running at an
accelerated time scale: every automatic move command reaches its target, planning goes through the doors and
never through a wall, a station is reached over the roadmap (guide 4.3 Motion mode Automatic)."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest

from pltf.reference_server.world.geometry import point_segment_distance
from tests.reference_server.conftest import Client
from tests.reference_server.world.scenarios import (
    START,
    MotionMode,
    PlannerState,
    R,
    Sample,
    WorldServer,
    assert_clear,
    office,
    poll,
    running,
    sample,
    settled_at,
)

OFFICE = office()
WALLS = OFFICE.obstacles  # walls and tables (auxiliary lines): both physical (E-MOT-001)
PILLARS = OFFICE.circles
TIMEOUT = 20.0  # wall s: the longest move here is ~40 s simulated, 1.6 s at 25x


@pytest.fixture
def auto(world_server: WorldServer) -> Iterator[Client]:
    with Client(world_server.ports[0]) as c:
        running(c, MotionMode.MODE_MOTION_AUTOMATIC)
        yield c


def rad(milli_deg: int) -> float:
    return math.radians(milli_deg / 1000.0)


def passes(trace: list[Sample], point: tuple[float, float], within: float) -> bool:
    """The sampled trajectory, joined sample to sample (polls may be sparse under load), comes within ``within``."""
    pts = np.array([(s.x, s.y) for s in trace], dtype=np.float64)
    steps = np.column_stack([pts[:-1], pts[1:]]) if len(pts) > 1 else np.hstack([pts, pts])
    return bool(point_segment_distance(np.array([point[0]]), np.array([point[1]]), steps).min() <= within)


def test_boots_at_the_start_pose_on_the_office_map(auto: Client) -> None:
    poll(auto, lambda s: s.t >= 0.5, TIMEOUT)  # a few laser scans (10 Hz)
    s = auto.status()
    assert (s.est_x, s.est_y, s.est_angle) == (*START[:2], 0)
    assert len(s.scan) > 400 and len(s.lines) >= 2  # the laser sees the corridor's walls


def test_move_abs_into_a_room_plans_through_its_door(auto: Client) -> None:
    # the straight line from the corridor's west end to the kitchen crosses the corridor's north wall at x ~3600
    goal = (5000, 12200, 90000)
    auto.send(R.CMD_MOVE_ABS(x=goal[0], y=goal[1], angle=goal[2]))
    trace = poll(auto, settled_at((goal[0], goal[1], rad(goal[2])), pos=40.0, angle_deg=2.5), TIMEOUT)
    assert_clear(trace, WALLS, PILLARS)
    assert passes(trace, (5000, 11200), 300.0)  # through the kitchen door (x 4400..5600)


def test_move_abs_across_the_floor_never_touches_a_wall(auto: Client) -> None:
    goal = (27500, 7800, -90000)  # Storage, the far south-east room
    auto.send(R.CMD_MOVE_ABS(x=goal[0], y=goal[1], angle=goal[2]))
    trace = poll(auto, settled_at((goal[0], goal[1], rad(goal[2])), pos=40.0, angle_deg=2.5), TIMEOUT)
    assert_clear(trace, WALLS, PILLARS)
    assert passes(trace, (27500, 8800), 300.0)
    assert not any(s.collision for s in trace)


def test_move_rel_is_relative_to_the_platform(auto: Client) -> None:
    auto.send(R.CMD_MOVE_REL(x=1500, y=-300, angle=90000))  # 1.5 m ahead, 0.3 m right, then facing north
    goal = (START[0] + 1500, START[1] - 300, math.pi / 2)
    trace = poll(auto, settled_at(goal, pos=40.0, angle_deg=2.5), TIMEOUT)
    assert_clear(trace, WALLS, PILLARS)
    auto.send(R.CMD_MOVE_REL(x=800, y=0, angle=-90000))  # relative to the new pose: 0.8 m north, facing east
    poll(auto, settled_at((goal[0], goal[1] + 800, 0.0), pos=40.0, angle_deg=2.5), TIMEOUT)


def test_move_path_passes_every_frame_and_ends_on_the_last(auto: Client) -> None:
    frames = [(4000, 10000, 0), (7000, 10000, 0), (7000, 8800, -90000), (7000, 7600, -90000)]  # into the lab
    auto.send(R.CMD_MOVE_PATH(frames=tuple(frames)))
    end = frames[-1]
    trace = poll(auto, settled_at((end[0], end[1], rad(end[2])), pos=40.0, angle_deg=2.5), TIMEOUT)
    assert_clear(trace, WALLS, PILLARS)
    for x, y, _ in frames[:-1]:
        assert passes(trace, (x, y), 150.0), (x, y)  # a fillet cuts a corner by at most 30 mm (E-MOT-007)


def test_move_to_station_follows_the_roadmap(auto: Client) -> None:
    auto.send(R.CMD_MOVE_TO_STATION(station="Office_S1"))  # station at (21000, 7800), facing south
    trace = poll(auto, settled_at((21000, 7800, -math.pi / 2), pos=40.0, angle_deg=2.5), TIMEOUT)
    assert_clear(trace, WALLS, PILLARS)
    # the roadmap's route: along the corridor to Corridor_06, through the door point, to the station
    for point in [(5000, 10000), (19000, 10000), (21000, 10000), (21000, 8800)]:
        assert passes(trace, point, 200.0), point
    assert max(abs(s.y - 10000) for s in trace if s.x < 20000) <= 200  # on the corridor's centre line


def test_a_new_move_preempts_the_running_one(auto: Client) -> None:
    auto.send(R.CMD_MOVE_ABS(x=27500, y=10000, angle=0))
    poll(auto, lambda s: s.x > 4000, TIMEOUT)
    auto.send(R.CMD_MOVE_ABS(x=3000, y=10000, angle=180000))  # turn back before the first target
    trace = poll(auto, settled_at((3000, 10000, math.pi), pos=40.0, angle_deg=2.5), TIMEOUT)
    assert max(s.x for s in trace) < 12000  # it never went on to the first target
    assert_clear(trace, WALLS, PILLARS)


def test_a_target_in_a_wall_is_a_collision_at_the_target_and_nothing_moves(auto: Client) -> None:
    before = sample(auto)
    auto.send(R.CMD_MOVE_ABS(x=3000, y=11250, angle=0))  # on the corridor's north wall (y 11200)
    trace = poll(auto, lambda s: s.planner_state == PlannerState.PLANNER_COLLISION_TARGET, TIMEOUT)
    trace += poll(auto, lambda s: s.t >= trace[-1].t + 2.0, TIMEOUT)
    assert all(abs(s.x - before.x) <= 2 and abs(s.y - before.y) <= 2 and s.vel_trans == 0 for s in trace)
    assert not trace[-1].target_reached


def test_move_to_an_unknown_station_does_not_move(auto: Client) -> None:
    before = sample(auto)
    auto.send(R.CMD_MOVE_TO_STATION(station="Nowhere"))
    trace = poll(auto, lambda s: s.t >= before.t + 2.0, TIMEOUT)
    assert all(abs(s.x - before.x) <= 2 and abs(s.y - before.y) <= 2 and s.vel_trans == 0 for s in trace)
