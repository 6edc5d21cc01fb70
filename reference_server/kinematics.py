"""A small ideal differential drive (the reference ``motion_api.MotionModel``) and the roadmap router (guide 4.3).

Rules:
- Sans-IO: one control period is ``step`` (control), ``move`` (physics) and ``odometry`` (estimation), see
  reference_server/motion_api.py; ``motion_api.advance_ideal`` runs all three without hardware. Units inside:
  mm, mm/s, rad, rad/s. Parameters are read on every step through ``params`` (a ``ParameterStore.get``), so a
  CMD_SET_PLTF_PARAM takes effect at once; the body's true track is DistWheels at construction (hardware).
- The setpoint velocities follow the desired ones within MaxTransAcc / MaxRotAcc and are limited to
  MaxTransVel / MaxRotVel (errata E-PAR-020, E-PAR-023); ``halt`` (emergency stop, shutdown) zeroes them.
  ``v`` and ``w`` are the velocities measured by the odometry.
- One command at a time (guide 4.3 Automatic: "the execution of the old command will be stopped immediately
  and the new command will be started"). ``hold`` (CMD_BREAK) brakes to zero and keeps the command,
  ``resume`` (CMD_CONTINUE) drives it on, ``stop`` (CMD_STOP) ends it.
- A path command is turn - drive - turn per waypoint, steered from the estimated pose on every step (so a
  CMD_SET_FRM_PLTF during a move simply re-aims), then a turn to the end angle; no planning, no obstacles:
  the true body goes wherever its wheels take it.
- ``step`` returns one-line event messages (watchdog expired, target reached); the platform logs them.
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

from pltf.fake_hardware.serial_scanner import Ranges
from pltf.reference_server.motion_api import Frame, Params, Pose, normalize

__all__ = ["Drive", "Frame", "Pose", "Roadmap", "Station", "normalize", "relative_to_world"]

_DRIVE_TOL = 0.02  # rad: heading error below which a turn on the spot ends and the drive starts
_TURN_AGAIN = 0.35  # rad: heading error above which the drive stops and turns on the spot again
_HEADING_GAIN = 2.0  # 1/s: proportional heading correction while driving
_MIN_SPEED = 20.0  # mm/s: floor of the braking profile, so a target is reached in finite time
_MIN_TURN = 0.02  # rad/s: the same for turns
_G = 9.81  # m/s^2


def relative_to_world(pose: Frame, rel: Frame) -> Frame:
    """CMD_MOVE_REL: a frame given in platform coordinates -> world coordinates."""
    c, s = math.cos(pose.angle), math.sin(pose.angle)
    return Frame(pose.x + c * rel.x - s * rel.y, pose.y + s * rel.x + c * rel.y, normalize(pose.angle + rel.angle))


def _approach(current: float, desired: float, max_delta: float) -> float:
    return current + max(-max_delta, min(max_delta, desired - current))


def _brake_profile(distance: float, v_max: float, acc: float, floor: float) -> float:
    """The highest speed from which ``distance`` still suffices to stop at ``acc``."""
    return max(floor, min(v_max, math.sqrt(2.0 * acc * distance)))


def _integrate(p: Pose, ds: float, dth: float) -> None:
    """Second-order (midpoint) integration of the unicycle over one period."""
    mid = p.angle + 0.5 * dth
    p.x += ds * math.cos(mid)
    p.y += ds * math.sin(mid)
    p.angle = normalize(p.angle + dth)


@dataclass
class _Path:
    waypoints: deque[Frame]
    end_angle: float
    turning: bool = True


@dataclass
class Drive:
    params: Params
    pose: Pose = field(default_factory=Pose)  # the estimate (odometry)
    true_pose: Pose = field(default_factory=Pose)  # the ground truth
    v: float = 0.0  # measured translational velocity, mm/s
    w: float = 0.0  # measured rotational velocity, rad/s
    target_reached: bool = False
    held: bool = False
    _kind: str = "idle"  # idle | vel | joy | path
    _v_cmd: float = 0.0
    _w_cmd: float = 0.0
    _v_set: float = 0.0  # setpoint velocities after the acceleration limits
    _w_set: float = 0.0
    _last_cmd: float = 0.0
    _path: _Path | None = None
    _true_track: float = 0.0  # mm: the body's wheel distance (DistWheels when built)
    _true_v: float = 0.0  # true velocities of the last ``move``
    _true_w: float = 0.0
    _true_acc: float = 0.0  # mm/s^2

    def __post_init__(self) -> None:
        self._true_track = float(self.params("DistWheels"))

    # ---- commands
    def command_velocity(self, v: float, w: float, now: float, kind: str = "vel") -> None:
        """MODE_MOTION_VEL (kind "vel": kept until the watchdog) or JOYSOFT (kind "joy": decays)."""
        self._kind, self._path = kind, None
        self._v_cmd, self._w_cmd, self._last_cmd = (*self._limit(v, w), now)

    def command_wheels(self, right: float, left: float, now: float) -> None:
        """CMD_MOVE_VEL_WHEEL: wheel speeds (mm/s) -> v, w through DistWheels (guide 5.9 Geometry)."""
        self.command_velocity((right + left) / 2.0, (right - left) / self._track(), now)

    def command_path(self, frames: list[Frame]) -> None:
        """Drive through the frames' points, then turn to the last frame's angle."""
        if not frames:
            return
        self._kind, self.target_reached = "path", False
        self._path = _Path(deque(frames), frames[-1].angle)

    def hold(self) -> None:
        self.held = True

    def resume(self) -> None:
        self.held = False

    def stop(self) -> None:
        """End the command; the platform brakes to standstill."""
        self._kind, self._path, self.held = "idle", None, False

    def halt(self) -> None:
        """Stop at once (emergency stop, drive fault, CAN shutdown): the setpoints are zero from now on (the
        measured velocities too, until the next odometry says otherwise)."""
        self.stop()
        self._v_set = self._w_set = self.v = self.w = 0.0

    def set_pose(self, frame: Frame) -> None:
        """CMD_SET_FRM_PLTF: the estimate only."""
        self.pose = Pose(frame.x, frame.y, normalize(frame.angle))

    def place(self, frame: Frame) -> None:
        self.set_pose(frame)
        self.true_pose = Pose(frame.x, frame.y, normalize(frame.angle))

    # ---- observation
    @property
    def active(self) -> bool:
        return self._kind != "idle"

    def remaining_path(self) -> list[Frame]:
        return list(self._path.waypoints) if self._path is not None else []

    def path_xy(self) -> list[tuple[float, float]]:
        return [(f.x, f.y) for f in self._path.waypoints] if self._path is not None else []

    def commanded_frame(self) -> Frame:
        """The frame the controller steers to now (the estimated pose when no path is driven)."""
        if self._path is None:
            return self.pose.frame()
        if self._path.waypoints:
            wp = self._path.waypoints[0]
            return Frame(wp.x, wp.y, self._path.end_angle if len(self._path.waypoints) == 1 else wp.angle)
        return Frame(self.pose.x, self.pose.y, self._path.end_angle)

    def wheel_setpoints(self) -> tuple[float, float]:
        half = 0.5 * self._w_set * self._track()
        return self._v_set + half, self._v_set - half

    # ---- the control period
    def step(self, now: float, dt: float) -> list[str]:
        events: list[str] = []
        v_d, w_d = self._desired(now, dt, events)
        if self.held:
            v_d = w_d = 0.0
        self._v_set = _approach(self._v_set, v_d, float(self.params("MaxTransAcc")) * dt)
        self._w_set = _approach(self._w_set, w_d, float(self.params("MaxRotAcc")) * dt)
        return events

    def move(self, right: float, left: float, dt: float) -> tuple[float, float]:
        """No obstacles: the wheels roll as driven and carry the body along."""
        dr, dl = right * dt, left * dt
        v = 0.5 * (right + left)
        self._true_acc = 0.0 if dt <= 0.0 else (v - self._true_v) / dt
        self._true_v, self._true_w = v, (right - left) / self._true_track
        _integrate(self.true_pose, 0.5 * (dr + dl), (dr - dl) / self._true_track)
        return dr, dl

    def odometry(self, right: float, left: float, dt: float) -> None:
        ds, dth = 0.5 * (right + left), (right - left) / self._track()
        _integrate(self.pose, ds, dth)
        if dt > 0.0:
            self.v, self.w = ds / dt, dth / dt

    # ---- sensor sources: no world, so no echo; the IMU feels the true motion
    def scan_ranges(self, now: float) -> Ranges | None:
        return None

    def us_ranges(self, now: float) -> Sequence[float | None] | None:
        return None

    def imu(self, now: float) -> tuple[float, float, float, float]:
        return self._true_acc / 1000.0, self._true_v * self._true_w / 1000.0, _G, self._true_w

    def _track(self) -> float:
        return float(self.params("DistWheels"))

    def _limit(self, v: float, w: float) -> tuple[float, float]:
        v_max, w_max = float(self.params("MaxTransVel")), float(self.params("MaxRotVel"))
        return max(-v_max, min(v_max, v)), max(-w_max, min(w_max, w))

    def _desired(self, now: float, dt: float, events: list[str]) -> tuple[float, float]:
        if self._kind == "vel":
            # guide 4.3 Mode Velocity: "keeps the last set velocity until a new velocity value is set or a
            # watchdog time expired" (VelWatchdogTime, erratum E-PAR-018)
            if now - self._last_cmd > float(self.params("VelWatchdogTime")) / 1000.0:
                events.append("velocity watchdog expired: platform stopped")
                self.stop()
                return 0.0, 0.0
            return self._v_cmd, self._w_cmd
        if self._kind == "joy":
            # guide 6.3 CMD_MOVE_VEL: "If no velocity commands are received, the platform will decelerate to
            # zero after few seconds" (JoySoftVelTimeout, erratum E-PAR-019)
            if now - self._last_cmd > float(self.params("JoySoftVelTimeout")) / 1000.0:
                if self._v_set == 0.0 and self._w_set == 0.0:
                    self.stop()
                return 0.0, 0.0
            return self._v_cmd, self._w_cmd
        if self._kind == "path" and self._path is not None and not self.held:
            return self._steer(self._path, dt, events)
        return 0.0, 0.0

    def _steer(self, path: _Path, dt: float, events: list[str]) -> tuple[float, float]:
        tol_pos = float(self.params("TargetReachedTolPos"))
        v_max = float(self.params("IpoTransVel"))
        w_max = float(self.params("IpoRotVel"))
        acc, alpha = float(self.params("MaxTransAcc")), float(self.params("MaxRotAcc"))
        pose = self.pose
        while path.waypoints:
            wp = path.waypoints[0]
            dist = math.hypot(wp.x - pose.x, wp.y - pose.y)
            if dist > tol_pos:
                break
            path.waypoints.popleft()
            path.turning = True
        if path.waypoints:
            error = normalize(math.atan2(wp.y - pose.y, wp.x - pose.x) - pose.angle)
            if path.turning and abs(error) < _DRIVE_TOL:
                path.turning = False
            elif not path.turning and abs(error) > _TURN_AGAIN:
                path.turning = True
            if path.turning:
                return 0.0, self._turn_speed(error, w_max, alpha, dt)
            v = min(_brake_profile(dist, v_max, acc, _MIN_SPEED), dist / dt)
            return v, max(-w_max, min(w_max, _HEADING_GAIN * error))
        error = normalize(path.end_angle - pose.angle)
        if abs(error) <= math.radians(float(self.params("TargetReachedTolAngle"))):
            self.halt()
            self.target_reached = True
            events.append(f"target reached: x {pose.x:.0f} mm, y {pose.y:.0f} mm, a {pose.angle:.3f} rad")
            return 0.0, 0.0
        return 0.0, self._turn_speed(error, w_max, alpha, dt)

    @staticmethod
    def _turn_speed(error: float, w_max: float, alpha: float, dt: float) -> float:
        w = min(_brake_profile(abs(error), w_max, alpha, _MIN_TURN), abs(error) / dt)
        return math.copysign(w, error)


# ---------------------------------------------------------------------------------------------- roadmap


class Station(NamedTuple):
    id: str
    name: str
    frame: Frame  # the station's angle: degrees in the XML (erratum E-XML-007), radians here


class Roadmap:
    """Stations and undirected edges of a validated roadmap (erratum E-XML-003: both directions)."""

    def __init__(self, tree: Any) -> None:
        root = tree.getroot() if hasattr(tree, "getroot") else tree
        self.stations: dict[str, Station] = {}
        for st in root.iterfind("stations/station"):
            pt = st.find("point")
            angle = math.radians(float(st.get("angle", "0")))
            sid = st.get("id")
            self.stations[sid] = Station(sid, st.get("name", sid), Frame(float(pt.get("x")), float(pt.get("y")), angle))
        self.edges: dict[str, list[tuple[str, float, list[tuple[float, float]]]]] = {s: [] for s in self.stations}
        frames = {sid: st.frame for sid, st in self.stations.items()}
        for edge in root.iterfind("edges/edge"):
            a, b = edge.get("startstation"), edge.get("endstation")
            pa, pb = frames[a], frames[b]
            if len(edge):  # points between the stations (a complete graph of 120 stations has 14,400 edges without)
                inner = [(float(p.get("x")), float(p.get("y"))) for p in edge.iter("point")]
                line = [(pa.x, pa.y), *inner, (pb.x, pb.y)]
                cost = sum(math.dist(p, q) for p, q in itertools.pairwise(line))
            else:
                inner, cost = [], math.hypot(pb.x - pa.x, pb.y - pa.y)
            self.edges[a].append((b, cost, inner))
            self.edges[b].append((a, cost, inner[::-1]))

    def find(self, name: str) -> Station | None:
        """A station by name, else by id (guide 6.3 CMD_MOVE_TO_STATION: "Name of the station")."""
        for st in self.stations.values():
            if st.name == name:
                return st
        return self.stations.get(name)

    def nearest(self, x: float, y: float) -> Station | None:
        return min(self.stations.values(), key=lambda s: math.hypot(s.frame.x - x, s.frame.y - y), default=None)

    def route(self, start: str, goal: str) -> list[Frame] | None:
        """Dijkstra: the frames from station ``start`` to ``goal`` (edge points included), None if unreachable."""
        dist, prev = {start: 0.0}, {}
        queue = [(0.0, start)]
        while queue:
            d, here = heapq.heappop(queue)
            if here == goal:
                break
            if d > dist[here]:
                continue
            for there, cost, inner in self.edges[here]:
                if d + cost < dist.get(there, math.inf):
                    dist[there], prev[there] = d + cost, (here, inner)
                    heapq.heappush(queue, (d + cost, there))
        if goal not in dist:
            return None
        points: list[tuple[float, float]] = []
        node = goal
        while node != start:
            parent, inner = prev[node]
            f = self.stations[node].frame
            points[:0] = [*inner, (f.x, f.y)]
            node = parent
        s = self.stations[start].frame
        frames = [Frame(x, y, 0.0) for x, y in [(s.x, s.y), *points]]
        frames[-1] = self.stations[goal].frame
        return frames
