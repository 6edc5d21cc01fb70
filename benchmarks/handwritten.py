"""Hand-written ``struct`` codecs of three telegrams: the baseline our spec-compiled codec is measured against.

What a careful engineer would write by hand for CMD_MOVE_VEL (request), CMD_MOVE_PATH (request) and the
CMD_GET_STATUS reply (guide 6.2 framing; 6.3 CMD_MOVE_VEL, CMD_MOVE_PATH; 6.4 CMD_GET_STATUS), with every
``struct.Struct`` precompiled at import. To keep the comparison fair they do the same work as
``pltf.spec.codec``:

- the results are of the same kind: a named tuple per telegram with the same field names, groups as tuples of
  named tuples, repeated fields as tuples, plain ints and floats (so ``tuple(ours) == tuple(handwritten)``);
- the same checks: header, frame length, identifier, group counts against the bytes that remain, trailing
  bytes, and the enum / BOOL / range checks of the status fields (on decode and on encode).

Decoders of telegram data take ``(buf, start, end)``, ``start`` being the offset of the identifier byte, so a
stream decoder can decode in place; ``decode_*_frame(frame)`` decode one whole frame.
"""

from __future__ import annotations

import struct
from collections import namedtuple
from collections.abc import Callable, Iterator
from typing import Any

HEADER = b"\xff\x01\xfe\x02"
_FRAME_HEAD = struct.Struct(">4sI")
_COUNT = struct.Struct(">i")
_ID_COUNT = struct.Struct(">Bi")

MOVE_VEL_ID = 24
MOVE_PATH_ID = 19
GET_STATUS_ID = 18


class DecodeError(ValueError):
    """Malformed bytes."""


class EncodeError(ValueError):
    """A value that cannot be sent."""


# ---------------------------------------------------------------------------------------------- result types

MoveVel = namedtuple("MoveVel", "vel_trans vel_rot")
PathFrame = namedtuple("PathFrame", "x y angle")
MovePath = namedtuple("MovePath", "frames")
ScanPoint = namedtuple("ScanPoint", "x y")
Point = namedtuple("Point", "x y")
ObservedLine = namedtuple("ObservedLine", "target_x target_y source_x source_y")
Circle = namedtuple("Circle", "x y radius")
Button = namedtuple("Button", "pressed")
Status = namedtuple(
    "Status",
    [
        "cmd_x",
        "cmd_y",
        "cmd_angle",
        "est_x",
        "est_y",
        "est_angle",
        "cov_major",
        "cov_minor",
        "cov_angle",
        "cov_axis_angle",
        "scan",
        "reflectors",
        "lines",
        "circles",
        "corners",
        "path",
        "joystick_buttons",
        "vel_trans",
        "vel_rot",
        "relay_digital_in",
        "relay_status",
        "relay_analog_in",
        "relay_opto_distance",
        "io_battery_voltage",
        "io_digital_in",
        "io_digital_out",
        "io_status",
        "io_analog_in",
        "motor_right_status",
        "motor_left_status",
        "motor_right_temp",
        "motor_left_temp",
        "us_distance",
        "us_analog_in",
        "us_status",
        "radar_velocity",
        "radar_status",
        "gps_latitude",
        "gps_longitude",
        "gyro_accel",
        "gyro_angle",
        "gyro_temp",
        "gyro_status",
        "initialized",
        "target_reached",
        "motion_mode",
        "operation_state",
        "emergency_state",
        "application_mode",
        "planner_state",
        "timestamp",
        "app_error",
        "docked",
        "localization_lost",
        "collision",
        "lookup_percent",
        "ir_active",
        "siren",
        "flashlight",
        "head_position",
    ],
)


# ---------------------------------------------------------------------------------------------- framing


def _unframe(frame: bytes) -> int:
    """Check header and length of a single frame; return the end of its data."""
    if len(frame) < 8:
        raise DecodeError("shorter than a frame header")
    head, length = _FRAME_HEAD.unpack_from(frame)
    if head != HEADER:
        raise DecodeError(f"bad header {head.hex()}")
    if length != len(frame) - 8:
        raise DecodeError(f"length field {length}, but {len(frame) - 8} data bytes")
    return len(frame)


def _framed(data: bytes) -> bytes:
    return _FRAME_HEAD.pack(HEADER, len(data)) + data


# ---------------------------------------------------------------------------------------------- CMD_MOVE_VEL

_MOVE_VEL = struct.Struct(">Bii")
_MOVE_VEL_FRAME = struct.Struct(">4sIBii")


def decode_move_vel(buf: Any, start: int, end: int) -> MoveVel:
    if end - start != _MOVE_VEL.size:
        raise DecodeError(f"CMD_MOVE_VEL of {end - start} bytes")
    ident, vel_trans, vel_rot = _MOVE_VEL.unpack_from(buf, start)
    if ident != MOVE_VEL_ID:
        raise DecodeError(f"identifier {ident}")
    return MoveVel(vel_trans, vel_rot)


def decode_move_vel_frame(frame: bytes) -> MoveVel:
    return decode_move_vel(frame, 8, _unframe(frame))


def encode_move_vel(t: MoveVel) -> bytes:
    try:
        return _MOVE_VEL_FRAME.pack(HEADER, _MOVE_VEL.size, MOVE_VEL_ID, t[0], t[1])
    except struct.error as exc:
        raise EncodeError(str(exc)) from None


# ---------------------------------------------------------------------------------------------- CMD_MOVE_PATH

_PATH_FRAME = struct.Struct(">iii")


def decode_move_path(buf: Any, start: int, end: int) -> MovePath:
    if end - start < _ID_COUNT.size:
        raise DecodeError("CMD_MOVE_PATH shorter than its count")
    ident, n = _ID_COUNT.unpack_from(buf, start)
    if ident != MOVE_PATH_ID:
        raise DecodeError(f"identifier {ident}")
    pos = start + _ID_COUNT.size
    if n < 0 or n * 12 != end - pos:
        raise DecodeError(f"CMD_MOVE_PATH: {n} frames in {end - pos} bytes")
    return MovePath(tuple(map(PathFrame._make, _PATH_FRAME.iter_unpack(buf[pos:end]))))


def decode_move_path_frame(frame: bytes) -> MovePath:
    return decode_move_path(frame, 8, _unframe(frame))


def encode_move_path(t: MovePath) -> bytes:
    frames = t[0]
    pack = _PATH_FRAME.pack
    try:
        data = b"".join([_ID_COUNT.pack(MOVE_PATH_ID, len(frames)), *[pack(*f) for f in frames]])
    except (struct.error, TypeError) as exc:
        raise EncodeError(str(exc)) from None
    return _framed(data)


# ---------------------------------------------------------------------------------------------- CMD_GET_STATUS

_STATUS_HEAD = struct.Struct(">B10i")  # identifier, commanded frame, estimated frame, covariance
_SCAN_POINT = struct.Struct(">hh")
_POINT = struct.Struct(">ii")
_LINE = struct.Struct(">iiii")
_CIRCLE = struct.Struct(">iii")
_BUTTON = struct.Struct(">B")
_STATUS_TAIL = struct.Struct(
    ">"
    "ii"  # vel_trans, vel_rot
    "ii8i4i"  # relay board: digital_in, status, analog_in[8], opto_distance[4]
    "iiii8i"  # io board: battery_voltage, digital_in, digital_out, status, analog_in[8]
    "iiii"  # motors: right/left status, right/left temperature
    "16i8ii"  # ultrasonic: distance[16], analog_in[8], status
    "4ii"  # radar: velocity[4], status
    "dd"  # gps latitude, longitude
    "3iiii"  # gyro: accel[3], angle, temp, status
    "BBBB"  # initialized, target_reached, motion_mode, operation_state
    "iBiii"  # emergency_state (INT), application_mode, planner_state, timestamp, app_error
    "BBBB4BBB"  # docked, localization_lost, collision, lookup_percent, ir_active[4], siren, flashlight
    "i"  # head_position
)
assert _STATUS_TAIL.size == 323

# value sets of guide 6.4 (spec/enums.yaml): Flag, MotionMode, OperationState, EmergencyState, PlannerState,
# AppError
_FLAG = frozenset((0, 1))
_MOTION_MODE = frozenset(range(7))
_OPERATION_STATE = frozenset(range(4))
_EMERGENCY_STATE = frozenset(range(3))
_PLANNER_STATE = frozenset(range(6))
_APP_ERROR = frozenset((0, 1))


def _group(buf: Any, pos: int, end: int, item: struct.Struct, cls: Any) -> tuple[tuple[Any, ...], int]:
    """Decode an INT count and that many fixed-size items at ``pos``; return (items, new pos)."""
    if end - pos < 4:
        raise DecodeError("CMD_GET_STATUS truncated before a count")
    (n,) = _COUNT.unpack_from(buf, pos)
    pos += 4
    stop = pos + n * item.size
    if n < 0 or stop > end:
        raise DecodeError(f"CMD_GET_STATUS: count {n} but only {end - pos} bytes remain")
    return tuple(map(cls._make, item.iter_unpack(buf[pos:stop]))), stop


def decode_status(buf: Any, start: int, end: int) -> Status:
    if end - start < _STATUS_HEAD.size:
        raise DecodeError("CMD_GET_STATUS truncated")
    head = _STATUS_HEAD.unpack_from(buf, start)
    if head[0] != GET_STATUS_ID:
        raise DecodeError(f"identifier {head[0]}")
    pos = start + _STATUS_HEAD.size
    scan, pos = _group(buf, pos, end, _SCAN_POINT, ScanPoint)
    reflectors, pos = _group(buf, pos, end, _POINT, Point)
    lines, pos = _group(buf, pos, end, _LINE, ObservedLine)
    circles, pos = _group(buf, pos, end, _CIRCLE, Circle)
    corners, pos = _group(buf, pos, end, _POINT, Point)
    path, pos = _group(buf, pos, end, _POINT, Point)
    buttons, pos = _group(buf, pos, end, _BUTTON, Button)
    if end - pos != _STATUS_TAIL.size:
        raise DecodeError(f"CMD_GET_STATUS: {end - pos} bytes after the groups, expected {_STATUS_TAIL.size}")
    if not _FLAG.issuperset([b[0] for b in buttons]):
        raise DecodeError("CMD_GET_STATUS: a joystick button is neither 0 nor 1")
    v = _STATUS_TAIL.unpack_from(buf, pos)
    if not (
        v[70] in _FLAG
        and v[71] in _FLAG
        and v[72] in _MOTION_MODE
        and v[73] in _OPERATION_STATE
        and v[74] in _EMERGENCY_STATE
        and v[76] in _PLANNER_STATE
        and v[78] in _APP_ERROR
        and v[79] in _FLAG
        and v[80] in _FLAG
        and v[81] in _FLAG
        and 0 <= v[82] <= 99
        and _FLAG.issuperset(v[83:87])
        and v[87] in _FLAG
        and v[88] in _FLAG
    ):
        raise DecodeError("CMD_GET_STATUS: a status field is out of range")
    return Status._make(
        (
            *head[1:],
            scan,
            reflectors,
            lines,
            circles,
            corners,
            path,
            buttons,
            *v[0:4],
            v[4:12],
            v[12:16],  # velocities, relay board
            *v[16:20],
            v[20:28],  # io board
            *v[28:32],  # motors
            v[32:48],
            v[48:56],
            v[56],  # ultrasonic
            v[57:61],
            *v[61:64],  # radar, gps
            v[64:67],
            *v[67:83],  # gyro, state bytes up to lookup_percent
            v[83:87],
            *v[87:90],  # ir_active, siren, flashlight, head_position
        )
    )


def decode_status_frame(frame: bytes) -> Status:
    return decode_status(frame, 8, _unframe(frame))


def _pack_group(parts: list[bytes], items: Any, item: struct.Struct) -> None:
    parts.append(_COUNT.pack(len(items)))
    pack = item.pack
    parts.extend([pack(*x) for x in items])


def encode_status(t: Status) -> bytes:
    if not (
        _FLAG.issuperset([b[0] for b in t[16]])
        and t[43] in _FLAG
        and t[44] in _FLAG
        and t[45] in _MOTION_MODE
        and t[46] in _OPERATION_STATE
        and t[47] in _EMERGENCY_STATE
        and t[49] in _PLANNER_STATE
        and t[51] in _APP_ERROR
        and t[52] in _FLAG
        and t[53] in _FLAG
        and t[54] in _FLAG
        and 0 <= t[55] <= 99
        and _FLAG.issuperset(t[56])
        and t[57] in _FLAG
        and t[58] in _FLAG
    ):
        raise EncodeError("CMD_GET_STATUS: a status field is out of range")
    try:
        parts = [_STATUS_HEAD.pack(GET_STATUS_ID, *t[0:10])]
        _pack_group(parts, t[10], _SCAN_POINT)
        _pack_group(parts, t[11], _POINT)
        _pack_group(parts, t[12], _LINE)
        _pack_group(parts, t[13], _CIRCLE)
        _pack_group(parts, t[14], _POINT)
        _pack_group(parts, t[15], _POINT)
        _pack_group(parts, t[16], _BUTTON)
        parts.append(
            _STATUS_TAIL.pack(
                *t[17:21],
                *t[21],
                *t[22],  # velocities, relay board
                *t[23:27],
                *t[27],  # io board
                *t[28:32],  # motors
                *t[32],
                *t[33],
                t[34],  # ultrasonic
                *t[35],
                *t[36:39],  # radar, gps
                *t[39],
                *t[40:56],  # gyro, state fields up to lookup_percent
                *t[56],
                *t[57:60],  # ir_active, siren, flashlight, head_position
            )
        )
    except (struct.error, TypeError) as exc:
        raise EncodeError(str(exc)) from None
    return _framed(b"".join(parts))


# ---------------------------------------------------------------------------------------------- stream decoder

DataDecoder = Callable[[Any, int, int], Any]
REQUEST_DECODERS: dict[int, DataDecoder] = {MOVE_VEL_ID: decode_move_vel, MOVE_PATH_ID: decode_move_path}
REPLY_DECODERS: dict[int, DataDecoder] = {GET_STATUS_ID: decode_status}


class StreamDecoder:
    """Hand-written streaming decoder: frames split or coalesced anyhow, dispatched on the identifier byte."""

    def __init__(self, decoders: dict[int, DataDecoder], max_length: int = 16 * 1024 * 1024) -> None:
        self._decoders = decoders
        self._max = max_length
        self._buf = bytearray()
        self._pos = 0

    def receive_data(self, data: bytes) -> None:
        if self._pos:
            del self._buf[: self._pos]
            self._pos = 0
        self._buf += data

    def __iter__(self) -> Iterator[Any]:
        buf, pos = self._buf, self._pos
        size = len(buf)
        unpack_head = _FRAME_HEAD.unpack_from
        decoders = self._decoders
        try:
            while size - pos >= 8:
                head, length = unpack_head(buf, pos)
                if head != HEADER:
                    raise DecodeError(f"bad header {head.hex()}")
                if length > self._max:
                    raise DecodeError(f"frame length {length}")
                start = pos + 8
                end = start + length
                if end > size:
                    break
                if length == 0:
                    raise DecodeError("frame without an identifier")
                dec = decoders.get(buf[start])
                if dec is None:
                    raise DecodeError(f"unknown identifier {buf[start]}")
                telegram = dec(buf, start, end)
                pos = end
                self._pos = pos
                yield telegram
        finally:
            self._pos = pos
