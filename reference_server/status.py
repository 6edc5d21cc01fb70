"""The reply telegrams of guide 6.4, filled from the live platform model.

Rules:
- Every value comes from the model; a board or sensor that does not exist reports ``ABSENT`` in its
  status field and 0 in all its readings, and empty "n times" groups (no scan, no reflectors, ...).
- With the hardware plug-in (reference_server/hardware_link.py) the board sections come from the CAN
  controller's ``BoardStatus`` (fake_hardware/board_status.py; a board not connected stays ABSENT), and the
  observed scan from the serial laser scanner: while it is silent the scan and the features seen in it are
  empty (erratum E-HW-026).
- Units on the wire are the guide's: mm and [1000*deg] as INT in GET_STATUS, rad and rad/s as DOUBLE in
  GET_POSITION (erratum E-REP-012), 1/1000 rad/s for the status' rotation velocity (erratum E-REP-005).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from pltf.spec.codec import REPLIES, encode
from pltf.spec.compiler import distance_from_end
from pltf.spec.model import enum_classes, telegram_def
from pltf.spec.parameters import ParameterError, ParameterStore
from pltf.spec.telegram import Telegram

if TYPE_CHECKING:
    from pltf.reference_server.motion_api import Points
    from pltf.reference_server.platform import Platform

ABSENT = -1  # status of a board that is not on the CAN bus (no reading of it is reported)
# E-REP-020: a platform without a camera answers CMD_GET_CAMERA with empty strings (no invented address)
NO_CAMERA_IP = ""
NO_CAMERA_ID = ""

_I32 = (-(2**31), 2**31 - 1)
AppError: Any = enum_classes()["AppError"]


def reply(telegram_name: str, /, **fields: Any) -> Telegram:
    """The reply telegram ``telegram_name`` (classes are built from the spec at import, untyped for mypy)."""
    cls: Any = REPLIES.by_name[telegram_name]
    return cast(Telegram, cls(**fields))


def _i32(value: float) -> int:
    """Round to the nearest INT, saturated to 32 bits."""
    return max(_I32[0], min(_I32[1], round(value)))


def _i32_points(frames: Points) -> tuple[tuple[int, int], ...]:
    """The (x, y) of each frame as ``_i32`` does it (round half to even, saturated), in one numpy pass: the
    interpolated path of the status telegram may hold thousands of points. ``frames`` may be an array."""
    if len(frames) == 0:
        return ()
    xy = np.clip(np.rint(np.asarray(frames, dtype=np.float64)[:, :2]), *_I32).astype(np.int64)
    return tuple(map(tuple, xy.tolist()))


def _milli_deg(rad: float) -> int:
    return _i32(math.degrees(rad) * 1000.0)


def status_reply(p: Platform, now: float) -> Telegram:
    """The status at the platform's last change (``Platform.epoch``), stamped ``now``."""
    return _cached(p)[0](now)


def status_frame(p: Platform, now: float) -> tuple[Telegram, bytes]:
    """``status_reply`` and its frame. The frame is encoded once per epoch and only its timestamp is replaced:
    a fuzzer's or a client's GET_STATUS between two control periods costs no encoding of the 541-beam scan.
    Only fixed-size fields follow the timestamp (guide 6.4), so it sits at a fixed distance from the frame's
    end however long the scan and the path before it are."""
    make, frame = _cached(p)
    telegram = make(now)
    at = len(frame) - _TS_FROM_END
    return telegram, frame[:at] + _TS.pack(_timestamp(now)) + frame[at + _TS.size :]


def _timestamp_from_end() -> int:
    """Bytes from the status timestamp's first byte to the frame's end, from the spec's layout."""
    distance = distance_from_end(telegram_def("CMD_GET_STATUS").layout("reply") or (), "timestamp")
    assert distance is not None, "the fields from the status timestamp on must have fixed sizes"
    return distance


_TS = struct.Struct(">i")
_TS_FROM_END = _timestamp_from_end()


def _timestamp(now: float) -> int:
    return int(now * 1000.0) % 2**31  # erratum E-REP-010


def _cached(p: Platform) -> tuple[Callable[[float], Telegram], bytes]:
    cached = p.status_cache
    if cached is None or cached[0] != p.epoch:
        fields = _status_fields(p)

        def make(now: float) -> Telegram:
            return reply("CMD_GET_STATUS", **fields, timestamp=_timestamp(now))

        zero = encode(reply("CMD_GET_STATUS", **fields, timestamp=0))
        cached = p.status_cache = (p.epoch, make, zero)
    return cached[1], cached[2]


def _status_fields(p: Platform) -> dict[str, Any]:
    cmd = p.motion.commanded_frame()
    pose = p.motion.pose
    flag = int
    fields: dict[str, Any] = dict(  # noqa: C408 - the telegram's field names, as keywords
        cmd_x=_i32(cmd.x),
        cmd_y=_i32(cmd.y),
        cmd_angle=_milli_deg(cmd.angle),
        est_x=_i32(pose.x),
        est_y=_i32(pose.y),
        est_angle=_milli_deg(pose.angle),
        # without a world (kinematics.Drive): no localization, the estimate is exact, its deviations 0
        cov_major=0,
        cov_minor=0,
        cov_angle=0,
        cov_axis_angle=0,
        scan=(),
        reflectors=(),
        lines=(),
        circles=(),
        corners=(),  # without a world: no laser scanner
        path=_i32_points(p.motion.path_xy()),
        joystick_buttons=(),  # no joystick
        vel_trans=_i32(p.motion.v),
        vel_rot=_i32(p.motion.w * 1000.0),
        relay_digital_in=0,
        relay_status=ABSENT,
        relay_analog_in=(0,) * 8,
        relay_opto_distance=(0,) * 4,
        io_battery_voltage=0,
        io_digital_in=0,
        io_digital_out=0,
        io_status=ABSENT,
        io_analog_in=(0,) * 8,
        motor_right_status=ABSENT,
        motor_left_status=ABSENT,
        motor_right_temp=0,
        motor_left_temp=0,
        us_distance=(0,) * 16,
        us_analog_in=(0,) * 8,
        us_status=ABSENT,
        radar_velocity=(0,) * 4,
        radar_status=ABSENT,
        gps_latitude=0.0,
        gps_longitude=0.0,  # no GPS receiver (the section has no status field)
        gyro_accel=(0,) * 3,
        gyro_angle=0,
        gyro_temp=0,
        gyro_status=ABSENT,
        initialized=flag(p.chart.initialized),
        target_reached=flag(p.motion.target_reached),
        motion_mode=p.motion_mode,
        operation_state=p.chart.operation_state,
        emergency_state=p.chart.emergency,
        application_mode=0,  # guide: "not used at the moment"
        planner_state=p.planner_state,
        app_error=AppError.APP_ERR_NONE,
        docked=0,
        localization_lost=0,
        collision=0,
        lookup_percent=0,
        ir_active=(0,) * 4,  # no IR sensors
        siren=flag(bool(p.params.get("SirenEnabled"))),
        flashlight=flag(bool(p.params.get("FlashlightEnabled"))),
        head_position=p.head_position,  # erratum E-TASK-017
    )
    if p.world is not None:  # localization, observations, collision (errata E-MOT-003, E-MOT-004, E-MOT-006)
        fields.update(p.world.status_fields())
    if p.hardware is not None:
        fields.update(p.hardware.board_fields())
        scan = p.hardware.scan_points(float(getattr(p.motion, "front", 0.0)))
        if scan == ():  # the scanner is silent: nothing the laser sees is reported (erratum E-HW-026)
            fields.update(scan=(), reflectors=(), lines=(), circles=(), corners=())
        elif scan is not None and p.world is not None:
            fields["scan"] = scan
    return fields


def position_reply(p: Platform) -> Telegram:
    pose = p.motion.pose
    return reply(
        "CMD_GET_POSITION",
        x=_i32(pose.x),
        y=_i32(pose.y),
        angle=pose.angle,
        vel_trans=float(p.motion.v),
        vel_rot=float(p.motion.w),
    )


def _param_fields(store: ParameterStore, name: str) -> tuple[str, str, int, int, int, int]:
    row = store.parameter(name)
    lo, hi = row.wire_bounds()
    return row.name, store.get_text(name), int(row.category), int(row.type), lo, hi


def param_reply(store: ParameterStore, key: str) -> Telegram:
    """An unknown key is answered with the key, an empty value and zeros (no parameter has an empty value)."""
    try:
        fields = _param_fields(store, key)
    except ParameterError:
        fields = (key, "", 0, 0, 0, 0)
    key, value, category, data_type, minimum, maximum = fields
    return reply(
        "CMD_GET_PLTF_PARAM",
        key=key,
        value=value,
        category=category,
        data_type=data_type,
        minimum=minimum,
        maximum=maximum,
    )


def param_vec_reply(store: ParameterStore) -> Telegram:
    return reply("CMD_GET_PLTF_PARAM_VEC", parameters=tuple(_param_fields(store, row.name) for row, _ in store.items()))


def debug_reply(p: Platform) -> Telegram:
    safe = _i32(float(p.params.get("MaxTransVel")))  # no sensor restricts the velocity
    return reply(
        "CMD_GET_DEBUG_DATA",
        validation_gate=(),
        mapping_mode=int(p.mapping),
        mapped_segments=(),
        explored_segments=(),
        global_localization=(),
        visible_lines=(),
        global_validation_gate=(),
        debug_path=(),
        graphics=(),
        variables=(),
        moving_clusters=(),
        person_clusters=(),
        ball_clusters=(),
        protocol_queue=tuple((entry,) for entry in p.protocol_queue),
        # TCP statistics are not measured (the network shell keeps none yet)
        tcp_avg_receive_time=0,
        tcp_receive_time_percent=0,
        tcp_avg_send_time=0,
        tcp_send_time_percent=0,
        tcp_received_bytes_per_s=0,
        tcp_sent_bytes_per_s=0,
        tcp_received_telegrams_per_s=0,
        tcp_sent_telegrams_per_s=0,
        tcp_avg_wait_time=0,
        tcp_wait_time_percent=0,
        safe_vel_laser_forward=safe,
        safe_vel_laser_backward=safe,
        safe_vel_us_forward=safe,
        safe_vel_us_backward=safe,
        safe_vel_optocoupler=safe,
    )


def camera_reply() -> Telegram:
    return reply("CMD_GET_CAMERA", ip=NO_CAMERA_IP, camera_id=NO_CAMERA_ID)
