"""Motion Commands (guide 6.3, 4.3): which move has an effect in which motion mode, then the motion model.

Rules: the state chart allows moves only in Running (and never while the emergency stop or a drive fault
is active); here the motion mode decides (erratum E-SRV-005: a move of the wrong mode is ignored and logged).
Angles arrive as [1000*deg] and go to the motion model in rad.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING, Any

from pltf.reference_server.commands.registry import ACCEPTED, Outcome, handles
from pltf.reference_server.enums import MotionMode, PlannerState
from pltf.reference_server.kinematics import Frame, relative_to_world

if TYPE_CHECKING:
    from pltf.reference_server.platform import Platform


def rad(milli_deg: int) -> float:
    """[1000*deg] of the motion telegrams -> rad."""
    return math.radians(milli_deg / 1000.0)


@handles("CMD_MOVE_VEL_WHEEL")
def move_vel_wheel(p: Platform, t: Any, now: float) -> Outcome:
    # guide 4.3 Mode Velocity: "set ... using the commands CMD_MOVE_VEL_WHEEL or CMD_MOVE_VEL"
    skip = p.unless_mode(t.NAME, MotionMode.MODE_MOTION_VEL)
    if skip is None:
        p.motion.command_wheels(t.vel_right, t.vel_left, now)
    return skip or ACCEPTED


@handles("CMD_MOVE_VEL")
def move_vel(p: Platform, t: Any, now: float) -> Outcome:
    # guide 4.3 Mode Joystick (Software): "set ... using the command CMD MOVE VEL"; [1000*rad/s] = mrad/s
    skip = p.unless_mode(t.NAME, MotionMode.MODE_MOTION_VEL, MotionMode.MODE_MOTION_JOYSOFT)
    if skip is None:
        kind = "joy" if p.motion_mode == MotionMode.MODE_MOTION_JOYSOFT else "vel"
        p.motion.command_velocity(float(t.vel_trans), t.vel_rot / 1000.0, now, kind)
    return skip or ACCEPTED


def drive_path(p: Platform, name: str, frames: list[Frame]) -> Outcome:
    skip = p.unless_mode(name, MotionMode.MODE_MOTION_AUTOMATIC)
    if skip is not None:
        return skip
    if not frames:
        return p.refuse(f"{name}: empty path")
    p.motion.command_path(frames)  # guide 4.3: a new move command preempts the running one
    end = frames[-1]
    p.log(logging.INFO, f"{name}: target x:{end.x:.0f} y:{end.y:.0f} a:{end.angle:.3f}")
    return ACCEPTED


@handles("CMD_MOVE_ABS")
def move_abs(p: Platform, t: Any, now: float) -> Outcome:
    return drive_path(p, t.NAME, [Frame(t.x, t.y, rad(t.angle))])


@handles("CMD_MOVE_REL")
def move_rel(p: Platform, t: Any, now: float) -> Outcome:
    target = relative_to_world(p.motion.pose.frame(), Frame(t.x, t.y, rad(t.angle)))
    return drive_path(p, t.NAME, [target])


@handles("CMD_MOVE_PATH")
def move_path(p: Platform, t: Any, now: float) -> Outcome:
    return drive_path(p, t.NAME, [Frame(f.x, f.y, rad(f.angle)) for f in t.frames])


@handles("CMD_MOVE_TO_STATION")
def move_to_station(p: Platform, t: Any, now: float) -> Outcome:
    # guide 4.3: "The shortest path on the roadmap from the current platform position to the target
    # station is calculated. Following the command CMD_MOVE_PATH is executed."
    skip = p.unless_mode(t.NAME, MotionMode.MODE_MOTION_AUTOMATIC)
    if skip is not None:
        return skip
    if p.roadmap is None:
        return p.refuse(f"{t.NAME}: no active roadmap")
    goal = p.roadmap.find(t.station)
    if goal is None:
        return p.refuse(f"{t.NAME}: no station {t.station!r} in the roadmap")
    pose = p.motion.pose
    start = p.roadmap.nearest(pose.x, pose.y)
    frames = None if start is None else p.roadmap.route(start.id, goal.id)
    if frames is None:
        p.planner_state = PlannerState.PLANNER_NO_PATH
        return p.refuse(f"{t.NAME}: no path on the roadmap to station {t.station!r}")
    p.planner_state = PlannerState.PLANNER_PATH_FOUND
    return drive_path(p, t.NAME, frames)
