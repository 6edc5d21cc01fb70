"""The platform's CAN database (``spec/can/pltf.dbc``), loaded once with cantools, and the node table.

Rules:
- Identifiers, signals, scales, units and cycle times live in the DBC only. Code names a message by node and
  function (``message_for(Node.MOTOR_RIGHT, "Encoder")`` is ``MotorRight_Encoder``); no id is written in Python.
- Identifier = node * 0x100 + function (erratum E-HW-001): 0x01-0x05 probe / self test / shutdown, 0x10-0x1F
  commands to the node, 0x20-0x2F data from the node; 0x700-0x7FF is left to applications.
- Status words are shared by every board (erratum E-HW-006): the low byte comes from the board, the second byte
  is added by the controller, ``ABSENT`` (-1) stands for a node that is not connected.
- ``build``/``decode`` run ~400 times per simulated second, so each message gets a precompiled ``FrameCodec``:
  every signal of the database is an Intel integer field, packed with shifts on one int, scaled by the
  signal's own cantools conversion, in an encode and a decode function compiled per message (straight-line
  code, like the spec's telegram codec). The bytes and values equal cantools' ``encode``/``decode`` (a test
  checks every message), at a fraction of the cost.
"""

from __future__ import annotations

import enum
import functools
import math
from collections.abc import Callable, Mapping
from typing import Any, TypeVar

import can
import cantools
from cantools.database.can import Database, Message, Signal
from cantools.database.conversion import IdentityConversion

from pltf.spec.model import SPEC_DIR

DBC_PATH = SPEC_DIR / "can" / "pltf.dbc"
Signals = Mapping[str, Any]


class Node(enum.IntEnum):
    """CAN node numbers: 0-3 from the Neobotix driver code (field evidence), 4-6 ours (erratum E-HW-001)."""

    IOBOARD = 0
    MOTOR_RIGHT = 1  # CANNODE_MOTORRIGHT of CMD_SET_BRAKE
    MOTOR_LEFT = 2  # CANNODE_MOTORLEFT
    USBOARD = 3
    RELAYBOARD = 4
    RADARBOARD = 5
    GYROBOARD = 6


ALL_NODES: tuple[Node, ...] = tuple(Node)
MOTORS: tuple[Node, Node] = (Node.MOTOR_RIGHT, Node.MOTOR_LEFT)
PREFIX: dict[Node, str] = {
    Node.IOBOARD: "IoBoard",
    Node.MOTOR_RIGHT: "MotorRight",
    Node.MOTOR_LEFT: "MotorLeft",
    Node.USBOARD: "UsBoard",
    Node.RELAYBOARD: "RelayBoard",
    Node.RADARBOARD: "RadarBoard",
    Node.GYROBOARD: "GyroBoard",
}
APPLICATION_IDS = range(0x700, 0x800)  # never used by a board: free for CMD_SEND_CAN_MESSAGE


class St:
    """Status bits (erratum E-HW-006). Low byte: reported by the board in its frames."""

    NOT_INITIALIZED = 0x01
    SELFTEST_FAILED = 0x02
    EMERGENCY_STOP = 0x04
    OVER_TEMPERATURE = 0x08
    # board specific, 0x10-0x80
    BRAKE_ENGAGED = 0x10  # motor
    SETPOINT_TIMEOUT = 0x20  # motor
    STALL = 0x40  # motor: the wheel does not turn although driven
    LOW_BATTERY = 0x10  # IO board
    MEASURING = 0x10  # ultrasonic board
    # second byte: added by the controller
    NODE_TIMEOUT = 0x100  # no frame from the node for NODE_TIMEOUT seconds
    FRAMES_LOST = 0x200  # a gap in a rolling counter within the last second
    BUS_OFF = 0x400  # the controller's CAN interface is bus-off
    ABSENT = -1  # not connected: not fitted, no answer to the probe, or the bus is not connected


@functools.cache
def database() -> Database:
    db = cantools.database.load_file(str(DBC_PATH), strict=True)
    assert isinstance(db, Database)
    return db


def message_for(node: Node, function: str) -> Message:
    return database().get_message_by_name(f"{PREFIX[node]}_{function}")


@functools.cache
def _by_id() -> dict[int, Message]:
    return {m.frame_id: m for m in database().messages}


def message_by_id(can_id: int) -> Message | None:
    return _by_id().get(can_id)


def node_of(can_id: int) -> Node | None:
    """The node owning an identifier of the database (None for application ids)."""
    m = message_by_id(can_id)
    return None if m is None else Node(can_id >> 8)


def cycle_time(msg: Message) -> float | None:
    """The cycle time of a cyclic message in seconds (DBC attribute GenMsgCycleTime), None when event driven."""
    return None if not msg.cycle_time else msg.cycle_time / 1000.0


_K = TypeVar("_K")
_V = TypeVar("_V")
_A = TypeVar("_A")


class FrameCodec:
    """One message's signals as (name, start bit, mask, sign bit, to raw, to physical, min, max), Intel byte order.

    An identity conversion (factor 1, offset 0: most signals) is ``round`` one way and nothing the other, not a
    call into cantools per signal. Frames are remembered both ways while that pays: a message whose frames do
    not repeat (a counter, a timestamp) stops being looked up after ``CACHE`` frames with few hits."""

    __slots__ = (
        "_cached",
        "_decode",
        "_decoded",
        "_encode",
        "_encoded",
        "_hits",
        "fields",
        "frame_id",
        "length",
        "names",
    )
    CACHE = 256  # frames remembered per message each way: status and analogue frames repeat, counters do not

    def __init__(self, msg: Message) -> None:
        if any(s.byte_order != "little_endian" or s.is_float for s in msg.signals) or msg.is_multiplexed():
            raise ValueError(f"{msg.name}: only Intel integer signals are precompiled")
        self.frame_id = msg.frame_id
        self.length = msg.length
        self.fields = tuple(
            (
                s.name,
                s.start,
                (1 << s.length) - 1,
                (1 << (s.length - 1)) if s.is_signed else 0,
                *_converters(s),
                float(s.minimum) if s.minimum is not None else -math.inf,
                float(s.maximum) if s.maximum is not None else math.inf,
            )
            for s in msg.signals
        )
        self.names = tuple(f[0] for f in self.fields)
        self._encoded: dict[tuple[Any, ...], bytes] = {}
        self._decoded: dict[bytes, dict[str, Any]] = {}
        self._cached = [True, True]  # encode, decode: still worth a lookup
        self._encode, self._decode = self._compile()
        self._hits = [0, 0]

    def encode(self, signals: Signals) -> bytes:
        """Physical values (clamped to each signal's range) -> the frame's bytes; every signal must be given."""
        if not self._cached[0]:
            return self._encode(signals)
        return self._remembered(0, self._encoded, tuple(map(signals.__getitem__, self.names)), self._encode, signals)

    def decode(self, data: bytes | bytearray) -> dict[str, Any]:
        """The physical values of a frame: a dict shared by every equal frame, so callers keep it but never
        change it."""
        key = bytes(data[: self.length])
        if not self._cached[1]:
            return self._decode(key)
        return self._remembered(1, self._decoded, key, self._decode, key)

    def _remembered(self, way: int, cache: dict[_K, _V], key: _K, make: Callable[[_A], _V], arg: _A) -> _V:
        """``make(arg)``, remembered under ``key`` in ``cache`` (way 0: encode, 1: decode)."""
        out = cache.get(key)
        if out is not None:
            self._hits[way] += 1
            return out
        if len(cache) >= self.CACHE:
            self._forget(way, cache)
        out = cache[key] = make(arg)
        return out

    def _forget(self, way: int, cache: dict[Any, Any]) -> None:
        """A full cache: start afresh, or stop looking up when fewer than a quarter of the lookups hit."""
        self._cached[way] = self._hits[way] >= self.CACHE // 4
        self._hits[way] = 0
        cache.clear()

    def _compile(self) -> tuple[Callable[[Signals], bytes], Callable[[bytes], dict[str, Any]]]:
        """Straight-line encode and decode functions of this message (no loop over the signal table per frame),
        as the spec's telegram codec is compiled: each signal clamped, converted and shifted in turn."""
        env: dict[str, Any] = {}
        enc = ["def encode(signals):", "    word = 0"]
        dec = ["def decode(data):", "    word = int.from_bytes(data, 'little')"]
        items = []
        for k, (name, start, mask, sign, to_raw, to_phys, lo, hi) in enumerate(self.fields):
            env.update({f"lo{k}": lo, f"hi{k}": hi, f"raw{k}": to_raw, f"phys{k}": to_phys})
            enc.append(f"    v = signals[{name!r}]")
            enc.append(f"    v = lo{k} if v < lo{k} else hi{k} if v > hi{k} else v")
            enc.append(f"    word |= (int(raw{k}(v)) & {mask}) << {start}")
            dec.append(f"    r{k} = (word >> {start}) & {mask}")
            if sign:
                dec.append(f"    if r{k} & {sign}: r{k} -= {mask + 1}")
            items.append(f"{name!r}: r{k}" if to_phys is None else f"{name!r}: phys{k}(r{k})")
        enc.append(f"    return word.to_bytes({self.length}, 'little')")
        dec.append("    return {" + ", ".join(items) + "}")
        exec(compile("\n".join(enc + dec), f"<candb:{self.frame_id:#x}>", "exec"), env)
        return env["encode"], env["decode"]


def _converters(s: Signal) -> tuple[Callable[[float], float | int], Callable[[int], Any] | None]:
    """(physical -> raw, raw -> physical or None for "the same") of an integer signal, as cantools converts."""
    conv = s.conversion
    if isinstance(conv, IdentityConversion):  # cantools: round(value); the raw value as it is
        return round, None
    return conv.numeric_scaled_to_raw, functools.partial(conv.raw_to_scaled, decode_choices=False)


@functools.cache
def codec(msg: Message) -> FrameCodec:
    return FrameCodec(msg)


def build(msg: Message, signals: Signals, now: float) -> can.Message:
    """A frame of ``msg`` stamped with simulated time ``now``; values are clamped to the signals' ranges."""
    return can.Message(
        arbitration_id=msg.frame_id, data=codec(msg).encode(signals), is_extended_id=False, timestamp=now
    )


def decode(msg: Message, frame: can.Message) -> dict[str, Any] | None:
    """The signals of a frame, or None when it is too short for ``msg`` (longer frames are accepted)."""
    c = codec(msg)
    if len(frame.data) < c.length:
        return None
    return c.decode(frame.data)
