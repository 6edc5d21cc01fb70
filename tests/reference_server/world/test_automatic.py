"""Motion mode Automatic (guide 4.3) as scenarios in simulated time: every move command reaches its target within
tolerance, planning goes around walls and never through them, obstacles stop, are driven around or waited for,
no path means no motion, stations are reached over the roadmap, a new command preempts the running one."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from pltf.reference_server.kinematics import Frame, Roadmap, relative_to_world
from pltf.reference_server.world import MapGeometry, PlannerState
from pltf.reference_server.world.automatic import AutoJob
from pltf.reference_server.world.geometry import circles, segments
from pltf.reference_server.world.paths import DS, MAX_SAMPLES, Turn
from pltf.spec.documents import DocumentKind, validate_document
from tests.reference_server.world.conftest import (
    CORRIDOR_WEST,
    OFFICE_ROADMAP,
    Sim,
    assert_clear_of,
    geometry_of,
    make_sim,
    room,
    within,
)

TOL = 20.0  # TargetReachedTolPos (the estimate); the truth is allowed the localization's error on top
TRUE_TOL = 60.0
STORAGE = (27500.0, 7800.0, -math.pi / 2)
KITCHEN = (5000.0, 12200.0, math.pi / 2)
OPEN = geometry_of(room(20000, 20000))


def _reached(sim: Sim, goal: tuple[float, float, float]) -> None:
    assert sim.world.target_reached, sim.events[-5:]
    assert within(sim.world, goal, TOL, 2.0, truth=False)
    assert within(sim.world, goal, TRUE_TOL, 3.0)
    assert sim.contacts == 0


def test_move_abs_plans_through_the_office_and_never_touches_a_wall(office: MapGeometry) -> None:
    sim = make_sim(office, CORRIDOR_WEST)
    sim.world.move_to(STORAGE)
    assert sim.world.motion.planner_state is PlannerState.PLANNING  # until the next control period
    sim.run(0.02)
    assert sim.world.motion.planner_state is PlannerState.PATH_FOUND  # type: ignore[comparison-overlap]
    path = sim.world.remaining_path()
    assert math.dist(path[-1], STORAGE[:2]) < 1.0
    assert sim.until_idle()
    _reached(sim, STORAGE)
    assert sim.world.motion.planner_state is PlannerState.STANDBY
    assert any(e.startswith("target reached") for e in sim.events)
    assert_clear_of(sim.trace, office.obstacles, sim.world.footprint.half_width, office.circles)
    assert not any(11000 < x < 14500 and 1000 < y < 5500 for x, y, _ in sim.trace)  # the prohibited area


def test_move_abs_from_room_to_room(office: MapGeometry) -> None:
    sim = make_sim(office, (19000.0, 12200.0, math.pi / 2))  # Office_N1
    sim.world.move_to(KITCHEN)
    assert sim.until_idle()
    _reached(sim, KITCHEN)
    assert_clear_of(sim.trace, office.obstacles, sim.world.footprint.half_width, office.circles)


def test_the_commanded_frame_leads_the_platform_along_the_path(office: MapGeometry) -> None:
    sim = make_sim(office, CORRIDOR_WEST)
    sim.world.move_to(STORAGE)
    for _ in range(10):
        sim.run(1.0)
        cmd, est = sim.world.commanded_frame(), sim.world.estimate
        assert math.dist(cmd[:2], est[:2]) < 400.0
    sim.until_idle()
    assert sim.world.commanded_frame() == sim.world.estimate and sim.world.remaining_path() == []


def test_move_rel_reaches_a_frame_given_in_platform_coordinates() -> None:
    sim = make_sim(OPEN, (10000.0, 10000.0, math.pi / 2))
    x, y, a = relative_to_world(Frame(*sim.world.estimate), Frame(2000.0, -1000.0, math.radians(-90)))
    goal = (x, y, a)
    sim.world.move_to(goal)
    assert sim.until_idle(60.0)
    _reached(sim, goal)


def test_without_planning_a_bezier_curve_or_a_turn_first() -> None:
    goal = (14000.0, 12000.0, math.pi / 2)
    sim = make_sim(OPEN, (10000.0, 10000.0, 0.0), PlanningEnabled=False)
    sim.world.move_to(goal)
    assert sim.world.motion.planner_state is PlannerState.STANDBY
    assert sim.until_idle(60.0)
    _reached(sim, goal)
    ys = [y for _, y, _ in sim.trace]
    assert min(ys) > 9950 and sim.trace[10][1] < 10030  # left along its heading: a curve, no turn on the spot
    turn = make_sim(OPEN, (10000.0, 10000.0, 0.0), PlanningEnabled=False, StartTurnEnabled=True)
    turn.world.move_to(goal)
    turn.run(1.0)
    assert math.dist(turn.world.truth[:2], (10000.0, 10000.0)) < 15 and turn.world.truth[2] > 0.2  # turned first
    assert turn.until_idle(60.0)
    _reached(turn, goal)


def test_without_planning_the_platform_waits_in_front_of_an_obstacle() -> None:
    sim = make_sim(OPEN, (3000.0, 10000.0, 0.0), PlanningEnabled=False)
    sim.world.set_mouse_obstacle((9000.0, 10000.0))
    sim.world.move_to((15000.0, 10000.0, 0.0))
    sim.run(15.0)
    assert sim.world.active and "obstacle on the path: stopping in front of it" in sim.events
    front = sim.world.truth[0] + sim.world.footprint.front
    assert 9000 - 200 - front >= 300  # CollLaserMinDist (and more) before the obstacle's surface
    waiting = sim.world.truth
    sim.run(5.0)
    assert math.dist(sim.world.truth[:2], waiting[:2]) < 1.0
    sim.world.set_mouse_obstacle(None)  # the obstacle goes: the platform drives on
    assert sim.until_idle(60.0)
    _reached(sim, (15000.0, 10000.0, 0.0))


def test_with_planning_the_platform_drives_around_an_obstacle() -> None:
    walls = room(20000, 20000)
    sim = make_sim(geometry_of(walls), (3000.0, 10000.0, 0.0))
    sim.world.set_mouse_obstacle((9000.0, 10000.0))  # not in the map: only the laser sees it
    sim.world.move_to((15000.0, 10000.0, 0.0))
    assert sim.until_idle(90.0)
    _reached(sim, (15000.0, 10000.0, 0.0))
    assert "replanned around an obstacle" in sim.events
    obstacle = circles([(9000.0, 10000.0, 200.0)])
    assert_clear_of(sim.trace, segments(walls), sim.world.footprint.half_width, obstacle)


def test_no_path_means_no_motion_and_the_planner_says_why() -> None:
    box = [(s[0] + 12000, s[1] + 8000, s[2] + 12000, s[3] + 8000) for s in room(4000, 4000)]
    sim = make_sim(geometry_of([*room(20000, 20000), *box]), (3000.0, 10000.0, 0.0))
    for goal, state in [
        ((14000.0, 10000.0, 0.0), PlannerState.NO_PATH),  # inside the closed box
        ((12000.0, 10000.0, 0.0), PlannerState.COLLISION_TARGET),  # on its wall
    ]:
        sim.world.move_to(goal)
        sim.run(2.0)
        assert sim.world.motion.planner_state is state
        assert not sim.world.active and not sim.world.target_reached
        assert math.dist(sim.trace[0][:2], sim.world.truth[:2]) < 1e-9


def test_a_new_move_preempts_the_running_one(office: MapGeometry) -> None:
    sim = make_sim(office, CORRIDOR_WEST)
    sim.world.move_to(STORAGE)
    sim.run(5.0)
    sim.world.move_to(KITCHEN)
    assert sim.until_idle()
    _reached(sim, KITCHEN)


def test_the_target_is_reached_at_standstill_and_the_pose_stays_there(office: MapGeometry) -> None:
    # E-SRV-009: "reached" waits for the odometry at rest; a goal behind a platform that drives east, to be faced
    # the other way (tests/clients/test_scenarios' replaced goal: it coasted 2 degrees past the verdict once)
    sim = make_sim(office, (2500.0, 10000.0, 0.0))
    sim.world.move_to((9000.0, 10000.0, 0.0))
    assert sim.run(30.0, lambda w: w.truth[0] > 3500.0)
    goal = (3000.0, 9800.0, math.pi)
    sim.world.move_to(goal)
    assert sim.run(60.0, lambda w: w.target_reached)
    v, w = sim.world.measured
    assert abs(v) < 1.0 and abs(w) < 0.002, (v, w)
    sim.run(2.0)
    assert within(sim.world, goal, TOL, 2.0, truth=False)


def test_move_path_follows_the_frames_and_turns_to_the_end_angle(office: MapGeometry) -> None:
    frames = [(3000.0, 10000.0, 0.0), (8500.0, 10000.0, 0.0), (8500.0, 11200.0, 0.0), (8500.0, 13000.0, math.pi)]
    sim = make_sim(office, (1500.0, 9500.0, 0.0))
    sim.world.follow_path(frames)
    assert sim.until_idle()
    _reached(sim, frames[-1])
    for fx, fy, _ in frames[1:3]:  # the path's corners are passed closely (fillets cut them by <= 30 mm)
        assert min(math.hypot(x - fx, y - fy) for x, y, _ in sim.trace) < 80.0
    assert_clear_of(sim.trace, office.obstacles, sim.world.footprint.half_width, office.circles)


def test_move_path_waits_then_drives_around_an_obstacle_and_rejoins() -> None:
    walls = room(20000, 20000)
    frames = [(3000.0, 10000.0, 0.0), (17000.0, 10000.0, 0.0)]
    sim = make_sim(geometry_of(walls), (3000.0, 10000.0, 0.0), PlanningEnabled=False)
    sim.world.set_mouse_obstacle((9000.0, 10000.0))
    sim.world.follow_path(frames)
    assert sim.run(30.0, lambda w: "obstacle on the path: stopping in front of it" in sim.events)
    stopped_at = sim.now
    assert sim.run(10.0, lambda w: "obstacle on the path: driving around it" in sim.events)
    assert sim.now - stopped_at >= 3.0  # PathObstacleWaitTime
    assert sim.until_idle(90.0)
    _reached(sim, frames[-1])
    behind = [y for x, y, _ in sim.trace if x > 12000]
    assert max(abs(y - 10000) for y in behind[-50:]) < 50  # back on the path
    assert_clear_of(sim.trace, segments(walls), sim.world.footprint.half_width, circles([(9000.0, 10000.0, 200.0)]))


def _off_path(trace: list[tuple[float, float, float]], corners: list[tuple[float, float]]) -> float:
    """The farthest the wheel axis' midpoint came from the polyline through ``corners`` (mm)."""
    pts = np.asarray(trace)[:, :2]
    best = np.full(len(pts), np.inf)
    for (x0, y0), (x1, y1) in itertools.pairwise(corners):
        d = np.array([x1 - x0, y1 - y0])
        t = np.clip(((pts - (x0, y0)) @ d) / (d @ d), 0.0, 1.0)
        best = np.minimum(best, np.hypot(*(pts - (x0, y0) - t[:, None] * d).T))
    return float(best.max())


def test_a_turn_held_back_by_the_collision_check_is_waited_for_before_the_next_leg() -> None:
    # a post beside the rear at the path's corner, which only the ultrasonic sensors see: the left turn there
    # is held back until the post goes; the next leg starts on its heading instead of 90 degrees off it
    # (seen 2026-11-26 in the editor test under load: a stalled turn at a station, the reference turned on alone)
    corners = [(10000.0, 10000.0), (12000.0, 10000.0), (12000.0, 12000.0)]
    sim = make_sim(OPEN, (*corners[0], 0.0), PlanningEnabled=False)
    sim.world.set_obstacle("post", (12000.0 - 250.0, 10000.0 - 270.0 - 150.0, 60.0))
    sim.world.follow_path([(*corners[1], 0.0), (*corners[2], math.pi / 2)])

    def turning(w: object) -> bool:
        job = sim.world.motion.job
        return isinstance(job, AutoJob) and job.ipo is not None and isinstance(job.ipo.leg, Turn)

    assert sim.run(30.0, turning)
    sim.run(6.0)  # longer than the whole turn takes
    assert sim.world.collision and abs(sim.world.truth[2]) < math.radians(15.0) and turning(sim.world)
    sim.world.set_obstacle("post", None)
    assert sim.until_idle(60.0)
    _reached(sim, (*corners[2], math.pi / 2))
    assert _off_path(sim.trace, corners) < 60.0


def test_move_to_station_over_the_roadmap(office: MapGeometry) -> None:
    roadmap = Roadmap(validate_document(DocumentKind.ROADMAP, OFFICE_ROADMAP.read_bytes()))
    sim = make_sim(office, (1200.0, 9900.0, 0.0))
    start = roadmap.nearest(*sim.world.estimate[:2])
    goal = roadmap.find("Office_S1")
    assert start is not None and goal is not None
    frames = roadmap.route(start.id, goal.id)
    assert frames is not None
    sim.world.follow_path([tuple(f) for f in frames])  # type: ignore[misc]
    assert sim.until_idle()
    _reached(sim, tuple(goal.frame))  # type: ignore[arg-type]
    for via in ("Corridor_04", "Corridor_06"):
        f = roadmap.find(via)
        assert f is not None
        assert min(math.hypot(x - f.frame.x, y - f.frame.y) for x, y, _ in sim.trace) < 80.0


def test_end_turn_and_position_stabilization_off(office: MapGeometry) -> None:
    sim = make_sim(office, CORRIDOR_WEST, EndTurnEnabled=False)
    sim.world.move_to((8500.0, 10000.0, math.pi / 2))
    assert sim.until_idle()
    _reached(sim, (8500.0, 10000.0, math.pi / 2))
    assert sim.trace[-60][2] > 0.5  # arrived turning along a curve, not on the spot at the end
    loose = make_sim(OPEN, (2000.0, 10000.0, 0.0), PositionStabilizationEnabled=False)
    loose.world.move_to((8000.0, 10000.0, 0.0))
    assert loose.until_idle(60.0)
    assert within(loose.world, (8000.0, 10000.0, 0.0), 100.0, 3.0)


def test_replay_reproduces_a_recorded_trajectory() -> None:
    sim = make_sim(OPEN, (5000.0, 10000.0, 0.0))
    assert sim.world.event(1, sim.now) == "post-process recording started"
    for k in range(40):  # a wiggly joystick drive, 8 s
        sim.world.command_velocity(400.0, 0.5 * math.sin(k / 5), sim.now, kind="joy")
        sim.run(0.2)
    sim.world.event(2, sim.now)
    recorded = np.array(sim.world.motion.recorder.samples)
    truth = sim.trace[-len(recorded) :]
    sim.run(2.0)
    sim.world.move_to((3000.0, 12000.0, 1.0))  # somewhere else
    assert sim.until_idle(60.0)
    assert sim.world.event(3, sim.now).startswith("post-process replay started")
    sim.trace.clear()
    assert sim.until_idle(90.0) and "replay finished" in sim.events
    replayed = np.array(sim.trace)[:, :2]
    err = [float(np.min(np.hypot(replayed[:, 0] - x, replayed[:, 1] - y))) for x, y, _ in truth[::10]]
    assert max(err) < 60.0
    assert math.dist(sim.world.truth[:2], truth[-1][:2]) < 60.0


def test_replay_break_and_continue() -> None:
    sim = make_sim(OPEN, (5000.0, 10000.0, 0.0))
    sim.world.event(1, 0.0)
    for _ in range(10):
        sim.world.command_velocity(400.0, 0.0, sim.now, kind="joy")
        sim.run(0.2)
    sim.world.event(2, sim.now)
    assert sim.world.event(5, sim.now) == "post-process replay: no replay running"
    sim.world.move_to((5000.0, 10000.0, 0.0))
    assert sim.until_idle(60.0)
    sim.world.event(3, sim.now)
    sim.run(1.0)
    assert sim.world.event(5, sim.now) == "post-process replay paused"
    held = sim.world.truth
    sim.run(1.0)
    assert sim.world.truth == held
    sim.world.event(6, sim.now)
    assert sim.until_idle(30.0)
    assert sim.world.truth[0] > 5000 + 500


def test_targets_at_the_int_limits_are_driven_towards_with_a_bounded_path() -> None:
    """E-MOT-014: a target 2147 km away (MOVE_ABS/MOVE_PATH at the INT limits, what a fuzzer sends) gets a
    path of at most MAX_SAMPLES samples; the platform heads for it and the status path stays bounded."""
    far = (2147483647.0, -2147483648.0, 0.0)
    sim = make_sim(OPEN, (10000.0, 10000.0, 0.0), PlanningEnabled=False)
    sim.world.move_to(far)
    sim.run(2.0)
    assert sim.world.active and sim.world.truth[0] > 10500.0  # along its heading: the Bezier leaves forwards
    assert 1000 < len(sim.world.remaining_path()) <= MAX_SAMPLES * DS / 100.0 + 2
    path = make_sim(OPEN, (10000.0, 10000.0, 0.0), PlanningEnabled=False)
    path.world.follow_path([(10000.0, 12000.0, 0.0), far, (-2147483648.0, 2147483647.0, 0.0), (10000.0, 8000.0, 0.0)])
    path.run(4.0)  # a start turn of ~3 s on the spot to face north, then away
    assert path.world.active and path.world.truth[1] > 10200.0  # towards the first frame
    assert len(path.world.remaining_path()) <= MAX_SAMPLES * DS / 100.0 + 10


# Issue 22: a target within TargetReachedTolPos / TargetReachedTolAngle of the pose is reached where the platform
# stands (E-PAR-021, E-MOT-015); before, the planner's 2 mm leg turned the platform round to drive it.
NEAR_POSE = (3502.0, 10500.0, math.radians(45.8))
NEAR_GOAL = (3500.0, 10500.0, math.radians(45.0))


def _swing(sim: Sim, start: tuple[float, float, float]) -> tuple[float, float]:
    """The farthest the true pose got from ``start``: (mm, degrees)."""
    pts = np.asarray(sim.trace)
    turn = np.abs((pts[:, 2] - start[2] + np.pi) % (2 * np.pi) - np.pi)
    return float(np.hypot(pts[:, 0] - start[0], pts[:, 1] - start[1]).max()), float(np.degrees(turn.max()))


@pytest.mark.parametrize("planning", [True, False])
def test_a_target_within_the_tolerances_does_not_move_the_platform(office: MapGeometry, planning: bool) -> None:
    sim = make_sim(office, NEAR_POSE, PlanningEnabled=planning)
    sim.world.move_to(NEAR_GOAL)
    assert sim.until_idle(5.0)
    assert sim.world.target_reached, sim.events[-3:]
    moved, turned = _swing(sim, NEAR_POSE)
    assert moved < 1.0 and turned < 0.1, (moved, turned)
    assert sim.now <= 0.1  # decided in the first control periods
    assert sim.world.motion.planner_state is PlannerState.STANDBY


@pytest.mark.parametrize("planning", [True, False])
def test_a_target_within_the_position_tolerance_only_turns_on_the_spot(office: MapGeometry, planning: bool) -> None:
    goal = (3500.0, 10500.0, math.radians(120.0))
    sim = make_sim(office, NEAR_POSE, PlanningEnabled=planning)
    sim.world.move_to(goal)
    assert sim.until_idle(30.0)
    _reached(sim, goal)
    moved, turned = _swing(sim, NEAR_POSE)
    assert moved < 15.0, moved  # a turn about the wheel axis, no leg driven
    assert turned < 120.0 - 45.8 + 3.0, turned  # the short way round, no swing beyond the goal


def test_move_to_the_station_where_the_platform_stands_does_not_move_it(office: MapGeometry) -> None:
    roadmap = Roadmap(validate_document(DocumentKind.ROADMAP, OFFICE_ROADMAP.read_bytes()))
    sim = make_sim(office, (5001.0, 10001.0, math.radians(0.5)))
    frames = roadmap.route(roadmap.nearest(5001.0, 10001.0).id, roadmap.find("Corridor_01").id)  # type: ignore[union-attr]
    assert frames is not None
    sim.world.command_path([(f.x, f.y, f.angle) for f in frames])
    assert sim.until_idle(5.0)
    assert sim.world.target_reached
    assert _swing(sim, (5001.0, 10001.0, math.radians(0.5)))[0] < 1.0
