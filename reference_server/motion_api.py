"""The seam between the platform and its motion model (guide 4.3): what ``Platform`` calls, and when.

Rules:
- The platform owns one ``MotionModel`` as ``Platform.motion``: today ``kinematics.Drive`` (an ideal
  differential drive without obstacles), later the world simulation of ``reference_server/world/``. Build it
  with ``Platform(..., motion=factory)``, ``factory(params) -> MotionModel``; nothing else constructs one.
- Units: mm, mm/s, rad, rad/s; ``now`` and ``dt`` are simulated seconds. No clock, no I/O, no asyncio.
- Ground truth and estimate are separate. ``true_pose`` is where the body really is (the world's); ``pose`` is
  where the platform believes it is, from odometry (and later localization). GET_STATUS and GET_POSITION
  report the estimate; the controller (``step``) steers on the estimate; only the fault-control channel and
  the tests look at the truth.
- One control period (``Platform.tick``, 50 Hz simulated) is three calls, always in this order:
  1. ``step(now, dt)`` - control: from the active command and the estimate, the wheel setpoints
     (``wheel_setpoints()``, mm/s at the wheel surface, right and left); returns event lines to log.
  2. ``move(right, left, dt)`` - physics: the wheels' true surface velocities move the true body for ``dt``
     (with hardware: what the motor boards report; without: the setpoints themselves). Returns how far each
     wheel really rolled (mm) - less than driven when the body is blocked; the motor boards' encoders count it.
  3. ``odometry(right, left, dt)`` - estimation: the wheel travel the encoders measured (mm, with hardware from
     the encoder frames, so slip and lost frames show here) updates ``pose`` and the measured ``v``/``w``.
- Commands (``command_*``, ``hold``/``resume``/``stop``/``halt``) only change what ``step`` will ask for;
  nothing moves between periods. ``halt`` zeroes the setpoints at once (emergency stop, drive fault,
  shutdown); the boards still decelerate physically.
- The sensor sources (``scan_ranges``, ``us_ranges``, ``imu``) feed the simulated boards and the laser scanner
  from the true state of the world; ``None`` means "no echo anywhere".
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from pltf.fake_hardware.serial_scanner import Ranges

# (x, y) points: pairs, or an (n, 2) array where a model has one already
Points = Sequence[Sequence[float]] | NDArray[np.float64]
Params = Callable[[str], Any]  # ParameterStore.get: parameters are read live, a change takes effect at once


class Frame(NamedTuple):
    x: float  # mm
    y: float  # mm
    angle: float  # rad


@dataclass
class Pose:
    x: float = 0.0
    y: float = 0.0
    angle: float = 0.0

    def frame(self) -> Frame:
        return Frame(self.x, self.y, self.angle)


def normalize(angle: float) -> float:
    """The same angle in (-pi, pi]."""
    a = math.fmod(angle, 2 * math.pi)
    if a <= -math.pi:
        a += 2 * math.pi
    elif a > math.pi:
        a -= 2 * math.pi
    return a


class MotionModel(Protocol):
    """What the platform needs from a motion model; ``kinematics.Drive`` is the reference implementation."""

    # ---- observation (GET_STATUS, GET_POSITION, the router)
    @property
    def pose(self) -> Pose:
        """The estimated pose (odometry; later localization)."""

    @property
    def true_pose(self) -> Pose:
        """The ground truth: where the body is in the world."""

    @property
    def v(self) -> float:
        """Measured translational velocity, mm/s (from the odometry of the last period)."""

    @property
    def w(self) -> float:
        """Measured rotational velocity, rad/s."""

    @property
    def target_reached(self) -> bool:
        """The last path command reached its target (GET_STATUS target_reached)."""

    @property
    def active(self) -> bool:
        """A command is being executed (a velocity within its watchdog, or a path)."""

    def commanded_frame(self) -> Frame:
        """The frame the controller steers to now (the estimated pose when no path is driven)."""

    def remaining_path(self) -> list[Frame]:
        """The waypoints still ahead (GET_STATUS path)."""

    def path_xy(self) -> Points:
        """``remaining_path`` as (x, y) points, in whatever form is cheapest to make: a sequence of pairs or an
        (n, 2) array (GET_STATUS converts it in one numpy pass; a path may hold thousands of points)."""

    def wheel_setpoints(self) -> tuple[float, float]:
        """The wheel surface velocities (right, left) in mm/s that ``step`` decided on."""

    # ---- commands (guide 4.3, 6.3)
    def command_velocity(self, v: float, w: float, now: float, kind: str = "vel") -> None:
        """CMD_MOVE_VEL: ``kind`` "vel" (MODE_MOTION_VEL: kept until VelWatchdogTime) or "joy" (JOYSOFT:
        decays after JoySoftVelTimeout)."""

    def command_wheels(self, right: float, left: float, now: float) -> None:
        """CMD_MOVE_VEL_WHEEL: wheel speeds in mm/s."""

    def command_path(self, frames: list[Frame]) -> None:
        """CMD_MOVE_ABS/REL/PATH/TO_STATION: drive through the frames (world coordinates); preempts."""

    def hold(self) -> None:
        """CMD_BREAK: brake to standstill, keep the command."""

    def resume(self) -> None:
        """CMD_CONTINUE: drive the held command on."""

    def stop(self) -> None:
        """CMD_STOP, CMD_START: end the command and brake to standstill."""

    def halt(self) -> None:
        """Emergency stop, drive fault, CAN shutdown: end the command, setpoints zero at once."""

    def set_pose(self, frame: Frame) -> None:
        """CMD_SET_FRM_PLTF: replace the estimate; the body does not move."""

    def place(self, frame: Frame) -> None:
        """Put the body (truth and estimate) at ``frame``: the start pose at boot."""

    # ---- the control period
    def step(self, now: float, dt: float) -> list[str]:
        """Control: decide the wheel setpoints; event lines to log ("target reached", "watchdog expired")."""

    def move(self, right: float, left: float, dt: float) -> tuple[float, float]:
        """Physics: true wheel velocities (mm/s) for ``dt``; the distances the wheels really rolled (mm)."""

    def odometry(self, right: float, left: float, dt: float) -> None:
        """Estimation: measured wheel travel (mm) over the last period."""

    # ---- sensor sources for the simulated hardware (from the true state)
    def scan_ranges(self, now: float) -> Ranges | None:
        """541 ranges (mm) of the laser scanner, -135..+135 degrees in 0.5 degree steps; None or inf: no echo."""

    def us_ranges(self, now: float) -> Sequence[float | None] | None:
        """16 ultrasonic ranges (mm); None: no echo."""

    def imu(self, now: float) -> tuple[float, float, float, float]:
        """(ax, ay, az in m/s^2, yaw rate in rad/s) of the body, for the gyro board."""


@runtime_checkable
class WorldFeatures(Protocol):
    """What a world adds to a ``MotionModel`` (reference_server/world/model.py ``WorldModel``); the platform looks
    for it with ``isinstance`` and does without it (``kinematics.Drive`` has none of it)."""

    @property
    def planner_state(self) -> int:
        """The planner's state of the last move (guide 6.2 PlannerState)."""

    def set_map_tree(self, tree: Any | None) -> None:
        """The active, validated map (None: no map): walls for the body, the sensors and the planner."""

    def set_mouse_obstacle(self, xy: tuple[float, float] | None) -> None:
        """CMD_MOUSE_MOVE: the mouse obstacle at (x, y) mm, or none."""

    def event(self, event: int, now: float) -> str:
        """CMD_SET_EVENT: post-process recording and replay; a log line."""

    def status_fields(self) -> dict[str, Any]:
        """The CMD_GET_STATUS fields the world fills (covariance, observations, collision, localization)."""


MotionFactory = Callable[[Params], MotionModel]


def advance_ideal(motion: MotionModel, now: float, dt: float) -> list[str]:
    """One control period without hardware: ideal wheels follow the setpoints, ideal encoders measure them."""
    events = motion.step(now, dt)
    travel = motion.move(*motion.wheel_setpoints(), dt)
    motion.odometry(*travel, dt)
    return events
