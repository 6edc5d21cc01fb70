"""The visibility-graph planner: shortest, never through walls, complete against a grid, and its planner states."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from benchmarks.bench_motion import grid_astar, maze, occupancy, path_length, queries
from pltf.reference_server.world import MapGeometry, PlannerState
from pltf.reference_server.world.geometry import circles, segments, segments_clear
from pltf.reference_server.world.planner import Planner
from tests.reference_server.world.conftest import geometry_of, make_sim, room

R = 563.0  # the default footprint's circumscribed radius + margin

# a 10 x 10 m room split by a wall from the floor up to 8 m: the way from left to right leads over the top
SPLIT = [*room(10000, 10000), (5000, 0, 5000, 8000)]


def _assert_keeps_radius(geometry: MapGeometry, points: tuple[tuple[float, float], ...], radius: float) -> None:
    q = np.array([[*a, *b] for a, b in itertools.pairwise(points)])
    walls = np.vstack([geometry.obstacles, geometry.constraint_edges()])
    assert segments_clear(q, walls, geometry.circles, radius * 0.999).all()


def test_the_path_goes_around_the_wall_and_is_shortest() -> None:
    g = geometry_of(SPLIT)
    plan = Planner(g, R).plan((2000.0, 2000.0), (8000.0, 2000.0))
    assert plan.state is PlannerState.PATH_FOUND
    assert plan.points[0] == (2000.0, 2000.0) and plan.points[-1] == (8000.0, 2000.0)
    assert max(y for _, y in plan.points) > 8000  # over the top of the wall
    _assert_keeps_radius(g, plan.points, R)
    free = occupancy(segments(SPLIT), 10000, 50.0, R)
    grid = grid_astar(free, 50.0, (2000.0, 2000.0), (8000.0, 2000.0))
    assert grid is not None
    assert grid / 1.09 < path_length(plan.points) <= grid  # the grid's 8 directions make it up to 8 % longer


def test_a_free_line_is_the_path() -> None:
    plan = Planner(geometry_of(room(10000, 10000)), R).plan((2000.0, 2000.0), (8000.0, 7000.0))
    assert plan.points == ((2000.0, 2000.0), (8000.0, 7000.0))


def test_no_path_into_a_closed_room() -> None:
    g = geometry_of(
        [*room(20000, 10000), *[(s[0] + 12000, s[1] + 2000, s[2] + 12000, s[3] + 2000) for s in room(4000, 4000)]]
    )
    assert Planner(g, R).plan((3000.0, 5000.0), (14000.0, 4000.0)).state is PlannerState.NO_PATH


def test_prohibited_areas_and_the_workarea_are_respected() -> None:
    walls = segments(room(12000, 8000))
    prohibited = (np.array([[5000.0, 0.0], [7000.0, 0.0], [7000.0, 5000.0], [5000.0, 5000.0]]),)
    workarea = (np.array([[0.0, 0.0], [12000.0, 0.0], [12000.0, 7000.0], [0.0, 7000.0]]),)
    g = MapGeometry(walls=walls, prohibited=prohibited, workareas=workarea)
    pl = Planner(g, R)
    plan = pl.plan((2000.0, 2000.0), (10000.0, 2000.0))
    assert plan.state is PlannerState.PATH_FOUND
    _assert_keeps_radius(g, plan.points, R)  # around the prohibited block, below the workarea's top at 7 m
    assert 5000 + R - 1 < max(y for _, y in plan.points) <= 7000 - R + 1
    assert pl.plan((2000.0, 2000.0), (6000.0, 3000.0)).state is PlannerState.COLLISION_TARGET
    assert pl.plan((2000.0, 2000.0), (6000.0, 7500.0)).state is PlannerState.COLLISION_TARGET  # outside
    assert pl.plan((6000.0, 3000.0), (2000.0, 2000.0)).state is PlannerState.COLLISION_START


def test_obstacles_seen_on_the_way_are_planned_around() -> None:
    g = geometry_of(room(12000, 6000))
    pl = Planner(g, R)
    blocked = circles([(6000.0, 3000.0, 300.0)])
    plan = pl.plan((2000.0, 3000.0), (10000.0, 3000.0), obstacles=blocked)
    assert plan.state is PlannerState.PATH_FOUND and len(plan.points) > 2
    q = np.array([[*a, *b] for a, b in zip(plan.points, plan.points[1:], strict=False)])
    assert segments_clear(q, segments([]), blocked, R * 0.999).all()
    wall = circles([(6000.0, y, 300.0) for y in range(0, 6001, 500)])
    assert pl.plan((2000.0, 3000.0), (10000.0, 3000.0), obstacles=wall).state is PlannerState.NO_PATH


def test_the_world_checks_the_real_footprint_at_start_and_target(office: MapGeometry) -> None:
    w = make_sim(office, (1000.0, 10000.0, 0.0)).world
    none = circles([])
    assert w.plan((1000.0, 10000.0, 0.0), (3000.0, 11200.0, 0.0), none).state is PlannerState.COLLISION_TARGET
    assert w.plan((300.0, 10000.0, 0.0), (5000.0, 10000.0, 0.0), none).state is PlannerState.COLLISION_START
    # close to a wall (inside the planning radius) but the real footprint is free: it plans with its clearance
    near = (1000.0, 8800.0 + 350.0, 0.0)
    assert w.plan(near, (5000.0, 10000.0, 0.0), none).state is PlannerState.PATH_FOUND
    assert w.plan((1000.0, 10000.0, 0.0), near, none).state is PlannerState.PATH_FOUND


def test_complete_and_shortest_against_the_grid_on_a_maze() -> None:
    walls = maze()
    pl = Planner(MapGeometry(walls=walls), R)
    free = occupancy(walls, 50000.0, 100.0, R)
    for start, goal in queries(walls, 4, R, seed=5):
        plan = pl.plan(start, goal)
        grid = grid_astar(free, 100.0, start, goal)
        assert plan.state is PlannerState.PATH_FOUND
        _assert_keeps_radius(pl.geometry, plan.points, R)
        if grid is not None:
            assert path_length(plan.points) <= grid * 1.01
        assert math.isfinite(path_length(plan.points))


@pytest.mark.slow
def test_many_maze_queries_find_paths_wherever_the_grid_does() -> None:
    walls = maze(seed=11)
    pl = Planner(MapGeometry(walls=walls), R)
    free = occupancy(walls, 50000.0, 50.0, R)
    for start, goal in queries(walls, 30, R, seed=9):
        grid = grid_astar(free, 50.0, start, goal)
        plan = pl.plan(start, goal)
        assert (grid is None) or plan.state is PlannerState.PATH_FOUND


def test_equal_maps_share_one_planner_and_plan_alike() -> None:
    """A fleet's platforms each parse the same map: they get one planner (one visibility graph), which plans
    what a planner of their own would; another map, area or radius gets its own."""
    first, second = geometry_of(SPLIT), geometry_of(SPLIT)
    assert first is not second
    shared = Planner.shared(first, R)
    assert Planner.shared(second, R) is shared
    start, goal = (2000.0, 2000.0), (8000.0, 2000.0)
    assert shared.plan(start, goal) == Planner(second, R).plan(start, goal)
    assert Planner.shared(first, R + 1.0) is not shared
    assert Planner.shared(geometry_of([*SPLIT, (1000.0, 9000.0, 2000.0, 9000.0)]), R) is not shared
    area = (np.array([[0.0, 0.0], [10000.0, 0.0], [10000.0, 9000.0], [0.0, 9000.0]]),)
    fenced = MapGeometry(walls=first.walls, aux=first.aux, workareas=area)
    assert Planner.shared(fenced, R) is not shared
