"""Motion mode Automatic (guide 4.3): one move command as a job that plans, drives, avoids and settles.

Rules (errata E-MOT-006, E-MOT-007, E-MOT-009, E-MOT-015):
- Phases: ``plan`` (the first control step after the command: the planner state is PLANNING until then),
  ``drive`` (the interpolator runs the legs), ``settle`` (position stabilisation and the final turn), ``done``.
- The reference waits for the platform: while it is more than ``LAG`` mm away (then the platform drives back
  onto it), and on a turn while the heading lags more than ``TURN_LAG`` (the collision check holding a turn on
  the spot back): a leg never starts with the platform far off its start or its heading.
- CMD_MOVE_ABS/REL ("goto"): PlanningEnabled -> the planner's shortest path; a failure (no path, collision at
  start or target) ends the job at once with no motion and the planner state says why. Planning disabled ->
  the direct Bezier path (paths.direct).
- CMD_MOVE_PATH / MOVE_TO_STATION ("path"): reach the first frame (planned when PlanningEnabled, else a
  straight line), follow the frames' points, turn to the last frame's angle.
- Obstacles: scan points inside the corridor ahead of the reference (half the platform's width plus
  ``CORRIDOR`` mm) stop the reference so the front edge stays CollLaserMinDist + 100 mm away. Then: goto with
  planning -> replan around the seen obstacle (circles clustered from the points), at most every
  ``REPLAN_EVERY`` s; goto without planning -> wait until the obstacle goes; path -> wait
  PathObstacleWaitTime, then plan a detour to the next free point of the path behind the obstacle and rejoin.
- A target within the tolerances of the pose (every frame within TargetReachedTolPos, E-MOT-015): reached at
  once where the platform stands when the angle is within TargetReachedTolAngle too, else a turn on the spot;
  the planner is not asked (STANDBY).
- Settle: with PositionStabilizationEnabled the platform is driven onto the target within
  TargetReachedTolPos; then it turns to the target angle within TargetReachedTolAngle (also without
  EndTurnEnabled, after the curve, when the angle is still off). The verdict waits for standstill (the
  odometry below ``STILL_TRANS`` / ``STILL_ROT``, erratum E-SRV-009): a platform that coasts out of the
  tolerance is corrected again. Target reached = both within tolerance at standstill. ``SETTLE_TIMEOUT`` s
  without success ends the job, not reached.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from pltf.reference_server.world.geometry import BOOL, F64, circles
from pltf.reference_server.world.ipo import Interpolator, Ref, stabilize, track
from pltf.reference_server.world.paths import NO_POINTS, Drive, Leg, Turn, direct, end_curve, polyline, wrap
from pltf.reference_server.world.planner import Plan, PlannerState

Params = Callable[[str], Any]
Pose = tuple[float, float, float]

CORRIDOR = 50.0  # mm beyond half the platform's width (less than the planner keeps from a sensed obstacle)
LAG = 300.0  # mm: the reference waits while the platform is farther from it, and the platform drives back
TURN_LAG = math.radians(10.0)  # the reference of a turn waits while the platform lags more than this behind it
RECOVER_VEL = 300.0  # mm/s
BRAKE_FIRST = 20.0  # mm/s: a new job plans once the platform is slower than this
REPLAN_EVERY = 0.5  # s
RETRY_EVERY = 1.0  # s
OBSTACLE_MEMORY = 3.0  # s an unseen obstacle is remembered
CLUSTER_GAP = 300.0  # mm
CLUSTER_PAD = 50.0  # mm added to a cluster's radius
CLUSTER_REACH = 600.0  # mm around the points in the corridor that belong to the same obstacle
SETTLE_TIMEOUT = 15.0  # s
SETTLE_TURN_GAIN = 2.0  # 1/s
STILL_TRANS = 1.0  # mm/s: the odometry's translation below this is standstill (the verdict waits for it)
STILL_ROT = 0.002  # rad/s, likewise the rotation


class Navigator(Protocol):
    """What a job needs from the world: planning with the footprint, and free-space tests."""

    @property
    def half_width(self) -> float: ...

    @property
    def front(self) -> float: ...

    @property
    def rear(self) -> float: ...

    @property
    def sweep(self) -> float: ...

    def plan(self, start: Pose, goal: Pose, obstacles: F64) -> Plan: ...

    def free(self, points: F64, obstacles: F64) -> BOOL: ...

    @property
    def measured(self) -> tuple[float, float]:
        """The platform's (v mm/s, w rad/s) from the odometry of the last period."""
        ...


@dataclass(frozen=True)
class Perception:
    """The latest scan's points (world frame through the estimate, and platform frame)."""

    world: F64 = field(default_factory=lambda: np.zeros((0, 2)))
    platform: F64 = field(default_factory=lambda: np.zeros((0, 2)))
    seq: int = 0  # one number per scan
    origin: tuple[float, float] = (0.0, 0.0)  # the laser in the world frame (through the estimate)


@dataclass
class AutoJob:
    kind: str  # "goto" | "path"
    goal: Pose
    frames: list[Pose]
    planning: bool
    phase: str = "plan"
    ipo: Interpolator | None = None
    planner_state: PlannerState = PlannerState.STANDBY
    reached: bool = False
    events: list[str] = field(default_factory=list)
    blocked_since: float | None = None
    next_try: float = 0.0
    obstacles: list[tuple[float, float, float, float]] = field(default_factory=list)  # x, y, r, last seen
    settle_since: float | None = None
    stabilizing: bool = False
    recovering: bool = False
    _seen: Perception | None = None
    _block_leg: Leg | None = None
    _block: float | None = None

    def __post_init__(self) -> None:
        if self.planning or self.kind == "goto":
            self.planner_state = PlannerState.PLANNING if self.planning else PlannerState.STANDBY

    @property
    def done(self) -> bool:
        return self.phase == "done"

    def reference(self, pose: Pose) -> Ref:
        if self.ipo is None or self.ipo.done:
            goal = self.goal if self.phase in ("settle", "done") else pose
            return Ref(*goal, 0.0, 0.0)
        return self.ipo.reference(pose)

    def path_points(self) -> F64:
        return NO_POINTS if self.ipo is None else self.ipo.path_points()

    # ---- the control step
    def step(
        self, now: float, dt: float, pose: Pose, seen: Perception, p: Params, nav: Navigator, speed: float = 0.0
    ) -> tuple[float, float]:
        """(v, w) for this period; ``speed``: the platform's commanded speed (a preempted move brakes first)."""
        if self.phase == "plan":
            if abs(speed) > BRAKE_FIRST:
                return 0.0, 0.0  # plan from where the platform stands
            self._start(now, pose, p, nav)
        if self.phase == "drive":
            assert self.ipo is not None
            stop_at = self._obstacle(now, pose, seen, p, nav)
            ref = self.ipo.reference(pose)
            off = math.hypot(ref.x - pose[0], ref.y - pose[1])
            self.recovering = off > LAG or (self.recovering and off > 0.5 * LAG)
            # a turn the platform does not follow (the collision check holds it back) waits for it: the next leg
            # starts with the platform on the leg's heading, not TURN_LAG or more off it
            behind = isinstance(self.ipo.leg, Turn) and abs(wrap(ref.theta - pose[2])) > TURN_LAG
            self.ipo.step(dt, p, hold=self.recovering or behind, stop_at=stop_at)
            if self.ipo.done:
                self.phase, self.settle_since = "settle", now
            elif self.recovering:  # far off the reference (blocked, pushed, a sharp preemption): back onto it
                v, w, _ = stabilize(pose, (ref.x, ref.y), RECOVER_VEL)
                return v, w
            else:
                ref = self.ipo.reference(pose)
                return track(pose, ref, isinstance(self.ipo.leg, Turn), p)
        if self.phase == "settle":
            return self._settle(now, pose, p, nav.measured)
        return 0.0, 0.0

    def _legs(self, points: list[tuple[float, float]], pose: Pose, p: Params, nav: Navigator) -> list[Leg]:
        tol = math.radians(float(p("TargetReachedTolAngle")))
        legs = polyline(points, pose[2], tol)
        return self._ending(legs, p, nav)

    def _ending(self, legs: list[Leg], p: Params, nav: Navigator) -> list[Leg]:
        tol = math.radians(float(p("TargetReachedTolAngle")))
        if not bool(p("EndTurnEnabled")):
            curve = end_curve(legs, self.goal[2])
            if curve is not None and bool(np.all(nav.free(np.column_stack([curve.x, curve.y]), self._circles()))):
                legs = [*legs[:-1], curve]
        last = next((lg for lg in reversed(legs) if isinstance(lg, Drive)), None)
        heading = float(last.theta[-1]) if last is not None else None
        if heading is not None and abs(wrap(self.goal[2] - heading)) > tol:
            legs.append(Turn(self.goal[0], self.goal[1], heading, heading + wrap(self.goal[2] - heading)))
        return legs

    def _start(self, now: float, pose: Pose, p: Params, nav: Navigator) -> None:
        if self._at_target(pose, p):
            return
        first = self.frames[0] if self.kind == "path" else self.goal
        if self.planning:
            plan = nav.plan(pose, first, self._circles())
            self.planner_state = plan.state
            if plan.state != PlannerState.PATH_FOUND:
                self.phase = "done"
                self.events.append(f"planner: {plan.state.name.lower()}, the platform does not move")
                return
            points = list(plan.points)
        elif self.kind == "goto":
            tol = math.radians(float(p("TargetReachedTolAngle")))
            legs = direct(pose, self.goal[:2], bool(p("StartTurnEnabled")), tol)
            self.ipo, self.phase = Interpolator(self._ending(legs, p, nav)), "drive"
            return
        else:
            points = [pose[:2], first[:2]]
        if self.kind == "path":
            points += [f[:2] for f in self.frames[1:]]
        self.ipo, self.phase = Interpolator(self._legs(points, pose, p, nav)), "drive"

    def _at_target(self, pose: Pose, p: Params) -> bool:
        """A move whose frames all lie within TargetReachedTolPos of the pose drives no leg (erratum E-MOT-015)."""
        # guide 4.3 Mode Automatic: "If the target is reached, the platform stops and waits for a new move
        # command"; E-PAR-021: reached = the position and the angle within TargetReachedTolPos/-Angle
        tol_pos = float(p("TargetReachedTolPos"))
        if any(math.hypot(f[0] - pose[0], f[1] - pose[1]) > tol_pos for f in self.frames):
            return False
        self.planner_state = PlannerState.STANDBY
        err = wrap(self.goal[2] - pose[2])
        if abs(err) <= math.radians(float(p("TargetReachedTolAngle"))):
            self.reached, self.phase = True, "done"
            self.events.append(
                f"target reached where the platform stands: x {pose[0]:.0f} mm, y {pose[1]:.0f} mm, a {pose[2]:.3f} rad"
            )
        else:
            self.ipo, self.phase = Interpolator([Turn(pose[0], pose[1], pose[2], pose[2] + err)]), "drive"
        return True

    # ---- obstacles
    def _circles(self) -> F64:
        return circles([o[:3] for o in self.obstacles])

    def _obstacle(self, now: float, pose: Pose, seen: Perception, p: Params, nav: Navigator) -> float | None:
        """The arc length on the current Drive leg to stop at (None: free); starts replanning and detours."""
        assert self.ipo is not None
        leg = self.ipo.leg
        if seen is not self._seen or leg is not self._block_leg:  # a new scan, or a new leg: look again
            self._seen, self._block_leg = seen, leg
            self._block = self._blocked_at(now, pose, seen, p, nav)
        if self._block is None:
            self.blocked_since = None
            return None
        if self.blocked_since is None:
            self.blocked_since = now
            self.events.append("obstacle on the path: stopping in front of it")
        self._react(now, pose, p, nav)
        if self.ipo.leg is not leg or self.blocked_since is None:
            return None  # replanned or detoured
        gap = nav.front + float(p("CollLaserMinDist")) + 100.0
        return max(self.ipo.s, self._block - gap)

    def _blocked_at(self, now: float, pose: Pose, seen: Perception, p: Params, nav: Navigator) -> float | None:
        """Arc length on the current Drive leg of the first scan point in the corridor ahead (None: free)."""
        self.obstacles = [o for o in self.obstacles if now - o[3] <= OBSTACLE_MEMORY]
        assert self.ipo is not None
        leg = self.ipo.leg
        if not isinstance(leg, Drive) or len(seen.world) == 0:
            return None
        gap = nav.front + float(p("CollLaserMinDist")) + 100.0
        look = self.ipo.v**2 / (2.0 * float(p("MaxTransAcc"))) + gap + 800.0
        i0 = int(np.searchsorted(leg.s, self.ipo.s))
        i1 = int(np.searchsorted(leg.s, self.ipo.s + look))
        xs, ys = leg.x[i0 : i1 + 1 : 2], leg.y[i0 : i1 + 1 : 2]
        if len(xs) == 0:
            return None
        pts = seen.world
        reach = nav.half_width + CORRIDOR
        box = (
            (pts[:, 0] >= xs.min() - reach)
            & (pts[:, 0] <= xs.max() + reach)
            & (pts[:, 1] >= ys.min() - reach)
            & (pts[:, 1] <= ys.max() + reach)
        )
        pts = pts[box]
        if len(pts) == 0:
            return None
        d = np.hypot(pts[:, 0, None] - xs[None, :], pts[:, 1, None] - ys[None, :])
        hit = d.min(axis=1) <= reach
        if not hit.any():
            return None
        first = int(d[hit].argmin(axis=1).min())
        self._remember(now, seen, pts[hit])
        return float(leg.s[min(i0 + 2 * first, len(leg.s) - 1)])

    def _remember(self, now: float, seen: Perception, hits: F64) -> None:
        """Round obstacles from the scan points around ``hits`` (the whole object, not only its part in the
        corridor); one that overlaps remembered ones is merged with them into the circle enclosing all (each
        view sees only the near side of an object: together they see more of it)."""
        pts = seen.world
        lo, hi = hits.min(axis=0) - CLUSTER_REACH, hits.max(axis=0) + CLUSTER_REACH
        box = np.all((pts >= lo) & (pts <= hi), axis=1)
        near = pts[box]
        d = np.hypot(near[:, 0, None] - hits[None, :, 0], near[:, 1, None] - hits[None, :, 1]).min(axis=1)
        near = near[d <= CLUSTER_REACH]
        for cx, cy, r in _clusters(near, seen.origin):
            keep = []
            for o in self.obstacles:
                if math.hypot(o[0] - cx, o[1] - cy) > o[2] + r:
                    keep.append(o)
                else:
                    cx, cy, r = _enclosing((cx, cy, r), o[:3])
            self.obstacles = [*keep, (cx, cy, r, now)]

    def _react(self, now: float, pose: Pose, p: Params, nav: Navigator) -> None:
        if now < self.next_try or self.blocked_since is None:
            return
        if self.kind == "goto" and self.planning:
            self.next_try = now + REPLAN_EVERY
            plan = nav.plan(pose, self.goal, self._circles())
            self.planner_state = plan.state
            if plan.state == PlannerState.PATH_FOUND:
                self.ipo, self.blocked_since = Interpolator(self._legs(list(plan.points), pose, p, nav)), None
                self.events.append("replanned around an obstacle")
            else:
                self.next_try = now + RETRY_EVERY
        elif self.kind == "path" and now - self.blocked_since >= float(p("PathObstacleWaitTime")) / 1000.0:
            self.next_try = now + RETRY_EVERY
            self._detour(pose, p, nav)

    def _detour(self, pose: Pose, p: Params, nav: Navigator) -> None:
        """guide 4.3: "drive around the obstacle and the target path will be entered again at the next reachable
        place"."""
        assert self.ipo is not None
        ahead = self.ipo.path_points(step=50.0)
        if len(ahead) < 2:
            return
        pts = np.asarray(ahead)
        obs = self._circles()
        blocked = np.zeros(len(pts), dtype=bool)
        for cx, cy, r in obs:
            blocked |= np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) <= r + nav.half_width + CORRIDOR
        if not blocked.any():
            return
        behind = np.flatnonzero(blocked)[-1] + 1
        clear = np.ones(len(pts) - behind, dtype=bool)  # the whole footprint, any heading, clear of them
        for cx, cy, r in obs:
            clear &= np.hypot(pts[behind:, 0] - cx, pts[behind:, 1] - cy) >= r + nav.sweep + CORRIDOR
        ok = np.flatnonzero(nav.free(pts[behind:], obs) & clear)
        if len(ok) == 0:
            self.events.append("obstacle on the path: no place to rejoin the path behind it, waiting")
            return
        k = int(behind + ok[0])
        nxt = pts[min(k + 1, len(pts) - 1)] if k + 1 < len(pts) else pts[k] + (pts[k] - pts[k - 1])
        along = math.atan2(float(nxt[1] - pts[k, 1]), float(nxt[0] - pts[k, 0]))  # the path's direction there
        rejoin = (float(pts[k, 0]), float(pts[k, 1]), along)
        plan = nav.plan(pose, rejoin, obs)
        self.planner_state = plan.state
        if plan.state != PlannerState.PATH_FOUND:
            self.events.append("obstacle on the path: no way around it yet, waiting")
            return
        points = list(plan.points) + [(float(q[0]), float(q[1])) for q in pts[k + 1 :]]
        self.ipo, self.blocked_since = Interpolator(self._legs(points, pose, p, nav)), None
        self.events.append("obstacle on the path: driving around it")

    # ---- the end
    def _settle(self, now: float, pose: Pose, p: Params, measured: tuple[float, float]) -> tuple[float, float]:
        """Position stabilisation (to half the tolerance once started), then the turn, then the verdict at
        standstill (``measured``: the odometry's v, w)."""
        tol_pos = float(p("TargetReachedTolPos"))
        tol_ang = math.radians(float(p("TargetReachedTolAngle")))
        dist = math.hypot(self.goal[0] - pose[0], self.goal[1] - pose[1])
        err = wrap(self.goal[2] - pose[2])
        stab = bool(p("PositionStabilizationEnabled"))
        timeout = self.settle_since is not None and now - self.settle_since > SETTLE_TIMEOUT
        if not timeout:
            if stab and (dist > tol_pos or (self.stabilizing and dist > 0.5 * tol_pos)):
                self.stabilizing = True
                v, w, _ = stabilize(pose, self.goal[:2])
                return v, w
            self.stabilizing = False
            if abs(err) > 0.5 * tol_ang:
                w_max = float(p("IpoRotVel"))
                return 0.0, max(-w_max, min(w_max, SETTLE_TURN_GAIN * err + math.copysign(0.01, err)))
            # guide 4.3 Mode Automatic: "If the target is reached, the platform stops": the verdict once it stands
            if abs(measured[0]) >= STILL_TRANS or abs(measured[1]) >= STILL_ROT:
                return 0.0, 0.0
        self.reached = dist <= tol_pos and abs(err) <= tol_ang
        self.phase = "done"
        self.planner_state = PlannerState.STANDBY
        what = "target reached" if self.reached else "target not reached"
        self.events.append(f"{what}: x {pose[0]:.0f} mm, y {pose[1]:.0f} mm, a {pose[2]:.3f} rad")
        return 0.0, 0.0


def _enclosing(a: tuple[float, float, float], b: tuple[float, float, float]) -> tuple[float, float, float]:
    """The smallest circle holding circles a and b."""
    d = math.hypot(b[0] - a[0], b[1] - a[1])
    if d + b[2] <= a[2]:
        return a
    if d + a[2] <= b[2]:
        return b
    r = 0.5 * (d + a[2] + b[2])
    f = (r - a[2]) / d
    return a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), r


def _clusters(pts: F64, origin: tuple[float, float]) -> list[tuple[float, float, float]]:
    """Round obstacles from points in scan order, split where neighbours are more than CLUSTER_GAP apart.

    Only the near side of an object is seen: for a round one of radius r (half the cluster's width) the
    points' mean lies 2r/pi in front of its centre, seen from ``origin`` (the laser)."""
    if len(pts) == 0:
        return []
    gaps = np.hypot(np.diff(pts[:, 0]), np.diff(pts[:, 1])) > CLUSTER_GAP
    out = []
    for part in np.split(pts, np.flatnonzero(gaps) + 1):
        m = part.mean(axis=0)
        r = max(0.5 * float(np.hypot(*(part[-1] - part[0]))), 50.0)
        view = np.hypot(m[0] - origin[0], m[1] - origin[1])
        c = m + (m - np.asarray(origin)) / max(float(view), 1.0) * (2.0 * r / math.pi)
        r = max(r, float(np.hypot(part[:, 0] - c[0], part[:, 1] - c[1]).max())) + CLUSTER_PAD
        out.append((float(c[0]), float(c[1]), r))
    return out
