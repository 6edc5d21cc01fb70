"""Scenarios over TCP on maps the test builds and sets with CMD_SET_MAP (free running at an accelerated time scale):
the planner finds its way around walls and never through them, respects prohibited areas, and says why when
there is no way (guide 4.3 PlanningEnabled, 6.4 PlannerState, 6.5 Map; errata E-MOT-001, E-MOT-006)."""

from __future__ import annotations

import math

from tests.reference_server.conftest import Client
from tests.reference_server.world.scenarios import (
    START,
    MotionMode,
    PlannerState,
    R,
    WorldServer,
    assert_clear,
    map_xml,
    param,
    poll,
    running,
    sample,
    settled_at,
    wall_array,
)

TIMEOUT = 20.0
Walls = list[tuple[float, float, float, float]]
# a 9 x 10 m hall around the start pose (2000, 10000)
HALL: Walls = [(0, 5000, 9000, 5000), (9000, 5000, 9000, 15000), (9000, 15000, 0, 15000), (0, 15000, 0, 5000)]
# two walls make an S: over the first one's north end, under the second one's south end
S_WALLS: Walls = [(3500, 5000, 3500, 13000), (6000, 7000, 6000, 15000)]
BOX: Walls = [  # a 2 x 2 m box around the start pose
    (1000, 9000, 3000, 9000),
    (3000, 9000, 3000, 11000),
    (3000, 11000, 1000, 11000),
    (1000, 11000, 1000, 9000),
]
DIVIDER: Walls = [(4500, 5000, 4500, 12500)]  # one gap, 12500..15000, in the north
NEW_WALL = (4000.0, 5000.0, 4000.0, 12500.0)
Zone = list[tuple[float, float]]
GAP_ZONE: Zone = [(3500.0, 12500.0), (5500.0, 12500.0), (5500.0, 15000.0), (3500.0, 15000.0)]


def start_on(world_server: WorldServer, walls: Walls, *setup: object, prohibit: Zone | None = None) -> Client:
    c = Client(world_server.ports[0])
    running(c, MotionMode.MODE_MOTION_AUTOMATIC, R.CMD_SET_MAP(name="test", xml=map_xml(walls, prohibit)), *setup)
    return c


def stands_still(c: Client, seconds: float = 2.0) -> None:
    before = sample(c)
    trace = poll(c, lambda s: s.t >= before.t + seconds, TIMEOUT)
    assert all(math.dist((s.x, s.y), (before.x, before.y)) <= 3 and s.vel_trans == 0 for s in trace), trace[-1]


def test_planning_winds_through_an_s_and_never_through_a_wall(world_server: WorldServer) -> None:
    with start_on(world_server, HALL + S_WALLS) as c:
        c.send(R.CMD_MOVE_ABS(x=7500, y=10000, angle=0))
        trace = poll(c, settled_at((7500, 10000, 0.0), pos=40.0, angle_deg=2.5), TIMEOUT)
        assert_clear(trace, wall_array(HALL + S_WALLS))
        assert max(s.y for s in trace if 3000 < s.x < 4000) > 13000  # over wall 1
        assert min(s.y for s in trace if 4000 < s.x < 6000) < 7000  # under wall 2
        assert trace[-1].planner_state in (PlannerState.PLANNER_PATH_FOUND, PlannerState.PLANNER_STANDBY)


def test_enclosed_start_is_no_path_and_no_motion(world_server: WorldServer) -> None:
    with start_on(world_server, HALL + BOX) as c:
        c.send(R.CMD_MOVE_ABS(x=6000, y=10000, angle=0))
        poll(c, lambda s: s.planner_state == PlannerState.PLANNER_NO_PATH, TIMEOUT)
        stands_still(c)
        assert not sample(c).target_reached


def test_a_prohibited_gap_is_no_path_and_without_it_the_way_leads_through(world_server: WorldServer) -> None:
    with start_on(world_server, HALL + DIVIDER, prohibit=GAP_ZONE) as c:
        c.send(R.CMD_MOVE_ABS(x=7000, y=10000, angle=0))
        poll(c, lambda s: s.planner_state == PlannerState.PLANNER_NO_PATH, TIMEOUT)
        stands_still(c)
        c.send(R.CMD_SET_MAP(name="test", xml=map_xml(HALL + DIVIDER)), R.CMD_MOVE_ABS(x=7000, y=10000, angle=0))
        trace = poll(c, settled_at((7000, 10000, 0.0), pos=40.0, angle_deg=2.5), TIMEOUT)
        assert_clear(trace, wall_array(HALL + DIVIDER))
        assert max(s.y for s in trace) > 12500  # through the gap


def test_a_target_in_a_prohibited_area_is_a_collision_at_the_target(world_server: WorldServer) -> None:
    with start_on(world_server, HALL + DIVIDER, prohibit=GAP_ZONE) as c:
        c.send(R.CMD_MOVE_ABS(x=4500, y=14000, angle=0))
        poll(c, lambda s: s.planner_state == PlannerState.PLANNER_COLLISION_TARGET, TIMEOUT)
        stands_still(c)


def test_without_planning_the_direct_path_stops_in_front_of_a_wall(world_server: WorldServer) -> None:
    wall: Walls = [(4000, 8000, 4000, 12000)]
    with start_on(world_server, HALL + wall, param("PlanningEnabled", False)) as c:
        c.send(R.CMD_MOVE_ABS(x=6000, y=10000, angle=0))  # straight through the wall
        trace = poll(c, lambda s: s.x > 2500, TIMEOUT)
        before = trace[-1]
        trace += poll(c, lambda s: s.t >= before.t + 8.0, TIMEOUT)
        assert_clear(trace, wall_array(HALL + wall))
        assert not trace[-1].target_reached
        # it waits in front of the wall: the tracking controller holds the stopped reference against the
        # estimate's scan-to-scan corrections (sub-millimetre moves the encoders read as a few mm/s), and a scan
        # whose corridor check briefly comes out free lets it creep a few millimetres before it stops again
        # (seen: +8 mm at ~40 mm/s, then back); it never drives on
        held = [s for s in trace if s.t >= before.t + 5.0]
        assert held and max(s.x for s in held) - min(s.x for s in held) <= 20, [(s.t, s.x, s.vel_trans) for s in held]
        # waits in front of it: the front edge (325 mm ahead of the axis) CollLaserMinDist 300 mm + 100 mm away
        assert all(4000 - 325 - 600 <= s.x <= 4000 - 325 - 300 for s in held)


def test_a_new_map_takes_effect_at_once(world_server: WorldServer) -> None:
    with start_on(world_server, HALL) as c:
        c.send(R.CMD_MOVE_ABS(x=6000, y=10000, angle=0))
        trace = poll(c, settled_at((6000, 10000, 0.0), pos=40.0, angle_deg=2.5), TIMEOUT)
        assert max(abs(s.y - START[1]) for s in trace) <= 50  # straight: nothing in the way
        c.send(R.CMD_SET_MAP(name="test", xml=map_xml([*HALL, NEW_WALL])))
        c.send(R.CMD_MOVE_ABS(x=2000, y=10000, angle=180000))
        trace = poll(c, settled_at((2000, 10000, math.pi), pos=40.0, angle_deg=2.5), TIMEOUT)
        assert_clear(trace, wall_array([*HALL, NEW_WALL]))
        assert max(s.y for s in trace) > 12500  # around the new wall's end
