"""The interpolator and the controller (guide 4.1 "The interpolator generates smooth and continuous movements").

Rules (erratum E-MOT-008):
- The interpolator moves a reference frame along the legs of a path: on a Drive leg at a speed up to
  IpoTransVel, limited by the curvature (speed * curvature <= IpoRotVel), accelerating with MaxTransAcc and
  braking so it stands at the leg's end (a backward pass over the samples); on a Turn leg it turns at up to
  IpoRotVel with MaxRotAcc. It waits while the platform lags more than ``LAG`` mm behind, and stops in
  front of a point the caller names (an obstacle).
- The controller makes the platform follow the reference: Kanayama's tracking law on Drive legs, with gains
  from PathFollowParam1 (lateral, 1e-5 / mm^2 per unit) and PathFollowParam2 (heading, 1.2e-2 / mm per unit);
  a proportional heading law on Turn legs; at the end, PositionStabilizationEnabled drives the last
  millimetres onto the target (forwards or backwards) before the end turn.
- Commanded frame (status): the reference frame; interpolated path (status): the remaining legs' points.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pltf.reference_server.world.geometry import F64
from pltf.reference_server.world.paths import Drive, Leg, Turn, sample_points, wrap

Params = Callable[[str], Any]

LAG = 300.0  # mm
K_ALONG = 1.5  # 1/s: along-track gain
K_LAT = 1e-5  # 1/mm^2 per unit of PathFollowParam1
K_HEAD = 1.2e-2  # 1/mm per unit of PathFollowParam2: damping ~0.95 with the defaults (K_HEAD / 2 sqrt(K_LAT))
K_TURN = 3.0  # 1/s on Turn legs
BRAKE = 0.75  # the reference brakes at this share of MaxTransAcc: the platform, catching up, still can
STAB_GAIN = 1.0  # 1/s
STAB_VEL = 150.0  # mm/s at most while stabilising


@dataclass(frozen=True)
class Ref:
    x: float
    y: float
    theta: float
    v: float
    w: float


def _profile(leg: Drive, v_max: float, w_max: float, acc: float) -> F64:
    """The highest reference speed at each sample: curvature, and braking to 0 at the leg's end."""
    with np.errstate(divide="ignore"):
        lim = np.minimum(v_max, w_max / np.abs(leg.kappa))
    lim[-1] = 0.0
    ds = np.diff(leg.s)
    out = lim.copy()
    for i in range(len(out) - 2, -1, -1):  # backward pass (samples are few: 50 per metre)
        out[i] = min(out[i], math.sqrt(out[i + 1] ** 2 + 2.0 * BRAKE * acc * ds[i]))
    return out


@dataclass
class Interpolator:
    legs: list[Leg]
    index: int = 0
    s: float = 0.0  # along the current Drive leg
    angle: float = 0.0  # on the current Turn leg
    v: float = 0.0
    w: float = 0.0
    _profile_key: tuple[float, ...] = ()
    _profile: F64 = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        self._enter()

    @property
    def done(self) -> bool:
        return self.index >= len(self.legs)

    @property
    def leg(self) -> Leg | None:
        return None if self.done else self.legs[self.index]

    def _enter(self) -> None:
        self.s, self.v, self.w, self._profile_key = 0.0, 0.0, 0.0, ()
        leg = self.leg
        if isinstance(leg, Turn):
            self.angle = leg.start

    def step(self, dt: float, params: Params, hold: bool = False, stop_at: float | None = None) -> None:
        """Advance the reference by ``dt``; ``hold``: stand still; ``stop_at``: arc length to stop before."""
        leg = self.leg
        if leg is None:
            return
        if isinstance(leg, Turn):
            alpha, w_max = float(params("MaxRotAcc")), float(params("IpoRotVel"))
            left = leg.end - self.angle
            allowed = 0.0 if hold else min(w_max, math.sqrt(2.0 * alpha * abs(left)))
            self.w = min(self.w + alpha * dt, allowed)
            step = self.w * dt
            if abs(left) <= max(step, 1e-4) and not hold:
                self.index += 1
                self._enter()
                return
            self.angle += math.copysign(step, left)
            return
        acc = float(params("MaxTransAcc"))
        key = (float(params("IpoTransVel")), float(params("IpoRotVel")), acc)
        if key != self._profile_key:
            self._profile_key, self._profile = key, _profile(leg, *key)
        left = leg.length - self.s
        # a floor of 20 mm/s so the end is reached in finite time (the profile is linear between samples)
        allowed = max(float(np.interp(self.s, leg.s, self._profile)), min(20.0, left / dt))
        if stop_at is not None:
            allowed = min(allowed, math.sqrt(2.0 * acc * max(0.0, stop_at - self.s)))
        if hold:
            allowed = 0.0
        self.v = min(self.v + acc * dt, allowed)
        self.s = min(self.s + self.v * dt, leg.length)
        if self.s >= leg.length - 1e-6:
            self.index += 1
            self._enter()

    def reference(self, fallback: tuple[float, float, float]) -> Ref:
        leg = self.leg
        if leg is None:
            return Ref(*fallback, 0.0, 0.0)
        if isinstance(leg, Turn):
            return Ref(leg.x, leg.y, wrap(self.angle), 0.0, math.copysign(self.w, leg.end - self.angle))
        x, y, th, kappa = leg.at(self.s)
        return Ref(x, y, th, self.v, self.v * kappa)

    def remaining(self) -> list[Leg]:
        """The legs still ahead, the current Drive leg cut at the reference."""
        if self.done:
            return []
        leg = self.legs[self.index]
        rest = self.legs[self.index + 1 :]
        if isinstance(leg, Drive):
            i = int(np.searchsorted(leg.s, self.s))
            if i < len(leg.s) - 1:
                leg = Drive(leg.x[i:], leg.y[i:], leg.theta[i:], leg.s[i:] - leg.s[i], leg.kappa[i:])
                return [leg, *rest]
            return list(rest)
        return [leg, *rest]

    def path_points(self, step: float = 100.0) -> F64:
        return sample_points(self.remaining(), step)


# ---------------------------------------------------------------------------------------------- controller


def errors(pose: tuple[float, float, float], ref: Ref) -> tuple[float, float, float]:
    """The reference in the platform frame: along, lateral, heading."""
    x, y, a = pose
    c, s = math.cos(a), math.sin(a)
    dx, dy = ref.x - x, ref.y - y
    return c * dx + s * dy, -s * dx + c * dy, wrap(ref.theta - a)


def track(pose: tuple[float, float, float], ref: Ref, turning: bool, params: Params) -> tuple[float, float]:
    """(v, w) that make the platform follow the reference (Kanayama on Drive legs)."""
    ex, ey, eth = errors(pose, ref)
    if turning:
        return K_ALONG * ex, ref.w + K_TURN * eth
    k_lat = K_LAT * float(params("PathFollowParam1"))
    k_head = K_HEAD * float(params("PathFollowParam2"))
    v = ref.v * math.cos(eth) + K_ALONG * ex
    # the heading term uses |v| so driving backwards (a replayed recording) corrects the heading too
    w = ref.w + ref.v * k_lat * ey + abs(ref.v) * k_head * math.sin(eth) + (K_TURN * eth if abs(ref.v) < 1.0 else 0.0)
    return v, w


def stabilize(
    pose: tuple[float, float, float], target: tuple[float, float], v_max: float = STAB_VEL
) -> tuple[float, float, float]:
    """Posture stabilisation onto a point: (v, w, distance); drives backwards to a point behind."""
    x, y, a = pose
    dx, dy = target[0] - x, target[1] - y
    dist = math.hypot(dx, dy)
    along = math.cos(a) * dx + math.sin(a) * dy
    bearing = wrap(math.atan2(dy, dx) - a)
    if along < 0:
        bearing = wrap(bearing + math.pi)
    v = math.copysign(min(v_max, STAB_GAIN * dist), along) * max(0.0, math.cos(bearing))
    return v, K_TURN * bearing * min(1.0, dist / 50.0), dist
