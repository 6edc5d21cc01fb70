"""Codec rates: ``pltf.spec.codec`` side by side with a hand-written ``struct`` codec and with ``construct``.

Telegrams: CMD_MOVE_VEL (a small command), CMD_MOVE_PATH with 100 frames, and a full CMD_GET_STATUS reply
with 541 scan points (a 270-degree scanner at 0.5 degrees), 3 reflectors, 4 lines, 2 circles, 5 corners, a
50-frame path and 12 joystick buttons.

Targets (issue "codec rates"): >= 300,000 small telegrams/s decoded on one core; the status telegram decoded
within 1.5x the time of the hand-written decoder and >= 10x faster than ``construct``.

Subjects: ``pltf.spec.codec`` (ours: ``decode_frame`` / ``TelegramDecoder`` / ``encode``), ``handwritten``
(``benchmarks.handwritten``), ``construct`` (``benchmarks.construct_defs``) and ``construct.compile`` (the same
declarations compiled by construct, for information).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial
from typing import Any

from benchmarks import construct_defs as cs
from benchmarks import handwritten as hw
from benchmarks.harness import Config, Row, Target, benchmark, median_rates, rate_rows
from pltf.spec.codec import REPLIES, REQUESTS, TelegramDecoder, decode_frame, encode
from pltf.spec.telegram import Telegram, plain

OURS = "pltf.spec.codec"
HANDWRITTEN = "handwritten"
CONSTRUCT = "construct"
CONSTRUCT_COMPILED = "construct.compile"

SMALL_RATE_TARGET = 300_000  # telegrams/s
STATUS_VS_HANDWRITTEN = 1.5  # max time ratio
CONSTRUCT_VS_STATUS = 10.0  # min time ratio

STREAM_FRAMES = 100_000
STREAM_FRAMES_QUICK = 2_000
CHUNK = 4096

# ---------------------------------------------------------------------------------------------- the telegrams


def small_telegram() -> Telegram:
    return REQUESTS.CMD_MOVE_VEL(vel_trans=350, vel_rot=-120)


def path_telegram(n: int = 100) -> Telegram:
    frames = tuple(
        (int(5000 * math.cos(i / 20)), int(3000 * math.sin(i / 15)), (i * 3600) % 360000 - 180000) for i in range(n)
    )
    return REQUESTS.CMD_MOVE_PATH(frames=frames)


def status_telegram(scan_points: int = 541) -> Telegram:
    """A full status reply as a platform in automatic mode sends it."""
    scan = []
    for i in range(scan_points):
        a = math.radians(-135 + i * 0.5)
        r = 2500 + 1200 * math.sin(i / 17) + (i % 7) * 13
        scan.append((int(r * math.cos(a)), int(r * math.sin(a))))
    fields: dict[str, Any] = {
        "cmd_x": 12500,
        "cmd_y": -3400,
        "cmd_angle": 91500,
        "est_x": 12488,
        "est_y": -3391,
        "est_angle": 91320,
        "cov_major": 35,
        "cov_minor": 12,
        "cov_angle": 450,
        "cov_axis_angle": 30000,
        "scan": tuple(scan),
        "reflectors": ((1200, 3400), (-2500, 800), (4100, -1500)),
        "lines": ((0, 2000, 3000, 2000), (3000, 2000, 3000, -1000), (-500, -2200, 2500, -2200), (-500, 0, -500, 1800)),
        "circles": ((1800, 900, 150), (-2200, -700, 300)),
        "corners": ((3000, 2000), (3000, -1000), (-500, -2200), (2500, -2200), (-500, 1800)),
        "path": tuple((12500 + 100 * i, -3400 + 35 * i) for i in range(50)),
        "joystick_buttons": tuple((1 if i in (2, 7) else 0,) for i in range(12)),
        "vel_trans": 450,
        "vel_rot": -80,
        "relay_digital_in": 0x0013,
        "relay_status": 0,
        "relay_analog_in": (512, 498, 0, 0, 1023, 77, 0, 3),
        "relay_opto_distance": (820, 815, 0, 0),
        "io_battery_voltage": 25400,
        "io_digital_in": 0x00A1,
        "io_digital_out": 0x0004,
        "io_status": 0,
        "io_analog_in": (100, 200, 300, 400, 500, 600, 700, 800),
        "motor_right_status": 0,
        "motor_left_status": 0,
        "motor_right_temp": 38,
        "motor_left_temp": 41,
        "us_distance": (1500, 1480, 2300, 3000, 3000, 870, 640, 3000, 3000, 2200, 1900, 1750, 3000, 3000, 990, 1010),
        "us_analog_in": (0, 0, 0, 0, 12, 0, 0, 0),
        "us_status": 0,
        "radar_velocity": (448, 452, 0, 0),
        "radar_status": 0,
        "gps_latitude": 48.7758459,
        "gps_longitude": 9.1829321,
        "gyro_accel": (1200, -340, 98100),
        "gyro_angle": 15970,
        "gyro_temp": 312500,
        "gyro_status": 0,
        "initialized": 1,
        "target_reached": 0,
        "motion_mode": 4,
        "operation_state": 1,
        "emergency_state": 0,
        "application_mode": 0,
        "planner_state": 3,
        "timestamp": 8_640_123,
        "app_error": 0,
        "docked": 0,
        "localization_lost": 0,
        "collision": 0,
        "lookup_percent": 0,
        "ir_active": (0, 1, 0, 0),
        "siren": 0,
        "flashlight": 1,
        "head_position": 90,
    }
    return REPLIES.CMD_GET_STATUS(**fields)


class Case:
    """One telegram and the decode/encode callables of every subject, all on the same frame."""

    def __init__(
        self,
        name: str,
        telegram: Telegram,
        hw_decode: Callable[[bytes], Any],
        hw_encode: Callable[[Any], bytes],
        cs_frame: Any,
        cs_compiled: Any,
    ) -> None:
        self.name = name
        self.frame = encode(telegram)
        self.direction = telegram.DIRECTION
        # as the codec returns it (group items as named tuples), so as_dict() gives construct's input shape
        self.telegram = decode_frame(self.frame, self.direction)
        if self.telegram != telegram:
            raise AssertionError(f"{name}: spec.codec does not round-trip the telegram")
        self.hw_decode, self.hw_encode = hw_decode, hw_encode
        self.cs_frame, self.cs_compiled = cs_frame, cs_compiled
        self.hw_telegram = hw_decode(self.frame)  # the hand-written codec's input for encoding
        self.cs_input = self.telegram.as_dict()  # construct's input for building

    def decoders(self) -> dict[str, Callable[[], Any]]:
        return {
            OURS: partial(decode_frame, self.frame, self.direction),
            HANDWRITTEN: partial(self.hw_decode, self.frame),
            CONSTRUCT: partial(self.cs_frame.parse, self.frame),
            CONSTRUCT_COMPILED: partial(self.cs_compiled.parse, self.frame),
        }

    def encoders(self) -> dict[str, Callable[[], bytes]]:
        return {
            OURS: partial(encode, self.telegram),
            HANDWRITTEN: partial(self.hw_encode, self.hw_telegram),
            CONSTRUCT: partial(self.cs_frame.build, self.cs_input),
            CONSTRUCT_COMPILED: partial(self.cs_compiled.build, self.cs_input),
        }

    def check(self) -> None:
        """Every subject decodes the frame to the same values and encodes the telegram to the same bytes."""
        ours = self.telegram
        expected = ours.as_dict()
        for subject, dec in self.decoders().items():
            got = dec()
            if subject == OURS:
                same = got == ours
            elif subject == HANDWRITTEN:
                same = got._fields == ours._fields and tuple(got) == tuple(ours) and plain(got) == expected
            else:
                same = cs.plain(got) == expected
            if not same:
                raise AssertionError(f"{self.name}: {subject} decodes to other values: {got!r:.300}")
        for subject, enc in self.encoders().items():
            if enc() != self.frame:
                raise AssertionError(f"{self.name}: {subject} encodes to other bytes")


def cases() -> dict[str, Case]:
    return {
        "move_vel": Case(
            "CMD_MOVE_VEL",
            small_telegram(),
            hw.decode_move_vel_frame,
            hw.encode_move_vel,
            cs.MOVE_VEL_FRAME,
            cs.MOVE_VEL_FRAME_COMPILED,
        ),
        "move_path": Case(
            "CMD_MOVE_PATH (100 frames)",
            path_telegram(),
            hw.decode_move_path_frame,
            hw.encode_move_path,
            cs.MOVE_PATH_FRAME,
            cs.MOVE_PATH_FRAME_COMPILED,
        ),
        "status": Case(
            "CMD_GET_STATUS reply (541 scan points)",
            status_telegram(),
            hw.decode_status_frame,
            hw.encode_status,
            cs.STATUS_FRAME,
            cs.STATUS_FRAME_COMPILED,
        ),
    }


_BASELINES = {OURS: HANDWRITTEN, CONSTRUCT: OURS, CONSTRUCT_COMPILED: OURS}


# ---------------------------------------------------------------------------------------------- stream decode


def stream_chunks(frames: int = STREAM_FRAMES, chunk: int = CHUNK) -> list[bytes]:
    data = encode(small_telegram()) * frames
    return [data[i : i + chunk] for i in range(0, len(data), chunk)]


def _feed(decoder: Any, chunks: list[bytes]) -> int:
    n = 0
    for chunk in chunks:
        decoder.receive_data(chunk)
        for _ in decoder:
            n += 1
    return n


def stream_decoders(chunks: list[bytes]) -> dict[str, Callable[[], int]]:
    """Each callable decodes the whole stream with a fresh decoder and returns the telegram count."""
    return {
        OURS: lambda: _feed(TelegramDecoder("request"), chunks),
        HANDWRITTEN: lambda: _feed(hw.StreamDecoder(hw.REQUEST_DECODERS), chunks),
        CONSTRUCT: lambda: _feed(cs.StreamDecoder(cs.MOVE_VEL_FRAME), chunks),
        CONSTRUCT_COMPILED: lambda: _feed(cs.StreamDecoder(cs.MOVE_VEL_FRAME_COMPILED), chunks),
    }


@benchmark()
def stream_decode(config: Config) -> list[Row]:
    """100,000 CMD_MOVE_VEL frames (2,000 with --quick) concatenated, fed in 4 KiB chunks and iterated."""
    frames = STREAM_FRAMES_QUICK if config.quick else STREAM_FRAMES
    chunks = stream_chunks(frames)
    subjects = stream_decoders(chunks)
    for subject, run in subjects.items():
        if run() != frames:
            raise AssertionError(f"{subject}: stream decoder lost telegrams")
    rates = median_rates(subjects, config, number=1, ops_per_call=frames)
    return rate_rows(
        "codec.stream_decode",
        "stream_decode_rate",
        "telegrams/s",
        rates,
        _BASELINES,
        {OURS: Target("value", ">=", SMALL_RATE_TARGET)},
    )


# ---------------------------------------------------------------------------------------------- single frames


def _frame_rows(key: str, config: Config, decode_targets: dict[str, Target]) -> list[Row]:
    case = cases()[key]
    case.check()
    name = f"codec.{key}"
    rows = rate_rows(
        name,
        "decode_rate",
        "telegrams/s",
        median_rates(case.decoders(), config),
        _BASELINES,
        decode_targets,
    )
    rows += rate_rows(name, "encode_rate", "telegrams/s", median_rates(case.encoders(), config), _BASELINES)
    return rows


@benchmark()
def move_vel(config: Config) -> list[Row]:
    """CMD_MOVE_VEL request: decode one frame, encode one telegram."""
    return _frame_rows("move_vel", config, {OURS: Target("value", ">=", SMALL_RATE_TARGET)})


@benchmark()
def move_path(config: Config) -> list[Row]:
    """CMD_MOVE_PATH request with 100 frames: decode one frame, encode one telegram."""
    return _frame_rows("move_path", config, {})


@benchmark()
def status(config: Config) -> list[Row]:
    """CMD_GET_STATUS reply with 541 scan points: decode one frame, encode one telegram."""
    return _frame_rows(
        "status",
        config,
        {
            OURS: Target("ratio", "<=", STATUS_VS_HANDWRITTEN),
            CONSTRUCT: Target("ratio", ">=", CONSTRUCT_VS_STATUS),
        },
    )
