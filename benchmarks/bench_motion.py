"""Motion benchmarks (issue 5): real-time factor, planning, wall corners, one laser scan; baselines side by side.

Benchmarks:
- ``motion.realtime_factor``: simulated seconds per wall second of one platform on the office map driving a tour
  of MOVE_ABS targets with planning: laser at 10 Hz, control at 50 Hz. Subjects: the world alone (ideal wheels),
  the world with the CAN boards on (fake_hardware: the motor boards drive the wheels, their encoder frames feed
  the odometry, the S300 streams over ``sim://`` at 10 Hz, the ultrasonic board measures), and the CAN boards
  alone on fixed sources (what the hardware costs by itself). The world with the boards is the server's own
  ``Platform`` with ``hardware_link`` ticking (``world_can_run``). Building, booting and connecting are not timed.
  Target >= 50x.
- ``motion.planning``: time per query on a 50 x 50 m maze of 340 walls (36 rooms, doors, stubs: ``maze``): the
  visibility-graph planner (``pltf.reference_server.world.planner``; its lookup data built once per map, reported as
  its own row) against a plain grid A* at 5 cm (``grid_astar``, 8-connected, octile heuristic, occupancy inflated
  by the same radius with a distance transform). Target: p95 <= 50 ms. Both subjects answer the same queries (the
  grid only the first eight: it takes up to seconds each; a row compares both on exactly those).
- ``motion.corners``: the wall corners of a ~2800-wall map (``World.set_map`` computes them when the laser first
  looks): ``geometry._corners`` (vectorised) against the endpoint-by-endpoint loop it replaced (``corners_by_loop``,
  benchmarks/corners_loop.py, the tests' oracle). The same corners, asserted.
- ``motion.scan``: one 541-beam scan against 200 random wall segments: ``raycast.cast_fan`` (C loops; its numpy
  fallback beside) against pymunk's own ``Space.segment_query_first`` per beam (the same segments as static
  shapes). Target <= 0.5 ms.
"""

from __future__ import annotations

import gc
import heapq
import itertools
import math
import random
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import pymunk
from scipy import ndimage  # type: ignore[import-untyped]

from benchmarks.harness import Config, Row, Target, benchmark, make_row, median_times
from pltf.reference_server.world import MapGeometry, World
from pltf.reference_server.world.geometry import F64, _corners, circles, clearance, segments
from pltf.reference_server.world.planner import Planner, PlannerState
from pltf.reference_server.world.raycast import Scene, cast_fan, cast_fan_numpy
from pltf.reference_server.world.sensors import LASER_FAN
from pltf.spec.documents import DocumentKind, validate_document
from pltf.spec.parameters import ParameterStore

DT = 0.02
RTF_TARGET = 50.0
PLAN_P95_TARGET = 0.050  # s
SCAN_TARGET = 0.0005  # s
MAZE_SIZE = 50000.0
GRID_CELL = 50.0  # mm
PLAN_RADIUS = 503.0 + 60.0  # the default footprint's circumscribed radius + the planning margin (E-MOT-006)

WORLD = "world (ideal wheels)"
WORLD_CAN = "platform: world + CAN boards"
HARDWARE = "CAN boards alone"
VISIBILITY = "visibility graph"
GRID = "grid A* 5 cm"
LOOKUP = "visibility graph lookup data"
OURS_SCAN = "raycast.cast_fan (C loops)"
NUMPY_SCAN = "raycast.cast_fan_numpy"
VECTOR_CORNERS = "geometry._corners (numpy, k-d tree)"
LOOP_CORNERS = "endpoint loop (before)"
PYMUNK_SCAN = "pymunk segment_query_first"
TOUR = [(27500.0, 7800.0, -math.pi / 2), (5000.0, 12200.0, math.pi / 2), (31200.0, 10000.0, 0.0)]


# ---------------------------------------------------------------------------------------------- (a) real time


def office() -> MapGeometry:
    from pathlib import Path

    data = (Path(__file__).resolve().parents[1] / "fixtures" / "maps" / "office.map").read_bytes()
    return MapGeometry.from_tree(validate_document(DocumentKind.MAP, data))


def _tour_world(seed: int = 1) -> World:
    world = World(ParameterStore().get, random.Random(seed), (1000.0, 10000.0, 0.0))
    world.set_map(office())
    world.planner()  # the map's lookup data, built once per map (motion.planning times it), not per period
    return world


Run = Callable[[], float]  # one timed run: the distance driven (mm)


def world_run(seconds: float) -> Run:
    """The tour with ideal wheels for ``seconds`` of simulated time, built (world, map, parameters) untimed."""
    world = _tour_world()

    def run() -> float:
        driven, goal = 0.0, 0
        for k in range(1, round(seconds / DT) + 1):
            if not world.active:
                world.move_to(TOUR[goal % len(TOUR)])
                goal += 1
            world.advance(k * DT, DT)
            driven += abs(world.measured[0]) * DT
        return driven

    return run


def world_can_run(seconds: float) -> Run:
    """The same tour driven through the platform as ``pltf serve`` runs it: a ``Platform`` with the world
    (``world.model.factory``) and the fake hardware (``hardware_link.factory``: seven CAN boards on a virtual bus,
    the S300 on ``sim://``), its control period ``Platform.tick`` (world step, setpoints to the motor boards over
    CAN, the boards' step, the body moved by the motors' wheel velocities, odometry from the encoder frames);
    MOVE_ABS telegrams through ``Platform.handle``. Untimed: the data dir, boot, CONNECT/INIT (the self test),
    START_ULTRASONIC on all 16 channels, the serial laser at 10 Hz, mode AUTOMATIC, START."""
    import tempfile
    from pathlib import Path

    from pltf.reference_server import hardware_link
    from pltf.reference_server.enums import MotionMode
    from pltf.reference_server.platform import Platform
    from pltf.reference_server.storage import Storage
    from pltf.reference_server.world.model import factory
    from pltf.spec.codec import REQUESTS

    r: Any = REQUESTS
    tmp = tempfile.TemporaryDirectory()
    storage = Storage(Path(tmp.name))
    storage.seed_from_fixtures()
    p = Platform(storage, seed=1, motion=factory(1), hardware=hardware_link.factory())
    p.boot(0.0)
    for t in (r.CMD_CONNECT_TO_PLTF(), r.CMD_INIT_PLTF(), r.CMD_START_ULTRASONIC(active_channels=0xFFFF)):
        assert p.handle(t, 0.0).refused is None, t
    k = 0
    while p.chart.state.name != "READY" and k < 100:  # the self test ends after a few periods
        k += 1
        p.tick(k * DT)
    assert p.hardware is not None and p.hardware.hw.scanner is not None
    p.hardware.hw.scanner.period = 0.1  # the laser at 10 Hz
    for t in (r.CMD_SET_MODE(mode=MotionMode.MODE_MOTION_AUTOMATIC), r.CMD_START()):
        p.handle(t, k * DT)
    assert p.chart.state.name == "RUNNING", p.chart.state
    assert isinstance(p.motion, World)
    p.motion.planner()  # as in ``_tour_world``
    first = k

    def run() -> float:
        try:
            driven, goal = 0.0, 0
            for k in range(first + 1, first + round(seconds / DT) + 1):
                now = k * DT
                if not p.motion.active:
                    x, y, a = TOUR[goal % len(TOUR)]
                    p.handle(r.CMD_MOVE_ABS(x=round(x), y=round(y), angle=round(math.degrees(a) * 1000)), now)
                    goal += 1
                p.tick(now)
                driven += abs(p.motion.v) * DT
            return driven
        finally:
            p.close()
            tmp.cleanup()

    return run


def hardware_run(seconds: float) -> Run:
    """The CAN boards and the S300 alone, as ``world_can_run`` drives them but fed by fixed sources (a constant
    scan and ultrasonic echo, wheels rolling as driven): the share of a period the hardware takes by itself."""
    from pltf.fake_hardware.hardware import build_platform_hardware

    scan = [5000.0] * LASER_FAN.count
    echoes: list[float | None] = [2000.0] * 16
    hw = build_platform_hardware(
        params=ParameterStore().get, rng=random.Random(1), scan_source=lambda now: scan, us_source=lambda now: echoes
    )
    assert hw.connect(0.0).ok and hw.init(0.0).ok
    if hw.scanner is not None:
        hw.scanner.period = 0.1
    hw.controller.start_ultrasonic(0xFFFF, 0.0)
    right, left = hw.motors
    assert right is not None and left is not None

    def run() -> float:
        try:
            driven = 0.0
            for k in range(1, round(seconds / DT) + 1):
                hw.controller.set_wheel_velocities(300.0, 300.0)
                hw.step(k * DT)
                right.report_wheel_travel(right.wheel_velocity * DT)
                left.report_wheel_travel(left.wheel_velocity * DT)
                driven += sum(hw.controller.take_wheel_travel()) / 2.0
            return driven
        finally:
            hw.close()

    return run


def run_world(seconds: float) -> float:
    return world_run(seconds)()


def run_world_can(seconds: float) -> float:
    return world_can_run(seconds)()


def timed_runs(builders: dict[str, Callable[[], Run]], repeats: int) -> dict[str, float]:
    """Median wall seconds of each subject's run, the subjects interleaved, each built afresh and untimed, its
    start-up heap frozen out of the collector's way as the server's is."""
    samples: dict[str, list[float]] = {name: [] for name in builders}
    for _ in range(repeats):
        for name, build in builders.items():
            run = build()
            gc.collect()
            gc.freeze()  # as ``pltf serve`` does once it has built its platform (reference_server/cli.py)
            try:
                t = time.perf_counter()
                run()
                samples[name].append(time.perf_counter() - t)
            finally:
                gc.unfreeze()
    return {name: statistics.median(times) for name, times in samples.items()}


@benchmark()
def realtime_factor(config: Config) -> list[Row]:
    """Simulated seconds per wall second: the world alone, and with the CAN boards and the S300 in the loop."""
    seconds = 5.0 if config.quick else 60.0
    builders = {
        WORLD: lambda: world_run(seconds),
        WORLD_CAN: lambda: world_can_run(seconds),
        HARDWARE: lambda: hardware_run(seconds),
    }
    times = timed_runs(builders, min(config.repeats, 5))
    rtf = {name: seconds / t for name, t in times.items()}
    target = Target("value", ">=", RTF_TARGET)
    return [
        make_row(
            "motion.realtime_factor",
            WORLD,
            "realtime_factor",
            rtf[WORLD],
            "sim-s/s",
            higher_is_better=True,
            target=target,
        ),
        make_row(
            "motion.realtime_factor",
            WORLD_CAN,
            "realtime_factor",
            rtf[WORLD_CAN],
            "sim-s/s",
            higher_is_better=True,
            baseline_subject=WORLD,
            baseline_value=rtf[WORLD],
            target=target,
        ),
        make_row(
            "motion.realtime_factor",
            HARDWARE,
            "realtime_factor",
            rtf[HARDWARE],
            "sim-s/s",
            higher_is_better=True,
            baseline_subject=WORLD_CAN,
            baseline_value=rtf[WORLD_CAN],
        ),
    ]


# ---------------------------------------------------------------------------------------------- (b) planning


def maze(seed: int = 7, size: float = MAZE_SIZE, rooms: int = 6, door: float = 1400.0, stubs: int = 6) -> F64:
    """A size x size hall of rooms x rooms rooms, a door in every inner wall, wall stubs inside: 340 segments."""
    rng = random.Random(seed)
    cell = size / rooms
    segs = [(0.0, 0.0, size, 0.0), (size, 0.0, size, size), (size, size, 0.0, size), (0.0, size, 0.0, 0.0)]
    for k in range(1, rooms):
        for m in range(rooms):
            for vertical in (True, False):
                a, b = m * cell, (m + 1) * cell
                c = rng.uniform(a + 1500, b - 1500 - door)
                if vertical:
                    segs += [(k * cell, a, k * cell, c), (k * cell, c + door, k * cell, b)]
                else:
                    segs += [(a, k * cell, c, k * cell), (c + door, k * cell, b, k * cell)]
    for i in range(rooms):
        for j in range(rooms):
            for _ in range(stubs):
                x0 = i * cell + rng.uniform(2000, cell - 2000)
                y0 = j * cell + rng.uniform(2000, cell - 2000)
                a = rng.choice([0.0, math.pi / 2])
                length = rng.uniform(1000, 3000)
                segs.append((x0, y0, x0 + length * math.cos(a), y0 + length * math.sin(a)))
    return segments(segs)


def queries(walls: F64, n: int, radius: float, seed: int = 3) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """``n`` start/goal pairs in free space (100 mm more than ``radius`` from every wall)."""
    rng = random.Random(seed)
    out: list[tuple[tuple[float, float], tuple[float, float]]] = []
    while len(out) < n:
        pts = np.array([[rng.uniform(1000, MAZE_SIZE - 1000) for _ in range(2)] for _ in range(2)])
        if (clearance(pts[:, 0], pts[:, 1], walls, circles([])) >= radius + 100).all():
            out.append(((float(pts[0, 0]), float(pts[0, 1])), (float(pts[1, 0]), float(pts[1, 1]))))
    return out


def occupancy(walls: F64, size: float, cell: float, radius: float) -> np.ndarray:
    """Free cells of a grid: farther than ``radius`` (plus one cell for the rasterisation) from every wall."""
    n = round(size / cell) + 1
    occ = np.zeros((n, n), dtype=bool)
    for x0, y0, x1, y1 in walls:
        k = max(2, int(math.hypot(x1 - x0, y1 - y0) / (cell / 2)) + 1)
        xs = np.clip(np.rint(np.linspace(x0, x1, k) / cell).astype(int), 0, n - 1)
        ys = np.clip(np.rint(np.linspace(y0, y1, k) / cell).astype(int), 0, n - 1)
        occ[ys, xs] = True
    return np.asarray(ndimage.distance_transform_edt(~occ) * cell >= radius + cell)


def grid_astar(free: np.ndarray, cell: float, start: tuple[float, float], goal: tuple[float, float]) -> float | None:
    """Plain 8-connected A* on the grid (octile heuristic); the path length in mm, None if there is none."""
    n = free.shape[1]
    fr = free.ravel().tolist()
    s = round(start[1] / cell) * n + round(start[0] / cell)
    g = round(goal[1] / cell) * n + round(goal[0] / cell)
    if not fr[s] or not fr[g]:
        return None
    gx, gy = g % n, g // n
    d2 = math.sqrt(2.0)
    steps = [(1, 1.0), (-1, 1.0), (n, 1.0), (-n, 1.0), (n + 1, d2), (n - 1, d2), (-n + 1, d2), (-n - 1, d2)]
    cost = {s: 0.0}
    heap = [(0.0, s)]
    closed = set()
    while heap:
        _, u = heapq.heappop(heap)
        if u == g:
            return cost[u] * cell
        if u in closed:
            continue
        closed.add(u)
        cu = cost[u]
        for off, w in steps:
            v = u + off
            if not fr[v] or v in closed:
                continue
            c = cu + w
            if c < cost.get(v, math.inf):
                cost[v] = c
                dx, dy = abs(v % n - gx), abs(v // n - gy)
                heapq.heappush(heap, (c + max(dx, dy) + (d2 - 1.0) * min(dx, dy), v))
    return None


def path_length(points: tuple[tuple[float, float], ...]) -> float:
    return sum(math.dist(a, b) for a, b in itertools.pairwise(points))


def _p95(times: list[float]) -> float:
    return float(np.percentile(times, 95))


@benchmark()
def planning(config: Config) -> list[Row]:
    """Planning time per query on a 50 x 50 m maze: visibility graph vs plain grid A* at 5 cm."""
    walls = maze()
    geometry = MapGeometry(walls=walls)
    t0 = time.perf_counter()
    planner = Planner(geometry, PLAN_RADIUS)
    build = time.perf_counter() - t0
    pairs = queries(walls, 10 if config.quick else 100, PLAN_RADIUS)
    ours = []
    for start, goal in pairs:
        best = math.inf
        for _ in range(1 if config.quick else 3):
            t = time.perf_counter()
            plan = planner.plan(start, goal)
            best = min(best, time.perf_counter() - t)
        assert plan.state is PlannerState.PATH_FOUND, (start, goal, plan.state)
        ours.append(best)
    free = occupancy(walls, MAZE_SIZE, GRID_CELL, PLAN_RADIUS)
    grid, longer = [], []
    n_grid = 1 if config.quick else 8
    for start, goal in pairs[:n_grid]:
        t = time.perf_counter()
        length = grid_astar(free, GRID_CELL, start, goal)
        grid.append(time.perf_counter() - t)
        if length is not None:
            longer.append(length / path_length(planner.plan(start, goal).points))
    target = Target("value", "<=", PLAN_P95_TARGET)
    rows = [
        make_row(
            "motion.planning",
            VISIBILITY,
            "p95_query_time",
            _p95(ours),
            "s",
            higher_is_better=False,
            baseline_subject=GRID,
            baseline_value=_p95(grid),
            target=target,
        ),
        make_row(
            "motion.planning",
            VISIBILITY,
            "median_query_time",
            statistics.median(ours),
            "s",
            higher_is_better=False,
            baseline_subject=GRID,
            baseline_value=statistics.median(grid),
        ),
        make_row(
            "motion.planning",
            VISIBILITY,
            "median_query_time_grid_queries",
            statistics.median(ours[:n_grid]),
            "s",
            higher_is_better=False,
            baseline_subject=GRID,
            baseline_value=statistics.median(grid),
        ),
        make_row("motion.planning", GRID, "p95_query_time", _p95(grid), "s", higher_is_better=False),
        make_row("motion.planning", GRID, "median_query_time", statistics.median(grid), "s", higher_is_better=False),
        make_row("motion.planning", LOOKUP, "build_time", build, "s", higher_is_better=False),
    ]
    if longer:
        rows.append(
            make_row(
                "motion.planning",
                GRID,
                "path_length_vs_visibility",
                statistics.median(longer),
                "x",
                higher_is_better=False,
            )
        )
    return rows


# ---------------------------------------------------------------------------------------------- corners


@benchmark()
def corners(config: Config) -> list[Row]:
    """Wall corners of a big map: vectorised vs the O(n^2) loop."""
    from benchmarks.corners_loop import corners_by_loop

    walls = maze(size=50000.0, rooms=5) if config.quick else maze(size=170000.0, rooms=17, stubs=6)
    if not np.array_equal(_corners(walls), corners_by_loop(walls)):
        raise AssertionError("the vectorised corners differ from the loop's")
    times = median_times(
        {VECTOR_CORNERS: lambda: _corners(walls), LOOP_CORNERS: lambda: corners_by_loop(walls)},
        Config(config.quick, min(config.repeats, 3), 0.0),
        number=1,
    )
    return [
        make_row(
            "motion.corners",
            VECTOR_CORNERS,
            f"time_{len(walls)}_walls",
            times[VECTOR_CORNERS],
            "s",
            higher_is_better=False,
            baseline_subject=LOOP_CORNERS,
            baseline_value=times[LOOP_CORNERS],
        ),
        make_row(
            "motion.corners", LOOP_CORNERS, f"time_{len(walls)}_walls", times[LOOP_CORNERS], "s", higher_is_better=False
        ),
    ]


# ---------------------------------------------------------------------------------------------- (c) one scan


def scan_scene(seed: int = 1, n: int = 200) -> F64:
    rng = np.random.default_rng(seed)
    c = rng.uniform(0, 50000, (n, 2))
    a = rng.uniform(0, math.pi, n)
    half = rng.uniform(500, 5000, n) / 2
    return np.column_stack(
        [c[:, 0] - half * np.cos(a), c[:, 1] - half * np.sin(a), c[:, 0] + half * np.cos(a), c[:, 1] + half * np.sin(a)]
    )


def pymunk_scan(space: pymunk.Space, x: float, y: float, heading: float) -> list[float]:
    """The baseline: one ``segment_query_first`` per beam."""
    out = []
    flt = pymunk.ShapeFilter()
    r = LASER_FAN.max_range
    for i in range(LASER_FAN.count):
        a = heading + LASER_FAN.start + i * LASER_FAN.step
        hit = space.segment_query_first((x, y), (x + r * math.cos(a), y + r * math.sin(a)), 0.0, flt)
        out.append(math.inf if hit is None else hit.alpha * r)
    return out


@benchmark()
def scan(config: Config) -> list[Row]:
    """One 541-beam scan against 200 segments: the fan caster (C loops; numpy, its fallback) vs pymunk."""
    segs = scan_scene()
    scene = Scene.make(segs)
    space = pymunk.Space()
    space.add(*[pymunk.Segment(space.static_body, (s[0], s[1]), (s[2], s[3]), 0.0) for s in segs])
    pose = (25000.0, 25000.0, 0.3)
    ours = cast_fan(*pose, scene, LASER_FAN)[0]
    theirs = np.asarray(pymunk_scan(space, *pose))
    if not np.allclose(np.nan_to_num(ours, posinf=-1), np.nan_to_num(theirs, posinf=-1), atol=0.01):
        raise AssertionError("the two ray casters disagree")
    times = median_times(
        {
            OURS_SCAN: lambda: cast_fan(*pose, scene, LASER_FAN),
            NUMPY_SCAN: lambda: cast_fan_numpy(*pose, scene, LASER_FAN),
            PYMUNK_SCAN: lambda: pymunk_scan(space, *pose),
        },
        config,
    )
    target = Target("value", "<=", SCAN_TARGET)
    return [
        make_row(
            "motion.scan",
            OURS_SCAN,
            "scan_time",
            times[OURS_SCAN],
            "s",
            higher_is_better=False,
            baseline_subject=PYMUNK_SCAN,
            baseline_value=times[PYMUNK_SCAN],
            target=target,
        ),
        make_row(
            "motion.scan",
            NUMPY_SCAN,
            "scan_time",
            times[NUMPY_SCAN],
            "s",
            higher_is_better=False,
            baseline_subject=PYMUNK_SCAN,
            baseline_value=times[PYMUNK_SCAN],
        ),
        make_row("motion.scan", PYMUNK_SCAN, "scan_time", times[PYMUNK_SCAN], "s", higher_is_better=False),
    ]
