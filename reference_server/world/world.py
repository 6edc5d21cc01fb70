"""One simulated platform in its world: physics, sensors, localization and motion, stepped in simulated time.

Rules:
- Sans-IO: every entry point takes ``now`` / ``dt``; randomness comes from the ``random.Random`` given at
  construction (a numpy generator seeded from it draws the sensor noise), so the same seed and the same
  commands give the same trajectory, bit for bit.
- A control period is three calls (reference_server.motion_api): ``step(now, dt)`` senses when due
  (laser and ultrasonic every ``SCAN_PERIOD``) and lets the motion modes set ``setpoints`` (wheel surface
  velocities); ``move(right, left, dt)`` drives the body with the wheels' velocities (the setpoints, or what
  the motor boards report) and returns how far each wheel rolled (for ``report_wheel_travel``, with seeded
  scale error and noise); ``odometry(right, left, dt)`` takes the encoders' travel. ``advance`` does all
  three with ideal wheels. ``scan(pose)`` and ``ultrasonic(pose)`` are the range callbacks of the serial
  scanner and the ultrasonic board.
- Parameters are read through ``self.params`` on every use (a CMD_SET_PLTF_PARAM acts at once; geometry
  changes rebuild the footprint and the planner).
- The world keeps the TRUE pose (``truth``); everything the platform reports or decides on uses the
  ESTIMATE (``loc``). ``kidnap`` moves the truth only.
- In a fleet (``attach``) the other platforms are bodies too (reference_server/world/neighbours.py): the
  physics stops at them, and every sensing period the laser and the ultrasonic ring cast against the map's scene
  plus their outlines within ``NEIGHBOUR_RANGE`` (``sensed``, the scene the last scan's hit ids index).
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from pltf.reference_server.world import sensors
from pltf.reference_server.world.automatic import AutoJob, Perception
from pltf.reference_server.world.geometry import (
    BOOL,
    F64,
    MapGeometry,
    circles,
    clearance,
    inside_polygon,
    point_segment_distance,
    polygon_edges,
    segments,
    segments_clear,
)
from pltf.reference_server.world.localization import Localization
from pltf.reference_server.world.motion import Motion
from pltf.reference_server.world.neighbours import Neighbours
from pltf.reference_server.world.physics import Footprint, Physics
from pltf.reference_server.world.planner import Plan, Planner, PlannerState
from pltf.reference_server.world.raycast import Scene
from pltf.reference_server.world.replay import ReplayJob

Params = Callable[[str], Any]
Pose = tuple[float, float, float]

SCAN_PERIOD = 0.1  # s: laser and ultrasonic at 10 Hz
PLAN_MARGIN = 60.0  # mm added to the footprint's circumscribed radius for planning (E-MOT-006)
OBSTACLE_MARGIN = 100.0  # mm added to half the platform's width around sensed obstacles (E-MOT-006)
MOUSE_RADIUS = 200.0  # mm: the CMD_MOUSE_MOVE obstacle (E-MOT-003)
ODO_SCALE_SIGMA = 0.002  # per-run wheel scale error (drift)
ODO_NOISE = 0.001  # mm^2 per mm of wheel travel: 1 mm per wheel and metre
GRAVITY = 9.81  # m/s^2
NEIGHBOUR_RANGE = sensors.LASER_FAN.max_range + 1000.0  # mm: other bodies farther away are neither seen nor heard


def _initial_exact() -> F64:
    loc = Localization()
    loc.set_estimate(0.0, 0.0, 0.0, exact=True)
    return loc.cov


class NormalBlock:
    """Standard normal draws of one seeded generator, a block at a time: one numpy call per ``size`` draws
    instead of one per control period (the same stream of values as drawing them two by two)."""

    def __init__(self, gen: np.random.Generator, size: int = 1024) -> None:
        self.gen, self.size = gen, size
        self._buf: list[float] = []
        self._i = 0

    def pair(self) -> tuple[float, float]:
        i = self._i
        if i + 2 > len(self._buf):
            self._buf, i = self.gen.standard_normal(self.size).tolist(), 0
        self._i = i + 2
        return self._buf[i], self._buf[i + 1]


class World:
    def __init__(self, params: Params, rng: random.Random, pose: Pose = (0.0, 0.0, 0.0)) -> None:
        self.params = params
        self.rng = rng
        self.noise = np.random.default_rng(rng.getrandbits(64))  # the laser, drawn in sensing order
        self._us_noise = np.random.default_rng(rng.getrandbits(64))  # ultrasonic: 16 draws every sensing period,
        self._us_eps = np.zeros(sensors.US_SENSORS)  # read or not, so reading it lazily changes nothing else
        self._cb_noise = np.random.default_rng(rng.getrandbits(64))  # the fake hardware's range callbacks
        self.scale = (1.0 + rng.gauss(0.0, ODO_SCALE_SIGMA), 1.0 + rng.gauss(0.0, ODO_SCALE_SIGMA))
        self._odo_noise = NormalBlock(np.random.default_rng(rng.getrandbits(64)))  # the encoders: 2 per period
        self._geom_key = self._geometry_key()
        self.footprint = Footprint.from_params(*self._geom_key)
        self.physics = Physics(self.footprint)
        self.geometry: MapGeometry | None = None
        self._obstacles: dict[object, tuple[float, float, float] | F64] = {}
        self._corners: F64 | None = np.zeros((0, 2))  # None: not computed yet for the active map
        self.map_scene = Scene.make()
        self.scene = Scene.make()
        self.sensed = self.scene  # what the last sensing period cast against: the scene and, in a fleet, the others
        self.neighbours: Neighbours | None = None
        self._planner: Planner | None = None
        self.truth: Pose = pose
        self.loc = Localization(*pose, cov=_initial_exact())
        self.motion = Motion()
        self.contact = False
        self.last_scan: sensors.Scan | None = None
        self._scan_pose: Pose = pose
        self._observation: sensors.Observation | None = None
        self.perception = Perception()
        self._us: tuple[int, list[float]] = (-1, [math.inf] * sensors.US_SENSORS)
        self._next_sense: float | None = None
        self._us_pose: Pose = pose
        self.setpoints: tuple[float, float] = (0.0, 0.0)  # wheel surface velocities, right and left, mm/s
        self.measured: tuple[float, float] = (0.0, 0.0)  # v, w from the odometry of the last period
        self._true_vel: tuple[float, float] = (0.0, 0.0)

    # ---- the map and obstacles
    def set_map(self, geometry: MapGeometry | None) -> None:
        """The active map (None: no map); the physical world and the planner's lookup data are rebuilt."""
        self.geometry = geometry
        self._corners = None if geometry is not None else np.zeros((0, 2))  # computed when first observed
        self._planner = None
        self._rebuild()

    def _wall_corners(self) -> F64:
        """The active map's wall corners (seen by the observations), computed once per map, when first needed:
        a big map is set at once, its corners cost a moment only when the laser first looks."""
        if self._corners is None:
            self._corners = self.geometry.corners() if self.geometry is not None else np.zeros((0, 2))
        return self._corners

    def set_obstacle(self, key: object, shape: tuple[float, float, float] | F64 | None) -> None:
        """Place, move or remove (None) an obstacle: a circle (x, y, r) or an (N, 4) array of wall segments."""
        if shape is None:
            self._obstacles.pop(key, None)
        else:
            self._obstacles[key] = shape if isinstance(shape, tuple) else segments(shape)
        self._rebuild()

    def set_mouse_obstacle(self, xy: tuple[float, float] | None) -> None:
        """guide 6.3 CMD_MOUSE_MOVE: a round obstacle of MOUSE_RADIUS at (x, y), or none."""
        self.set_obstacle("mouse", None if xy is None else (float(xy[0]), float(xy[1]), MOUSE_RADIUS))

    def _rebuild(self) -> None:
        g = self.geometry or MapGeometry()
        extra_c = [s for s in self._obstacles.values() if isinstance(s, tuple)]
        extra_s = [s for s in self._obstacles.values() if not isinstance(s, tuple)]
        self.map_scene = Scene.make(g.obstacles, g.circles)
        segs = np.vstack([g.obstacles, *extra_s])
        circs = np.vstack([g.circles, circles(extra_c)])
        self.scene = Scene.make(segs, circs)
        self.physics.set_map(segs, circs)
        # the last scan's hits index the old scene: its observations are gone until the next scan
        self.last_scan, self._observation, self.sensed = None, None, self.scene

    def attach(self, neighbours: Neighbours) -> None:
        """Share the world with other bodies (a fleet): they block the body and the sensors see them."""
        self.neighbours = self.physics.neighbours = neighbours
        neighbours.set_footprint(self.footprint)
        neighbours.place(*self.truth)

    def _scene_now(self) -> Scene:
        """The scene the sensors cast against now: the map's (with obstacles), plus the other bodies near."""
        if self.neighbours is None:
            return self.scene
        x, y, _ = self.truth
        others = self.neighbours.segments_near(x, y, NEIGHBOUR_RANGE)
        if len(others) == 0:
            return self.scene
        return Scene.make(np.vstack([self.scene.segs, others]), self.scene.circs)

    # ---- geometry parameters
    def _geometry_key(self) -> tuple[float, float, float]:
        p = self.params
        return float(p("PltfLength")), float(p("DistPltfCenterToWheelAxis")), float(p("DistWheels"))

    def _sync_geometry(self) -> None:
        key = self._geometry_key()
        if key != self._geom_key:
            self._geom_key = key
            self.footprint = Footprint.from_params(*key)
            self.physics.set_footprint(self.footprint)
            self._planner = None
            if self.neighbours is not None:
                self.neighbours.set_footprint(self.footprint)

    @property
    def track(self) -> float:
        return float(self.params("DistWheels"))

    # ---- one control period (the order of reference_server.motion_api: step, move, odometry)
    def advance(self, now: float, dt: float) -> list[str]:
        """One period with ideal wheels that follow their setpoints."""
        events = self.step(now, dt)
        self.odometry(*self.move(*self.setpoints, dt), dt)
        return events

    def step(self, now: float, dt: float) -> list[str]:
        """Control: sense when due, then the motion modes decide the wheel setpoints; log lines."""
        self._sync_geometry()
        self.sense(now)
        events = self.motion.step(now, dt, self.estimate, self.perception, self.us_distances, self.params, self)
        half = 0.5 * self.track * self.motion.w
        self.setpoints = (self.motion.v + half, self.motion.v - half)
        return events

    def move(self, right: float, left: float, dt: float) -> tuple[float, float]:
        """Physics: the wheels' velocities (mm/s) drive the body for ``dt`` as far as the world lets it.

        Returns how far each wheel rolled (mm): the body's true motion, with the wheels' seeded scale error
        (drift) and noise - what ideal encoders count.
        """
        v, w = 0.5 * (right + left), (right - left) / self.track
        x0, y0, a0 = self.truth
        x, y, a, self.contact = self.physics.move(x0, y0, a0, v, w, dt)
        self.truth = (float(x), float(y), float((a + math.pi) % (2 * math.pi) - math.pi))
        if self.neighbours is not None:
            self.neighbours.place(*self.truth)
        da = (a - a0 + math.pi) % (2 * math.pi) - math.pi
        mid = a0 + 0.5 * da
        d = (x - x0) * math.cos(mid) + (y - y0) * math.sin(mid)
        self._true_vel = (d / dt, da / dt) if dt > 0 else (0.0, 0.0)
        dr, dl = d + 0.5 * self.track * da, d - 0.5 * self.track * da
        nr, nl = self._odo_noise.pair()
        return (
            dr * self.scale[0] + nr * math.sqrt(ODO_NOISE * abs(dr)),
            dl * self.scale[1] + nl * math.sqrt(ODO_NOISE * abs(dl)),
        )

    def odometry(self, right: float, left: float, dt: float) -> None:
        """Estimation: the measured wheel travel (mm) of the last period."""
        self.loc.predict(right, left, self.track)
        if dt > 0:
            self.measured = (0.5 * (right + left) / dt, (right - left) / self.track / dt)

    def sense(self, now: float, force: bool = False) -> None:
        """Laser, ultrasonic and scan matching, every SCAN_PERIOD of simulated time."""
        if not force and self._next_sense is not None and now < self._next_sense - 1e-9:
            return
        self._next_sense = now + SCAN_PERIOD if self._next_sense is None else max(self._next_sense + SCAN_PERIOD, now)
        self._sync_geometry()
        mount = self.footprint.front
        self.sensed = self._scene_now()
        s = sensors.scan(self.truth, mount, self.sensed, self.noise)
        self.last_scan, self._scan_pose, self._observation = s, self.truth, None
        est = self.estimate
        pts = sensors.points_platform(s, mount)
        c, sn = math.cos(est[2]), math.sin(est[2])
        world = np.column_stack([est[0] + c * pts[:, 0] - sn * pts[:, 1], est[1] + sn * pts[:, 0] + c * pts[:, 1]])
        origin = (est[0] + c * mount, est[1] + sn * mount)
        self.perception = Perception(world, pts, self.perception.seq + 1, origin)
        self._us_pose, self._us_eps = self.truth, self._us_noise.standard_normal(sensors.US_SENSORS)
        if self.geometry is not None and bool(self.params("LocalLocalization")):
            score = sensors.match_score(s.ranges, sensors.expected_ranges(est, mount, self.map_scene))
            self.loc.correct(score, self.truth, now, self.rng, bool(self.params("GlobalLocalization")))

    def us_distances(self) -> list[float]:
        """The 16 ultrasonic distances of the last sensing period (mm, inf: no echo); computed on demand."""
        seq = self.perception.seq
        if self._us[0] != seq:
            mounts = sensors.ultrasonic_mounts(self.params)
            self._us = (seq, sensors.ultrasonic(self._us_pose, mounts, self.sensed, self._us_eps))
        return self._us[1]

    # ---- range callbacks for the fake hardware
    def scan(self, pose: Pose | None = None) -> list[float | None]:
        """541 ranges (mm, None: no echo) from ``pose`` (default: the true pose)."""
        s = sensors.scan(pose or self.truth, self.footprint.front, self._scene_now(), self._cb_noise)
        return [float(r) if math.isfinite(r) else None for r in s.ranges]

    def ultrasonic(self, pose: Pose | None = None) -> list[float]:
        """16 distances (mm, inf: no echo) from ``pose`` (default: the true pose)."""
        mounts = sensors.ultrasonic_mounts(self.params)
        eps = self._cb_noise.standard_normal(sensors.US_SENSORS)
        return sensors.ultrasonic(pose or self.truth, mounts, self._scene_now(), eps)

    # ---- state for the status telegram
    @property
    def estimate(self) -> Pose:
        return float(self.loc.x), float(self.loc.y), float(self.loc.angle)

    def observation(self) -> sensors.Observation:
        if self.last_scan is None:
            return sensors.Observation()
        if self._observation is None:
            g = self.geometry or MapGeometry()
            min_line = float(self.params("MinLineLenAux"))
            self._observation = sensors.observe(
                self.last_scan,
                self._scan_pose,
                self.footprint.front,
                self.sensed,
                g.reflectors,
                self._wall_corners(),
                min_line,
            )
        return self._observation

    @property
    def collision(self) -> bool:
        return self.contact or self.motion.collision

    def kidnap(self, pose: Pose) -> None:
        """Move the platform without telling it (tests of "localization lost")."""
        self.truth = pose
        if self.neighbours is not None:
            self.neighbours.place(*pose)

    # ---- commands (the platform's side; guide 4.3, 6.3)
    def command_velocity(self, v: float, w: float, now: float, kind: str = "vel") -> None:
        """CMD_MOVE_VEL: "vel" (MODE_MOTION_VEL, kept until the watchdog) or "joy" (JOYSOFT, decays)."""
        self.motion.command_velocity(v, w, now, kind, self.params)

    def command_wheels(self, right: float, left: float, now: float) -> None:
        """CMD_MOVE_VEL_WHEEL: wheel speeds (mm/s) -> v, w through DistWheels."""
        self.command_velocity(0.5 * (right + left), (right - left) / self.track, now)

    def move_to(self, goal: Pose) -> None:
        """CMD_MOVE_ABS / CMD_MOVE_REL: plan (PlanningEnabled) or the direct Bezier path."""
        self.motion.command_job(AutoJob("goto", goal, [goal], bool(self.params("PlanningEnabled"))))

    def follow_path(self, frames: Sequence[Pose]) -> None:
        """CMD_MOVE_PATH (and CMD_MOVE_TO_STATION with the roadmap's frames)."""
        self.motion.command_job(AutoJob("path", frames[-1], list(frames), bool(self.params("PlanningEnabled"))))

    def command_path(self, frames: Sequence[Pose]) -> None:
        """One frame: ``move_to``; more: ``follow_path``."""
        if len(frames) == 1:
            self.move_to(frames[0])
        elif frames:
            self.follow_path(frames)

    def hold(self) -> None:
        self.motion.hold()

    def resume(self) -> None:
        self.motion.resume()

    def stop(self) -> None:
        self.motion.stop()

    def halt(self) -> None:
        """Emergency stop, drive fault, shutdown: the setpoints (and the measured velocities, until the next
        odometry says otherwise) are zero at once; the command ends."""
        self.motion.halt()
        self.setpoints = (0.0, 0.0)
        self.measured = (0.0, 0.0)

    def set_estimate(self, pose: Pose) -> None:
        """CMD_SET_FRM_PLTF: the estimate only; the body does not move."""
        self.loc.set_estimate(*pose)

    def place(self, pose: Pose) -> None:
        """The body and the estimate at ``pose`` (the start pose at boot)."""
        self.truth = pose
        self.loc.set_estimate(*pose, exact=True)
        if self.neighbours is not None:
            self.neighbours.place(*pose)

    def event(self, event: int, now: float) -> str:
        """guide 6.3 CMD_SET_EVENT (1..6): post-process recording and replay; returns a log line."""
        m = self.motion
        if event == 1:
            m.recorder.start()
            return "post-process recording started"
        if event == 2:
            m.recorder.stop()
            return f"post-process recording stopped: {len(m.recorder.samples)} samples"
        if event == 3:
            job = ReplayJob.of(m.recorder.samples, bool(self.params("PlanningEnabled")))
            if job is None:
                return "post-process replay: nothing recorded"
            m.recorder.stop()
            m.command_job(job)
            return f"post-process replay started: {job.duration:.1f} s"
        if isinstance(m.job, ReplayJob):
            if event == 4:
                m.stop()
                return "post-process replay stopped"
            m.job.paused = event == 5
            if event == 5:
                m.hold()
            else:
                m.resume()
            return "post-process replay " + ("paused" if event == 5 else "continued")
        return "post-process replay: no replay running"

    # ---- what the platform reports
    @property
    def active(self) -> bool:
        return self.motion.active

    @property
    def target_reached(self) -> bool:
        return self.motion.target_reached

    def commanded_frame(self) -> Pose:
        ref = self.motion.reference(self.estimate)
        return ref.x, ref.y, ref.theta

    def remaining_path(self) -> list[tuple[float, float]]:
        return [(x, y) for x, y in self.path_xy().tolist()]

    def path_xy(self) -> F64:
        """``remaining_path`` as an (n, 2) array (GET_STATUS converts it in one numpy pass)."""
        return self.motion.path_points()

    def imu(self, now: float) -> tuple[float, float, float, float]:
        """(ax, ay, az in m/s^2, yaw rate in rad/s) of the body, from its true motion."""
        v, w = self._true_vel
        return 0.0, v * w / 1000.0, GRAVITY, w

    def scan_ranges(self, now: float) -> F64:
        """The serial scanner's source: the latest laser scan of ``sense`` (10 Hz), whatever its own period; mm,
        inf: no echo (the S300 encodes the ranges as an array: no list of floats and Nones in between)."""
        if self.last_scan is None:  # before the first sensing period: a scan of its own, as ``scan`` casts it
            return sensors.scan(self.truth, self.footprint.front, self._scene_now(), self._cb_noise).ranges
        return self.last_scan.ranges.copy()

    def us_ranges(self, now: float) -> list[float | None]:
        """The ultrasonic board's source: the distances of the latest sensing period (read every period)."""
        return [None if r == math.inf else r for r in self.us_distances()]

    # ---- Navigator (automatic.Navigator): planning with the footprint
    @property
    def half_width(self) -> float:
        return self.footprint.half_width

    @property
    def front(self) -> float:
        return self.footprint.front

    @property
    def rear(self) -> float:
        return self.footprint.rear

    @property
    def sweep(self) -> float:
        return self.footprint.radius

    def planner(self) -> Planner:
        if self._planner is None:
            self._planner = Planner.shared(self.geometry or MapGeometry(), self.footprint.radius + PLAN_MARGIN)
        return self._planner

    def plan(self, start: Pose, goal: Pose, obstacles: F64) -> Plan:
        pl = self.planner()
        g = pl.geometry
        if self._footprint_hits(start, g.obstacles, g.circles):  # sensed obstacles are estimates: not here
            return Plan(PlannerState.COLLISION_START)
        if self._footprint_hits(goal, g.obstacles, np.vstack([g.circles, circles(obstacles)])):
            return Plan(PlannerState.COLLISION_TARGET)
        obs = self._as_planned(obstacles)
        pts = np.array([start[:2], goal[:2]])
        clear = np.maximum(clearance(pts[:, 0], pts[:, 1], pl.walls, np.vstack([pl.circs, obs])) * 0.999, 0.0)
        return pl.plan(start[:2], goal[:2], float(clear[0]), float(clear[1]), obs)

    def free(self, points: F64, obstacles: F64) -> BOOL:
        pl = self.planner()
        circs = np.vstack([pl.circs, self._as_planned(obstacles)])
        ok = np.asarray(pl.geometry.allowed(points[:, 0], points[:, 1]))
        return ok & (clearance(points[:, 0], points[:, 1], pl.walls, circs) >= pl.radius)

    def _as_planned(self, obstacles: F64) -> F64:
        """Sensed obstacles are passed at half the platform's width plus the margin, not at the turning radius
        the map's walls get (E-MOT-006): the planner inflates everything by its radius, so their radii shrink by
        the difference (and may go negative; only radius + planner radius is ever used)."""
        obs = circles(obstacles).copy()
        obs[:, 2] -= self.planner().radius - (self.footprint.half_width + OBSTACLE_MARGIN)
        return obs

    def _footprint_hits(self, pose: Pose, segs: F64, circs: F64) -> bool:
        x, y, a = pose
        c, s = math.cos(a), math.sin(a)
        poly = np.array([(x + c * px - s * py, y + s * px + c * py) for px, py in self.footprint.corners])
        edges = polygon_edges(poly)
        if len(segs):
            if not bool(np.all(segments_clear(edges, segs, circles([]), 0.0))):
                return True
            if bool(np.any(inside_polygon(segs[:, 0], segs[:, 1], poly))):
                return True
        if len(circs):
            if bool(np.any(inside_polygon(circs[:, 0], circs[:, 1], poly))):
                return True
            if bool(np.any(point_segment_distance(circs[:, 0], circs[:, 1], edges).min(axis=1) < circs[:, 2])):
                return True
        return False
