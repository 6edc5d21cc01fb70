"""The three benchmark telegrams declared with ``construct``: the declarative baseline.

CMD_MOVE_VEL and CMD_MOVE_PATH (requests) and the CMD_GET_STATUS reply, each as a whole frame (guide 6.2:
header FF 01 FE 02, big-endian uint32 length of the data, data starting with the identifier). Parsing a frame
gives a ``Container`` of the telegram's fields (the header and identifier are ``Const``, so they are checked
but not returned); building takes a dict of the fields, e.g. ``telegram.as_dict()``.

The declarations are what a construct user would write; construct does not check the enum fields of the status
reply (an ``Enum`` would turn the values into strings). ``*_COMPILED`` are the same declarations after
``construct``'s own ``.compile()`` (generated Python code), measured as a second, informational subject.
"""

from __future__ import annotations

from typing import Any

from construct import (
    Array,
    Const,
    Construct,
    Container,
    Float64b,
    FocusedSeq,
    Int8ub,
    Int16sb,
    Int32sb,
    Int32ub,
    ListContainer,
    Prefixed,
    PrefixedArray,
    Struct,
)

HEADER = b"\xff\x01\xfe\x02"


def framed(body: Construct) -> Construct:
    """A frame around telegram data: parse returns the data's fields, build takes them."""
    return FocusedSeq("data", Const(HEADER), "data" / Prefixed(Int32ub, body))


def group(item: Construct) -> Construct:
    """The guide's "INT n, then n times ..." group."""
    return PrefixedArray(Int32sb, item)


MOVE_VEL = Struct(
    Const(24, Int8ub),
    "vel_trans" / Int32sb,
    "vel_rot" / Int32sb,
)

MOVE_PATH = Struct(
    Const(19, Int8ub),
    "frames" / group(Struct("x" / Int32sb, "y" / Int32sb, "angle" / Int32sb)),
)

_POINT = Struct("x" / Int32sb, "y" / Int32sb)

STATUS = Struct(
    Const(18, Int8ub),
    "cmd_x" / Int32sb,
    "cmd_y" / Int32sb,
    "cmd_angle" / Int32sb,
    "est_x" / Int32sb,
    "est_y" / Int32sb,
    "est_angle" / Int32sb,
    "cov_major" / Int32sb,
    "cov_minor" / Int32sb,
    "cov_angle" / Int32sb,
    "cov_axis_angle" / Int32sb,
    "scan" / group(Struct("x" / Int16sb, "y" / Int16sb)),
    "reflectors" / group(_POINT),
    "lines" / group(Struct("target_x" / Int32sb, "target_y" / Int32sb, "source_x" / Int32sb, "source_y" / Int32sb)),
    "circles" / group(Struct("x" / Int32sb, "y" / Int32sb, "radius" / Int32sb)),
    "corners" / group(_POINT),
    "path" / group(_POINT),
    "joystick_buttons" / group(Struct("pressed" / Int8ub)),
    "vel_trans" / Int32sb,
    "vel_rot" / Int32sb,
    "relay_digital_in" / Int32sb,
    "relay_status" / Int32sb,
    "relay_analog_in" / Array(8, Int32sb),
    "relay_opto_distance" / Array(4, Int32sb),
    "io_battery_voltage" / Int32sb,
    "io_digital_in" / Int32sb,
    "io_digital_out" / Int32sb,
    "io_status" / Int32sb,
    "io_analog_in" / Array(8, Int32sb),
    "motor_right_status" / Int32sb,
    "motor_left_status" / Int32sb,
    "motor_right_temp" / Int32sb,
    "motor_left_temp" / Int32sb,
    "us_distance" / Array(16, Int32sb),
    "us_analog_in" / Array(8, Int32sb),
    "us_status" / Int32sb,
    "radar_velocity" / Array(4, Int32sb),
    "radar_status" / Int32sb,
    "gps_latitude" / Float64b,
    "gps_longitude" / Float64b,
    "gyro_accel" / Array(3, Int32sb),
    "gyro_angle" / Int32sb,
    "gyro_temp" / Int32sb,
    "gyro_status" / Int32sb,
    "initialized" / Int8ub,
    "target_reached" / Int8ub,
    "motion_mode" / Int8ub,
    "operation_state" / Int8ub,
    "emergency_state" / Int32sb,
    "application_mode" / Int8ub,
    "planner_state" / Int32sb,
    "timestamp" / Int32sb,
    "app_error" / Int32sb,
    "docked" / Int8ub,
    "localization_lost" / Int8ub,
    "collision" / Int8ub,
    "lookup_percent" / Int8ub,
    "ir_active" / Array(4, Int8ub),
    "siren" / Int8ub,
    "flashlight" / Int8ub,
    "head_position" / Int32sb,
)

MOVE_VEL_FRAME = framed(MOVE_VEL)
MOVE_PATH_FRAME = framed(MOVE_PATH)
STATUS_FRAME = framed(STATUS)

MOVE_VEL_FRAME_COMPILED = MOVE_VEL_FRAME.compile()
MOVE_PATH_FRAME_COMPILED = MOVE_PATH_FRAME.compile()
STATUS_FRAME_COMPILED = STATUS_FRAME.compile()

# the frame head alone, for the stream decoder
FRAME_HEAD = Struct(Const(HEADER), "length" / Int32ub)


class StreamDecoder:
    """Streaming decoder with construct doing all parsing: the head first, then the whole frame once complete."""

    def __init__(self, frame: Construct) -> None:
        self._frame = frame
        self._buf = bytearray()
        self._pos = 0

    def receive_data(self, data: bytes) -> None:
        if self._pos:
            del self._buf[: self._pos]
            self._pos = 0
        self._buf += data

    def __iter__(self) -> Any:
        buf = self._buf
        while len(buf) - self._pos >= 8:
            pos = self._pos
            end = pos + 8 + FRAME_HEAD.parse(buf[pos : pos + 8]).length
            if end > len(buf):
                return
            telegram = self._frame.parse(bytes(buf[pos:end]))
            self._pos = end
            yield telegram


def plain(value: Any) -> Any:
    """A parse result as plain dicts and lists (``_io`` and other private keys dropped), to compare it with
    ``Telegram.as_dict()``."""
    if isinstance(value, Container):
        return {k: plain(v) for k, v in value.items() if not k.startswith("_")}
    if isinstance(value, ListContainer | list):
        return [plain(v) for v in value]
    return value
