"""foxglove.LaserScan in protobuf, written by hand (issue 35): the MCAP export's scan channel.

A status reply's 541 ranges cost ~90 us as JSON text (a Python float's repr each) and nothing as protobuf's packed
doubles (numpy's ``tobytes``). The protobuf wire format is small enough to write here without the protobuf
runtime: varints, length-delimited fields, little-endian doubles (protobuf.dev, "Encoding"). Foxglove and the
other viewers decode a protobuf channel with the schema the MCAP file carries: a ``FileDescriptorSet`` (the
``.proto`` files of the message and of everything it uses), built below from a table of Foxglove's published
schemas (github foxglove/schemas, schemas/proto/foxglove/LaserScan.proto, Pose.proto, Vector3.proto,
Quaternion.proto; google/protobuf/timestamp.proto). The tests decode what is written here with the protobuf
library from that descriptor set, as Foxglove does.
"""

from __future__ import annotations

import functools
import struct
from typing import Any

ENCODING = "protobuf"  # the schema's encoding (a FileDescriptorSet) and the messages'

# google/protobuf/descriptor.proto: FieldDescriptorProto.Type and .Label
DOUBLE, INT64, INT32, STRING, MESSAGE = 1, 3, 5, 9, 11
OPTIONAL, REPEATED = 1, 3
_VARINT, _FIXED64, _LEN = 0, 1, 2  # wire types

# (file, package, dependencies, message, fields: (name, number, type, label, type name))
FILES: tuple[tuple[str, str, tuple[str, ...], str, tuple[tuple[str, int, int, int, str], ...]], ...] = (
    (
        "google/protobuf/timestamp.proto",
        "google.protobuf",
        (),
        "Timestamp",
        (("seconds", 1, INT64, OPTIONAL, ""), ("nanos", 2, INT32, OPTIONAL, "")),
    ),
    (
        "foxglove/Vector3.proto",
        "foxglove",
        (),
        "Vector3",
        tuple((n, i, DOUBLE, OPTIONAL, "") for i, n in enumerate("xyz", 1)),
    ),
    (
        "foxglove/Quaternion.proto",
        "foxglove",
        (),
        "Quaternion",
        tuple((n, i, DOUBLE, OPTIONAL, "") for i, n in enumerate("xyzw", 1)),
    ),
    (
        "foxglove/Pose.proto",
        "foxglove",
        ("foxglove/Quaternion.proto", "foxglove/Vector3.proto"),
        "Pose",
        (
            ("position", 1, MESSAGE, OPTIONAL, ".foxglove.Vector3"),
            ("orientation", 2, MESSAGE, OPTIONAL, ".foxglove.Quaternion"),
        ),
    ),
    (
        "foxglove/LaserScan.proto",
        "foxglove",
        ("foxglove/Pose.proto", "google/protobuf/timestamp.proto"),
        "LaserScan",
        (
            ("timestamp", 1, MESSAGE, OPTIONAL, ".google.protobuf.Timestamp"),
            ("frame_id", 2, STRING, OPTIONAL, ""),
            ("pose", 3, MESSAGE, OPTIONAL, ".foxglove.Pose"),
            ("start_angle", 4, DOUBLE, OPTIONAL, ""),
            ("end_angle", 5, DOUBLE, OPTIONAL, ""),
            ("ranges", 6, DOUBLE, REPEATED, ""),  # proto3: a repeated double is packed
            ("intensities", 7, DOUBLE, REPEATED, ""),
        ),
    ),
)


_SMALL = tuple(bytes((n,)) for n in range(0x80))  # the one-byte varints


def varint(n: int) -> bytes:
    """An unsigned varint (a negative int64 is its two's complement, ten bytes)."""
    if 0 <= n < 0x80:
        return _SMALL[n]
    n &= (1 << 64) - 1
    out = bytearray()
    while n > 0x7F:
        out.append(n & 0x7F | 0x80)
        n >>= 7
    out.append(n)
    return bytes(out)


@functools.cache
def key(number: int, wire: int) -> bytes:
    return varint(number << 3 | wire)


def length_delimited(number: int, payload: bytes) -> bytes:
    return key(number, _LEN) + varint(len(payload)) + payload


def text(number: int, value: str) -> bytes:
    return length_delimited(number, value.encode("utf-8"))


def double(number: int, value: float) -> bytes:
    return key(number, _FIXED64) + struct.pack("<d", value)


def integer(number: int, value: int) -> bytes:
    return key(number, _VARINT) + varint(value)


# ---------------------------------------------------------------------------------------- the schema


def _field(name: str, number: int, ftype: int, label: int, type_name: str) -> bytes:
    # descriptor.proto FieldDescriptorProto: name 1, number 3, label 4, type 5, type_name 6, json_name 10
    first, *rest = name.split("_")
    camel = first + "".join(w.title() for w in rest)
    out = text(1, name) + integer(3, number) + integer(4, label) + integer(5, ftype)
    return out + (text(6, type_name) if type_name else b"") + text(10, camel)


def _file(name: str, package: str, deps: tuple[str, ...], message: str, fields: Any) -> bytes:
    # FileDescriptorProto: name 1, package 2, dependency 3, message_type 4 (DescriptorProto: name 1, field 2), syntax 12
    body = text(1, message) + b"".join(length_delimited(2, _field(*f)) for f in fields)
    head = text(1, name) + text(2, package) + b"".join(text(3, d) for d in deps)
    return head + length_delimited(4, body) + text(12, "proto3")


def file_descriptor_set() -> bytes:
    """The schema of foxglove.LaserScan: a FileDescriptorSet (field 1: each file), dependencies first."""
    return b"".join(length_delimited(1, _file(*f)) for f in FILES)


# ---------------------------------------------------------------------------------------- the message


def timestamp(ns: int) -> bytes:
    """google.protobuf.Timestamp of ``ns`` nanoseconds (seconds 1, nanos 2; zeros left out, as proto3 does)."""
    sec, nsec = divmod(ns, 1_000_000_000)
    return (integer(1, sec) if sec else b"") + (integer(2, nsec) if nsec else b"")


# foxglove.Pose: position (0, 0, 0) written as an empty Vector3 (a reader's defaults give a missing one as null),
# orientation w = 1
IDENTITY_POSE = length_delimited(1, b"") + length_delimited(2, double(4, 1.0))


_ANGLES = struct.Struct("<BdBd")  # start_angle (4) and end_angle (5): each a key byte and a little-endian double


@functools.cache
def _scan_head(frame_id: str) -> bytes:
    return text(2, frame_id) + length_delimited(3, IDENTITY_POSE)


def laser_scan_tail(frame_id: str, start: float, end: float, ranges: bytes) -> bytes:
    """foxglove.LaserScan after its timestamp (field 1, written first by ``stamped``): ``ranges`` are the packed
    little-endian doubles (``ndarray.astype("<f8").tobytes()``); no intensities."""
    out = _scan_head(frame_id) + _ANGLES.pack(4 << 3 | _FIXED64, start, 5 << 3 | _FIXED64, end)
    return out + key(6, _LEN) + varint(len(ranges)) + ranges if ranges else out


def stamped(ns: int, tail: bytes) -> bytes:
    """A message whose field 1 is its google.protobuf.Timestamp, then ``tail``."""
    stamp = timestamp(ns)
    return b"%c%c%s%s" % (1 << 3 | _LEN, len(stamp), stamp, tail)  # a Timestamp is < 128 bytes: one length byte
