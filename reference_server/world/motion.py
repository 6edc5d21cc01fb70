"""The motion modes of guide 4.3 on top of the jobs: what the platform's wheels are told every control period.

Rules (errata E-MOT-005, E-MOT-009; E-SRV-005 and E-SRV-016 stay as they are):
- One command at a time: a velocity ("vel": MODE_MOTION_VEL, kept until VelWatchdogTime), a joystick
  velocity ("joy": JOYSOFT, decays to zero after JoySoftVelTimeout), an automatic job (automatic.AutoJob) or
  a replay (replay.ReplayJob). A new command preempts the running one (guide 4.3 Automatic). Which command is
  allowed in which mode is the platform's business (state chart); this module executes.
- ``hold`` (CMD_BREAK) stops the platform within one control period and keeps the command; ``resume``
  (CMD_CONTINUE) drives it on; ``stop`` (CMD_STOP) ends the command and the platform brakes with
  MaxTransAcc / MaxRotAcc; ``halt`` (emergency stop, shutdown, exit) ends it and stops at once.
- Every period: the command's desired (v, w), then the collision check (CollCheckEnabled: laser points in
  the field ahead of the front edge up to CollLaserMinDist stop forward motion, ultrasonic echoes of the
  rear sensors closer than CollLaserMinDist stop backward motion, a turn on the spot that would bring a laser
  point or a place an ultrasonic echo may come from within ``TURN_MARGIN`` of the footprint within
  ``TURN_LOOK`` stops in that direction: all at once, and the status' collision flag says so), then
  MaxTransVel / MaxRotVel and the acceleration limits.
- An ultrasonic sensor tells how far its echo is, not where in its 25 degree cone: the turn check takes the
  echo at that range on each ray of the cone (``echo_points``), so a wall the sweep clears does not hold a turn
  back however close it is to a side sensor, and one the rear corner would touch does (E-MOT-009).
- Sans-IO: ``step`` takes ``now``, ``dt``, the estimated pose and what the sensors saw, and returns log lines.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pltf.reference_server.world.automatic import AutoJob, Navigator, Perception
from pltf.reference_server.world.geometry import F64
from pltf.reference_server.world.ipo import Ref
from pltf.reference_server.world.paths import NO_POINTS
from pltf.reference_server.world.planner import PlannerState
from pltf.reference_server.world.replay import Recorder, ReplayJob
from pltf.reference_server.world.sensors import US_RAY_OFFSETS, ultrasonic_mounts

Params = Callable[[str], Any]
Pose = tuple[float, float, float]
REAR_SENSORS = (8, 9, 10, 11)  # USSensor09..12 face backwards (E-PAR-017)
TURN_MARGIN = 20.0  # mm
TURN_LOOK = np.radians([5.0, 10.0, 15.0])  # rotations checked ahead of a turn on the spot
TURN_ON_SPOT = 50.0  # mm/s: below this a rotation is a turn on the spot


def _approach(current: float, desired: float, max_delta: float) -> float:
    return current + max(-max_delta, min(max_delta, desired - current))


@dataclass
class Motion:
    v: float = 0.0  # commanded translational velocity after all limits, mm/s
    w: float = 0.0  # rad/s
    held: bool = False
    target_reached: bool = False
    collision: bool = False  # the collision check is holding the platform back
    kind: str = "idle"  # idle | vel | joy | auto | replay
    job: AutoJob | ReplayJob | None = None
    planner_state: PlannerState = PlannerState.STANDBY
    recorder: Recorder = field(default_factory=Recorder)
    _v_cmd: float = 0.0
    _w_cmd: float = 0.0
    _last_cmd: float = 0.0
    _coll_key: tuple[float, ...] = ()
    _coll_ahead: bool = False
    _coll_turn: tuple[bool, bool] = (False, False)  # a turn left / right would hit something
    _echo_key: tuple[Any, ...] = ()  # the echoes, footprint and direction ``_echo_hit`` was computed for
    _echo_mounts: F64 | None = None
    _echo_hit: bool = False

    # ---- commands
    def command_velocity(self, v: float, w: float, now: float, kind: str, params: Params) -> None:
        v_max, w_max = float(params("MaxTransVel")), float(params("MaxRotVel"))
        self._end_job()
        self.kind = kind
        self._v_cmd, self._w_cmd = max(-v_max, min(v_max, v)), max(-w_max, min(w_max, w))
        self._last_cmd = now

    def command_job(self, job: AutoJob | ReplayJob) -> None:
        self._end_job()
        self.kind, self.job, self.target_reached = ("replay" if isinstance(job, ReplayJob) else "auto"), job, False
        self.planner_state = job.planner_state

    def hold(self) -> None:
        self.held = True

    def resume(self) -> None:
        self.held = False

    def stop(self) -> None:
        self._end_job()
        self.kind, self.held = "idle", False

    def halt(self) -> None:
        self.stop()
        self.v = self.w = 0.0

    def _end_job(self) -> None:
        if self.job is not None and self.planner_state == PlannerState.PLANNING:
            self.planner_state = PlannerState.STANDBY
        self.job = None

    # ---- observation
    @property
    def active(self) -> bool:
        return self.kind != "idle"

    def reference(self, pose: Pose) -> Ref:
        if self.job is not None:
            return self.job.reference(pose)
        return Ref(*pose, self.v, self.w)

    def path_points(self) -> F64:
        """The remaining path, (n, 2) points (``paths.sample_points``)."""
        return NO_POINTS if self.job is None else self.job.path_points()

    # ---- the control period
    def step(
        self,
        now: float,
        dt: float,
        pose: Pose,
        seen: Perception,
        us: Callable[[], list[float]],
        params: Params,
        nav: Navigator,
    ) -> list[str]:
        events: list[str] = []
        v_d, w_d = self._desired(now, dt, pose, seen, params, nav, events)
        if self.held:
            self.v = self.w = 0.0  # CMD_BREAK: within one control period (E-MOT-005)
            self.recorder.sample(now, pose)
            return events
        v_d, w_d = self._collision_check(v_d, w_d, seen, us, params, nav)
        v_max, w_max = float(params("MaxTransVel")), float(params("MaxRotVel"))
        v_d, w_d = max(-v_max, min(v_max, v_d)), max(-w_max, min(w_max, w_d))
        if self.collision:
            self.v = 0.0 if v_d == 0.0 else _approach(self.v, v_d, float(params("MaxTransAcc")) * dt)
            self.w = 0.0 if w_d == 0.0 else _approach(self.w, w_d, float(params("MaxRotAcc")) * dt)
        else:
            self.v = _approach(self.v, v_d, float(params("MaxTransAcc")) * dt)
            self.w = _approach(self.w, w_d, float(params("MaxRotAcc")) * dt)
        self.recorder.sample(now, pose)
        return events

    def _desired(
        self, now: float, dt: float, pose: Pose, seen: Perception, params: Params, nav: Navigator, events: list[str]
    ) -> tuple[float, float]:
        if self.kind == "vel":
            # guide 4.3 Mode Velocity: "keeps the last set velocity until a new velocity value is set or a
            # watchdog time expired" (VelWatchdogTime, erratum E-PAR-018)
            if now - self._last_cmd > float(params("VelWatchdogTime")) / 1000.0:
                events.append("velocity watchdog expired: platform stopped")
                self.stop()
                return 0.0, 0.0
            return self._v_cmd, self._w_cmd
        if self.kind == "joy":
            # guide 6.3 CMD_MOVE_VEL: "the platform will decelerate to zero after few seconds" (E-PAR-019)
            if now - self._last_cmd > float(params("JoySoftVelTimeout")) / 1000.0:
                if self.v == 0.0 and self.w == 0.0:
                    self.stop()
                return 0.0, 0.0
            return self._v_cmd, self._w_cmd
        job = self.job
        if job is None or self.held:  # a held job's clock stands still: it is not stepped
            return 0.0, 0.0
        v, w = job.step(now, dt, pose, seen, params, nav, self.v)
        events += job.events
        job.events = []
        self.planner_state = job.planner_state
        if job.done:
            self.target_reached = isinstance(job, AutoJob) and job.reached
            self.job, self.kind = None, "idle"
        return v, w

    def _collision_check(
        self, v: float, w: float, seen: Perception, us: Callable[[], list[float]], params: Params, nav: Navigator
    ) -> tuple[float, float]:
        self.collision = False
        if not bool(params("CollCheckEnabled")):
            return v, w
        limit = float(params("CollLaserMinDist"))
        key = (seen.seq, limit, nav.front, nav.half_width, nav.sweep)
        if key != self._coll_key:  # once per scan: is anything in the field ahead, in the turning circle?
            self._coll_key = key
            pts, hw = seen.platform, nav.half_width
            ahead = (pts[:, 0] >= nav.front - 1.0) & (pts[:, 0] <= nav.front + limit) & (np.abs(pts[:, 1]) <= hw + 50.0)
            self._coll_ahead = bool(ahead.any())
            self._coll_turn = (_turn_hits(pts, nav, 1.0), _turn_hits(pts, nav, -1.0))
        if v > 0.0 and self._coll_ahead:
            v, self.collision = 0.0, True
        if v < 0.0:
            dist = us()
            rear = [dist[i] for i in REAR_SENSORS if i < len(dist)]
            if rear and min(rear) < limit:
                v, self.collision = 0.0, True
        if w != 0.0 and abs(v) < TURN_ON_SPOT:
            sign = 1.0 if w > 0 else -1.0
            # a turn on the spot swings the rear out to the side, where the laser cannot see: the echoes guard it
            if self._coll_turn[0 if w > 0 else 1] or self._echoes_hit(us(), params, nav, sign):
                w, self.collision = 0.0, True
        return v, w

    def _echoes_hit(self, dist: list[float], params: Params, nav: Navigator, sign: float) -> bool:
        """``_turn_hits`` of the places the echoes may come from (``echo_points``), computed again only when the
        echoes, the sensors' mounts, the footprint or the direction changed: a turn held back asks every control
        period, the echoes change once per sensing period."""
        mounts = ultrasonic_mounts(params)
        key = (*dist, nav.front, nav.rear, nav.half_width, nav.sweep, sign)
        if key != self._echo_key or mounts is not self._echo_mounts:
            self._echo_key, self._echo_mounts = key, mounts
            self._echo_hit = _turn_hits(echo_points(dist, mounts), nav, sign)
        return self._echo_hit


def _turn_hits(pts: np.ndarray, nav: Navigator, sign: float) -> bool:
    """Would turning on the spot by TURN_LOOK (left: sign 1) bring a point within TURN_MARGIN of the footprint?"""
    if len(pts) == 0:
        return False
    near = pts[np.hypot(pts[:, 0], pts[:, 1]) <= nav.sweep + TURN_MARGIN]
    if len(near) == 0:
        return False
    for a in TURN_LOOK:
        c, s = np.cos(-sign * a), np.sin(-sign * a)  # the platform turns by +a: the points by -a
        x = c * near[:, 0] - s * near[:, 1]
        y = s * near[:, 0] + c * near[:, 1]
        m = TURN_MARGIN
        hit = (x <= nav.front + m) & (x >= nav.rear - m) & (np.abs(y) <= nav.half_width + m)
        if hit.any():
            return True
    return False


def echo_points(dist: list[float], mounts: F64) -> F64:
    """(n, 2), platform frame: where the ultrasonic echoes may come from - each finite range on every ray of its
    sensor's cone (``mounts``: x, y, angle of each sensor, sensors.ultrasonic_mounts)."""
    d = np.asarray(dist[: len(mounts)], dtype=np.float64)
    seen = np.isfinite(d)
    m, r = mounts[: len(d)][seen], d[seen][:, None]
    rays = m[:, 2:3] + US_RAY_OFFSETS[None, :]
    x = m[:, 0:1] + r * np.cos(rays)
    y = m[:, 1:2] + r * np.sin(rays)
    return np.column_stack([x.ravel(), y.ravel()])
