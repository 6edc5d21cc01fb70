"""The world as the platform's motion model (reference_server.motion_api.MotionModel), plus what only a world has.

Rules:
- ``WorldModel`` is a ``World`` that speaks the seam's types: ``pose``/``true_pose`` as ``motion_api.Pose``,
  frames as ``motion_api.Frame``, ``v``/``w`` the velocities the odometry measured over the last period.
  Everything else (control, physics, odometry, the sensors' sources) is the World's own, unchanged.
- Beyond the seam the platform tells it about the active map (``set_map_tree``), the mouse obstacle and
  post-process events, and reads the status telegram's world fields from ``status_fields`` (errata E-MOT-003,
  E-MOT-004, E-MOT-006); a plain ``motion_api.MotionModel`` (kinematics.Drive) has none of these, which is why
  they live here and the platform looks for them with ``isinstance``.
- ``factory(seed)`` builds the ``motion_api.MotionFactory`` the platform takes: one seeded world per platform.
"""

from __future__ import annotations

import math
import random
from typing import Any

from pltf.reference_server.motion_api import Frame, MotionFactory, Params, Pose
from pltf.reference_server.world.geometry import MapGeometry
from pltf.reference_server.world.world import World

_MILLI_DEG = 180000.0 / math.pi


def _i32(value: float) -> int:
    return max(-(2**31), min(2**31 - 1, round(value)))


class WorldModel(World):
    # ---- the seam's observation
    @property
    def pose(self) -> Pose:
        return Pose(*self.estimate)

    @property
    def true_pose(self) -> Pose:
        return Pose(*self.truth)

    @property
    def v(self) -> float:
        return self.measured[0]

    @property
    def w(self) -> float:
        return self.measured[1]

    def commanded_frame(self) -> Frame:
        return Frame(*super().commanded_frame())

    def remaining_path(self) -> list[Frame]:  # type: ignore[override]
        return [Frame(x, y, 0.0) for x, y in self.path_xy().tolist()]

    def wheel_setpoints(self) -> tuple[float, float]:
        return self.setpoints

    # ---- the seam's commands (frames are (x, y, angle) tuples already)
    def set_pose(self, frame: Frame) -> None:
        """CMD_SET_FRM_PLTF."""
        self.set_estimate((frame.x, frame.y, frame.angle))

    def place(self, frame: Frame) -> None:  # type: ignore[override]
        super().place((frame.x, frame.y, frame.angle))

    # ---- beyond the seam
    def set_map_tree(self, tree: Any | None) -> None:
        """CMD_SET_MAP / CMD_LOAD_MAP: the validated map (None: no map)."""
        self.set_map(None if tree is None else MapGeometry.from_tree(tree))

    @property
    def planner_state(self) -> int:
        return int(self.motion.planner_state)

    def status_fields(self) -> dict[str, Any]:
        """The CMD_GET_STATUS fields a world fills: covariance, observations, collision, localization."""
        major, minor, angle, axis = self.loc.deviations()
        obs = self.observation()
        return {
            "cov_major": _i32(major),
            "cov_minor": _i32(minor),
            "cov_angle": _i32(angle * _MILLI_DEG),
            "cov_axis_angle": _i32(axis * _MILLI_DEG),
            "scan": obs.scan,
            "reflectors": obs.reflectors,
            "lines": obs.lines,
            "circles": obs.circles,
            "corners": obs.corners,
            "collision": int(self.collision),
            "localization_lost": int(self.loc.lost),
        }


def factory(seed: int | random.Random) -> MotionFactory:
    """A ``motion_api.MotionFactory`` building one ``WorldModel`` seeded from ``seed``."""
    rng = seed if isinstance(seed, random.Random) else random.Random(seed)

    def build(params: Params) -> WorldModel:
        return WorldModel(params, random.Random(rng.getrandbits(64)))

    return build


__all__ = ["WorldModel", "factory"]
