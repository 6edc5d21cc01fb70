"""Mutation of valid traffic: flips, header and length corruption, truncation, odd delivery, floods.

Rules:
- A mutator is ``(seed_case, rng) -> Case`` in ``MUTATORS``; the seed is valid traffic (a boundary case, a
  state prelude, a corpus entry). Mutators never look at the target; randomness only from ``rng``.
- Length lies follow the issue: 0, one short, one long, huge, over 2^31 (guide 6.2: N is a uint32).
- Delivery mutators (bytewise, slow, half-close) keep the bytes and change how they are written.
"""

from __future__ import annotations

import random
import struct
from collections.abc import Callable
from dataclasses import replace

from pltf.fuzz.case import Case, Delivery
from pltf.fuzz.wire import frame_lie, split_frames
from pltf.spec.codec import FRAME_OVERHEAD, HEADER, REQUESTS, encode

INTERESTING_BYTES = (0x00, 0x01, 0x7F, 0x80, 0xFE, 0xFF)
LENGTH_LIES = ("zero", "one_short", "one_long", "huge", "over_2_31", "max")
GET_STATUS = encode(REQUESTS.CMD_GET_STATUS())
FLOOD_BYTES = 1 << 18  # a flood case stays under this many bytes
BYTEWISE_MAX = 512  # bytes; a longer case is written in slow pieces instead


def _pick(case: Case, rng: random.Random) -> tuple[int, bytes]:
    i = rng.randrange(len(case.frames))
    return i, case.frames[i]


def _put(case: Case, i: int, new: bytes, origin: str, note: str, **changes: object) -> Case:
    frames = (*case.frames[:i], new, *case.frames[i + 1 :])
    return replace(case, frames=frames, origin=origin, note=note, expect="", **changes)  # type: ignore[arg-type]


def bit_flip(case: Case, rng: random.Random) -> Case:
    i, f = _pick(case, rng)
    b = bytearray(f)
    flips = []
    for _ in range(rng.choice((1, 1, 2, 4))):
        pos = rng.randrange(len(b))
        bit = rng.randrange(8)
        b[pos] ^= 1 << bit
        flips.append(f"{pos}:{bit}")
    return _put(case, i, bytes(b), "mut.bit_flip", f"frame {i} bits {','.join(flips)}")


def byte_set(case: Case, rng: random.Random) -> Case:
    i, f = _pick(case, rng)
    b = bytearray(f)
    pos = rng.randrange(FRAME_OVERHEAD, len(b)) if len(b) > FRAME_OVERHEAD else rng.randrange(len(b))
    b[pos] = rng.choice(INTERESTING_BYTES) if rng.random() < 0.7 else rng.randrange(256)
    return _put(case, i, bytes(b), "mut.byte_set", f"frame {i} byte {pos}={b[pos]:#04x}")


def header(case: Case, rng: random.Random) -> Case:
    i, f = _pick(case, rng)
    how = rng.randrange(4)
    if how == 0:
        pos = rng.randrange(4)
        new = f[:pos] + bytes([f[pos] ^ rng.randrange(1, 256)]) + f[pos + 1 :]
        note = f"header byte {pos} changed"
    elif how == 1:
        new, note = f[4:], "header missing"
    elif how == 2:
        new, note = HEADER + f, "header doubled"
    else:
        new, note = HEADER[::-1] + f[4:], "header reversed"
    return _put(case, i, new, "mut.header", f"frame {i}: {note}")


def length_lie(case: Case, rng: random.Random) -> Case:
    i, f = _pick(case, rng)
    data = f[FRAME_OVERHEAD:]
    kind = rng.choice(LENGTH_LIES)
    declared = {
        "zero": 0,
        "one_short": len(data) - 1,
        "one_long": len(data) + 1,
        "huge": 0x00FFFFFF + rng.randrange(1 << 24),
        "over_2_31": 0x80000000 + rng.randrange(1 << 16),
        "max": 0xFFFFFFFF,
    }[kind]
    return _put(case, i, frame_lie(data, declared & 0xFFFFFFFF), "mut.length_lie", f"frame {i} length {kind}")


def truncate(case: Case, rng: random.Random) -> Case:
    data = case.data
    cut = rng.randrange(1, len(data)) if len(data) > 1 else 0
    pieces = tuple(split_frames(data[:cut])) or (b"",)
    return replace(
        case, frames=pieces, origin="mut.truncate", note=f"cut at byte {cut} of {len(data)}", half_close=True, expect=""
    )


def insert_delete(case: Case, rng: random.Random) -> Case:
    i, f = _pick(case, rng)
    pos = rng.randrange(len(f) + 1)
    if rng.random() < 0.5 and len(f) > 1:
        n = rng.randrange(1, min(8, len(f) - pos) + 1) if pos < len(f) else 1
        return _put(case, i, f[:pos] + f[pos + n :], "mut.delete", f"frame {i}: {n} bytes deleted at {pos}")
    blob = bytes(rng.randrange(256) for _ in range(rng.choice((1, 2, 4, 8))))
    return _put(case, i, f[:pos] + blob + f[pos:], "mut.insert", f"frame {i}: {blob.hex()} inserted at {pos}")


def int_field(case: Case, rng: random.Random) -> Case:
    """Overwrite an aligned 4-byte word of the data (an INT, a count or a length) with an extreme value."""
    i, f = _pick(case, rng)
    if len(f) < FRAME_OVERHEAD + 5:
        return length_lie(case, rng)
    pos = rng.randrange(FRAME_OVERHEAD + 1, len(f) - 3)
    value = rng.choice((0, 0xFFFFFFFF, 0x7FFFFFFF, 0x80000000, 0x00010000, 0xFFFF0000))
    new = f[:pos] + struct.pack(">I", value) + f[pos + 4 :]
    return _put(case, i, new, "mut.int_field", f"frame {i}: word at {pos} = {value:#010x}")


def splice(case: Case, rng: random.Random) -> Case:
    """Two frames cut and glued: a frame boundary that falls inside another frame."""
    data = case.data + case.data
    a = rng.randrange(1, len(case.data) + 1)
    b = rng.randrange(a, len(data) + 1)
    return replace(case, frames=(data[:a], data[b:]), origin="mut.splice", note=f"bytes [{a}:{b}] removed", expect="")


def bytewise(case: Case, rng: random.Random) -> Case:
    if case.size > BYTEWISE_MAX:
        return slow(case, rng)
    return replace(
        case,
        frames=(*case.frames, GET_STATUS),
        delivery=Delivery("bytewise"),
        origin="mut.bytewise",
        note="one write per byte",
        expect="",
    )


def slow(case: Case, rng: random.Random) -> Case:
    pieces = rng.choice((2, 3, 4))
    return replace(
        case,
        frames=(*case.frames, GET_STATUS),
        delivery=Delivery("slow", pieces, 0.001),
        origin="mut.slow",
        note=f"{pieces} writes 1 ms apart",
        expect="",
    )


def half_close(case: Case, rng: random.Random) -> Case:
    """Valid frames, a GET_STATUS, then end-of-stream: the reply is still owed."""
    return replace(
        case,
        frames=(*case.frames, GET_STATUS),
        half_close=True,
        origin="mut.half_close",
        note="write side shut after the frames",
        expect="",
    )


def flood(case: Case, rng: random.Random) -> Case:
    n = max(1, min(rng.choice((100, 300, 1_000)), FLOOD_BYTES // max(1, case.size)))
    return replace(case, frames=case.frames * n, origin="mut.flood", note=f"{n} copies", expect="")


Mutator = Callable[[Case, random.Random], Case]

MUTATORS: dict[str, tuple[float, Mutator]] = {
    "mut.bit_flip": (3.0, bit_flip),
    "mut.byte_set": (2.0, byte_set),
    "mut.header": (1.0, header),
    "mut.length_lie": (2.0, length_lie),
    "mut.truncate": (1.0, truncate),
    "mut.insert_delete": (1.0, insert_delete),
    "mut.int_field": (2.0, int_field),
    "mut.splice": (1.0, splice),
    "mut.bytewise": (0.05, bytewise),
    "mut.slow": (0.05, slow),
    "mut.half_close": (0.3, half_close),
    "mut.flood": (0.003, flood),
}
