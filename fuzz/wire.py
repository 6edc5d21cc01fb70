"""Raw frames for the fuzzer: writes any layout with any lie, and classifies bytes the way a server reads them.

Rules:
- ``pltf.spec.codec.encode`` refuses invalid values (it is the honest encoder); the fuzzer needs the dishonest one.
  ``pack_fields`` walks a spec layout and writes whatever it is given: integers wrap to the field's width,
  doubles may be NaN, a string or group may carry a ``declared`` length or count that disagrees with its bytes.
- ``classify`` decides, with the strict codec, what a well-behaved server (erratum E-WIRE-006) does with bytes:
  ``KEEP`` (every frame decodes, the connection stays open), ``CLOSE`` (an error, or CMD_CLOSE_SOCKET) or
  ``PARTIAL`` (bytes wait for more data). The fuzzer only uses it to schedule (what may be pipelined); it is
  never the oracle: a server that reads a frame differently is not wrong for it.
- ``forbidden_ids`` finds every telegram id a lenient reader could see in the bytes (frames walked by their
  length field, and any header anywhere, as a resynchronising server would), so that the safety filter can
  drop cases that might shut the target down or move it.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from pltf.spec import errors
from pltf.spec.codec import HEADER, REQUESTS, TelegramDecoder, decode_frame, frame
from pltf.spec.model import FieldDef, load_telegrams

KEEP, CLOSE, PARTIAL = "keep", "close", "partial"

_PACK = {"BYTE": (">B", 0xFF), "BOOL": (">B", 0xFF), "INT16": (">H", 0xFFFF), "INT": (">I", 0xFFFFFFFF)}
_LEN = struct.Struct(">I")
_DOUBLE = struct.Struct(">d")

CLOSE_SOCKET_ID = REQUESTS.CMD_CLOSE_SOCKET.ID
ANSWERED = frozenset(t.id for t in load_telegrams() if t.answered)  # the requests a server replies to


@dataclass(frozen=True)
class Raw:
    """Bytes written as they are in place of a field (a DOUBLE's exact bit pattern, a cut-off value)."""

    data: bytes


@dataclass(frozen=True)
class Str:
    """A STRING/XML value whose length field may lie (``declared`` None: the true length)."""

    data: bytes
    declared: int | None = None


@dataclass(frozen=True)
class Group:
    """A GROUP value (items are sequences of field values) whose count field may lie."""

    items: tuple[Sequence[Any], ...]
    declared: int | None = None


def pack_int(value: int, type_: str) -> bytes:
    fmt, mask = _PACK[type_]
    return struct.pack(fmt, value & mask)


def pack_length(value: int) -> bytes:
    """A length or count field (INT) holding any integer, wrapped to 32 bits."""
    return _LEN.pack(value & 0xFFFFFFFF)


def pack_value(f: FieldDef, value: Any) -> bytes:
    """One field's bytes; ``value`` may be anything the field's wire type can be made to carry."""
    if isinstance(value, Raw):
        return value.data
    if f.is_group:
        group = value if isinstance(value, Group) else Group(tuple(value))
        n = len(group.items) if group.declared is None else group.declared
        sub = [g for g in f.fields if g.const is None]
        body = b"".join(pack_value(g, v) for item in group.items for g, v in zip(sub, item, strict=False))
        return pack_length(n) + body
    if f.type in ("STRING", "XML"):
        s = (
            value
            if isinstance(value, Str)
            else Str(value if isinstance(value, bytes) else str(value).encode("latin-1"))
        )
        n = len(s.data) if s.declared is None else s.declared
        return pack_length(n) + s.data
    if f.repeat:
        return b"".join(_scalar(f.type, v) for v in value)
    return _scalar(f.type, value)


def _scalar(type_: str, value: Any) -> bytes:
    if isinstance(value, Raw):
        return value.data
    if type_ == "DOUBLE":
        return _DOUBLE.pack(float(value))
    return pack_int(int(value), type_)


def pack_fields(ident: int, layout: Sequence[FieldDef], values: Sequence[Any]) -> bytes:
    """Telegram data: the identifier, then each field of ``layout`` (constants included) from ``values``."""
    it = iter(values)
    parts = [bytes([ident & 0xFF])]
    for f in layout:
        parts.append(pack_value(f, f.const if f.const is not None else next(it)))
    return b"".join(parts)


def frame_lie(data: bytes, declared: int) -> bytes:
    """A frame whose length field says ``declared`` whatever the data's length is."""
    return HEADER + pack_length(declared) + data


def classify(data: bytes) -> str:
    """What a strict server does with ``data`` sent on a fresh connection (see the module rules)."""
    return survey(data)[0]


def answered_ids(data: bytes) -> list[int]:
    """Ids of the answered requests among the frames of ``data``, up to the first malformed frame."""
    return survey(data)[1]


def survey(data: bytes) -> tuple[str, list[int]]:
    """``classify`` and ``answered_ids`` of ``data`` from one strict decoding."""
    dec = TelegramDecoder("request")
    dec.receive_data(data)
    ids: list[int] = []
    expect = ""
    try:
        for telegram in dec:
            ident = telegram.ID
            if ident in ANSWERED:
                ids.append(ident)
            elif ident == CLOSE_SOCKET_ID:
                expect = CLOSE
    except errors.RemoteProtocolError:
        return CLOSE, ids
    return expect or (PARTIAL if dec.pending else KEEP), ids


def skipping_ids(data: bytes) -> list[int]:
    """Ids of the answered requests among the frames of ``data`` that decode, each frame on its own: what a target
    that skips a malformed frame and goes on answers (E-WIRE-006's alternative reading)."""
    ids = []
    for f in split_frames(data):
        try:
            ident = decode_frame(f, "request").ID
        except errors.ProtocolError:
            continue
        if ident in ANSWERED:
            ids.append(ident)
    return ids


def frame_ids(data: bytes) -> list[int]:
    """Ids of the frames a length-walking reader sees, up to the first bad header or incomplete frame."""
    ids, pos, end = [], 0, len(data)
    while pos + 8 <= end and data[pos : pos + 4] == HEADER:
        (n,) = _LEN.unpack_from(data, pos + 4)
        if n == 0 or pos + 8 + n > end:
            break
        ids.append(data[pos + 8])
        pos += 8 + n
    return ids


def forbidden_ids(data: bytes, forbidden: frozenset[int]) -> set[int]:
    """Forbidden ids any plausible reader could act on: length-walked frames and every header in the bytes."""
    found = {i for i in frame_ids(data) if i in forbidden}
    pos = data.find(HEADER)
    while pos != -1:
        if pos + 8 < len(data) and data[pos + 8] in forbidden:
            found.add(data[pos + 8])
        pos = data.find(HEADER, pos + 1)
    return found


def split_frames(data: bytes) -> list[bytes]:
    """Cut bytes into frames by their length fields; whatever does not walk is one last piece."""
    out, pos, end = [], 0, len(data)
    while pos + 8 <= end and data[pos : pos + 4] == HEADER:
        (n,) = _LEN.unpack_from(data, pos + 4)
        if pos + 8 + n > end:
            break
        out.append(data[pos : pos + 8 + n])
        pos += 8 + n
    if pos < end:
        out.append(data[pos:])
    return out


def join(frames: Iterable[bytes]) -> bytes:
    return b"".join(frames)


__all__ = [
    "CLOSE",
    "KEEP",
    "PARTIAL",
    "Group",
    "Raw",
    "Str",
    "answered_ids",
    "classify",
    "forbidden_ids",
    "frame",
    "frame_ids",
    "frame_lie",
    "pack_fields",
    "pack_length",
    "pack_value",
    "skipping_ids",
    "split_frames",
    "survey",
]
