"""Hand-written convenience on the generated reply classes (their bases: ``REPLY_EXTRAS`` in the generator,
clients/stubgen/pltf_client/replies.py).

Rules: properties only, computed from the fields the generated subclass declares (re-declared here as
annotations so mypy can check them); no state, no I/O. Units follow the guide (6.4 CMD_GET_STATUS:
mm and 1000*deg; 6.4 CMD_GET_POSITION: mm and rad, erratum E-REP-012).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from pltf.client._enums import EmergencyState, MotionMode, OperationState, ParamDataType


class Pose(NamedTuple):
    """A platform frame in convenient units: millimetres and degrees.

    Attributes:
        x_mm: X coordinate [mm].
        y_mm: Y coordinate [mm].
        angle_deg: Orientation [deg], counter-clockwise from the x axis.
    """

    x_mm: float
    y_mm: float
    angle_deg: float


class StatusExtras:
    """Properties of ``Status`` (guide 6.4 CMD_GET_STATUS)."""

    est_x_mm: int
    est_y_mm: int
    est_angle_mdeg: int
    cmd_x_mm: int
    cmd_y_mm: int
    cmd_angle_mdeg: int
    operation_state: OperationState
    motion_mode: MotionMode
    emergency_state: EmergencyState

    @property
    def pose(self) -> Pose:
        """The estimated platform frame in mm and degrees."""
        return Pose(float(self.est_x_mm), float(self.est_y_mm), self.est_angle_mdeg / 1000.0)

    @property
    def commanded_pose(self) -> Pose:
        """The commanded platform frame in mm and degrees."""
        return Pose(float(self.cmd_x_mm), float(self.cmd_y_mm), self.cmd_angle_mdeg / 1000.0)

    @property
    def is_ready(self) -> bool:
        """Operation state Ready (initialized, not running: the only state where the mode may change)."""
        return self.operation_state == OperationState.ST_OP_READY

    @property
    def is_running(self) -> bool:
        """Operation state Running (guide "Moving"): the only state in which the platform moves."""
        return self.operation_state == OperationState.ST_OP_RUNNING

    @property
    def emergency_stop_active(self) -> bool:
        """The emergency stop is pressed (ST_EM_ACTIVE)."""
        return self.emergency_state == EmergencyState.ST_EM_ACTIVE


class PositionExtras:
    """Properties of ``Position`` (guide 6.4 CMD_GET_POSITION)."""

    x_mm: int
    y_mm: int
    angle_rad: float

    @property
    def angle_deg(self) -> float:
        """The platform's angle to the x axis in degrees."""
        return math.degrees(self.angle_rad)

    @property
    def pose(self) -> Pose:
        """The estimated platform frame in mm and degrees."""
        return Pose(float(self.x_mm), float(self.y_mm), math.degrees(self.angle_rad))


class ParamExtras:
    """Properties of ``PltfParam`` (guide 6.4 CMD_GET_PLTF_PARAM; value text: errata E-PAR-005, E-PAR-006)."""

    value: str
    data_type: ParamDataType

    @property
    def typed_value(self) -> bool | int | float:
        """The value text read as its data type: BOOLEAN -> bool, INTEGER -> int, DOUBLE -> float.

        Raises:
            ValueError: the text is not a value of that type.
        """
        return parse_param_value(self.data_type, self.value)


_BOOL_TEXT = {"true": True, "1": True, "false": False, "0": False}


def parse_param_value(data_type: ParamDataType, text: str) -> bool | int | float:
    """A parameter value string as ``bool``/``int``/``float`` according to its data type.

    Raises:
        ValueError: the text is not a value of that type.
    """
    text = text.strip()
    if data_type == ParamDataType.BOOLEAN:
        if text.lower() not in _BOOL_TEXT:
            raise ValueError(f"not a BOOLEAN parameter value: {text!r}")
        return _BOOL_TEXT[text.lower()]
    if data_type == ParamDataType.INTEGER:
        return int(text)
    return float(text)


def format_param_value(value: bool | int | float | str) -> str:
    """A value as parameter text: ``true``/``false``, a decimal integer, the shortest float text."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)
