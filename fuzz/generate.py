"""Generation from the spec: every request telegram with boundary and hostile field values.

Rules:
- The layouts come from ``pltf.spec.model.load_telegrams()``; no telegram is written by hand here. Values come
  from per-wire-type tables (``BOUNDARY``: still valid for the codec, ``HOSTILE``: refused by it) and from
  what the target told us (``pltf.fuzz.knowledge``: parameter keys, station names, the current pose).
- Each generator is ``(rng, kb) -> Case`` in ``GENERATORS``; randomness only from the ``random.Random`` given.
- Telegrams the safety policy forbids (``pltf.fuzz.safety``) are never generated; the scheduler filters again
  after mutation.
"""

from __future__ import annotations

import bisect
import functools
import itertools
import math
import random
import struct
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from pltf.fuzz import xml_attacks
from pltf.fuzz.case import Case
from pltf.fuzz.knowledge import Knowledge
from pltf.fuzz.wire import Group, Raw, Str, frame, frame_lie, pack_fields
from pltf.spec.compiler import WIRE, allowed_values, value_range
from pltf.spec.model import FieldDef, TelegramDef, load_telegrams

I32_MIN, I32_MAX = -(2**31), 2**31 - 1
INT_EDGES = (0, 1, -1, 2, 255, 256, 32767, 32768, 65535, 65536, I32_MAX, I32_MIN, I32_MAX - 1, I32_MIN + 1)
# guide 6.2: INT is 4 bytes two's complement; these are the patterns naive parsers trip on
BOUNDARY: dict[str, tuple[Any, ...]] = {
    "BYTE": (0, 1, 0x7F, 0x80, 0xFE, 0xFF),
    "BOOL": (0, 1),
    "INT16": (0, 1, -1, 2**15 - 1, -(2**15)),
    "INT": INT_EDGES,
    "DOUBLE": (0.0, -0.0, 1e-308, 5e-324, 1.7976931348623157e308, -1.7976931348623157e308),
}
HOSTILE_DOUBLES = (
    Raw(struct.pack(">d", math.nan)),
    Raw(struct.pack(">d", math.inf)),
    Raw(struct.pack(">d", -math.inf)),
    Raw(bytes.fromhex("7ff0000000000001")),  # signalling NaN
    Raw(bytes.fromhex("fff8000000000000")),  # negative quiet NaN
)
STRINGS: tuple[bytes, ...] = (
    b"",
    b"\x00",
    b"A" * 255,
    b"A" * 4096,
    b"\xff\xfe\xfd",  # not UTF-8
    b"\xc3\x28",  # invalid UTF-8 continuation
    b"\xc0\xaf",  # overlong '/'
    b"\xed\xa0\x80",  # UTF-8 encoded surrogate
    "Ärger ß µ".encode("latin-1"),
    "日本".encode(),
    b"%s%s%n%x%p",
    b"../../../../../../etc/passwd",
    b"/dev/zero",
    b"nul\x00hidden",
    b"\r\n\r\n",
    b"<?xml",
    b"-1",
    b"nan",
    b"inf",
    b"1e309",
    b"9" * 5000,
    b"0x7fffffff",
    b" ",
)
BIG_STRING_SIZES = (65_536, 1 << 20)  # bytes; beyond the codec's frame limit comes from the length lies


@functools.cache
def request_defs(forbidden: frozenset[int] = frozenset()) -> tuple[TelegramDef, ...]:
    """Request telegrams with a known layout, less the ids in ``forbidden``."""
    return tuple(t for t in load_telegrams() if t.layout_known and t.request is not None and t.id not in forbidden)


# Telegrams whose handling costs a server milliseconds (documents: parse, validate, file I/O; big replies).
# They get ``HEAVY_WEIGHT`` of a plain telegram's share, so a campaign's cases/s is not set by them alone (the
# usual fuzzing trade: favour fast inputs). Static, so the case stream stays a function of the seed.
HEAVY = frozenset(
    {
        "CMD_SET_MAP",
        "CMD_SET_ROADMAP",
        "CMD_SET_PROGRAM",
        "CMD_LOAD_MAP",
        "CMD_LOAD_ROADMAP",
        "CMD_LOAD_PROGRAM",
        "CMD_SAVE_MAP",
        "CMD_SAVE_ROADMAP",
        "CMD_SAVE_PROGRAM",
        "CMD_GET_MAP",
        "CMD_GET_ROADMAP",
        "CMD_GET_PROGRAM",
        "CMD_GET_PLTF_PARAM_VEC",
        "CMD_GET_DEBUG_DATA",
        "CMD_GET_STATUS",
    }
)
HEAVY_WEIGHT = 0.1


T = TypeVar("T")


def weighted(rng: random.Random, population: Sequence[T], cum_weights: list[float]) -> T:
    """``rng.choices(population, weights)[0]`` from the weights' running sums, computed once: the same draw from
    the same state (``random.choices`` sums the weights on every call)."""
    return population[bisect.bisect(cum_weights, rng.random() * (cum_weights[-1] + 0.0), 0, len(cum_weights) - 1)]


@functools.cache
def _cum_weights(forbidden: frozenset[int]) -> list[float]:
    return list(itertools.accumulate(HEAVY_WEIGHT if t.name in HEAVY else 1.0 for t in request_defs(forbidden)))


def pick_telegram(rng: random.Random, forbidden: frozenset[int]) -> TelegramDef:
    return weighted(rng, request_defs(forbidden), _cum_weights(forbidden))


@functools.cache
def request_def(ident: int) -> TelegramDef:
    return next(t for t in request_defs() if t.id == ident)


@functools.cache
def _free_ids(forbidden: frozenset[int]) -> tuple[int, ...]:
    return tuple(i for i in range(256) if i not in forbidden)


_SORTED_ALLOWED: dict[int, tuple[FieldDef, tuple[int, ...] | None]] = {}  # id(field) -> (field, its values sorted)


def _sorted_allowed(f: FieldDef) -> tuple[int, ...] | None:
    """``sorted(allowed_values(f))``, once per field (fields live as long as the process: ``load_telegrams``)."""
    known = _SORTED_ALLOWED.get(id(f))
    if known is None or known[0] is not f:
        allowed = allowed_values(f)
        known = _SORTED_ALLOWED[id(f)] = (f, None if allowed is None else tuple(sorted(allowed)))
    return known[1]


def _valid_scalar(f: FieldDef, rng: random.Random) -> Any:
    allowed = _sorted_allowed(f)
    if allowed is not None:
        return rng.choice(allowed)
    if f.type == "DOUBLE":
        return rng.choice(BOUNDARY["DOUBLE"]) if rng.random() < 0.5 else rng.uniform(-1e6, 1e6)
    rng_ = value_range(f)
    if rng_ is not None:
        lo, hi = max(rng_[0], I32_MIN), min(rng_[1], I32_MAX)
        return rng.choice((lo, hi, rng.randint(lo, hi)))
    if rng.random() < 0.6:
        return rng.choice(BOUNDARY[f.type])
    bits = WIRE[f.type][1] * 8
    return rng.randrange(1 << bits) - (0 if f.type in ("BYTE", "BOOL") else 1 << (bits - 1))


def _hostile_scalar(f: FieldDef, rng: random.Random) -> tuple[Any, str]:
    if f.type == "DOUBLE":
        v = rng.choice(HOSTILE_DOUBLES)
        return v, v.data.hex()
    allowed, rng_ = allowed_values(f), value_range(f)
    picks: list[int] = []
    if allowed is not None:
        picks += [max(allowed) + 1, min(allowed) - 1, 0xFF, -1]
    if rng_ is not None:
        picks += [rng_[0] - 1, rng_[1] + 1]
    picks += list(INT_EDGES[9:]) if f.type == "INT" else [0xFF, 0x80]
    pick = rng.choice(picks)
    return pick, str(pick)


def _string(rng: random.Random, kb: Knowledge, f: FieldDef, telegram: str) -> bytes:
    if f.type == "XML":
        kind = {"CMD_SET_MAP": "map", "CMD_SET_ROADMAP": "roadmap", "CMD_SET_PROGRAM": "program"}[telegram]
        if rng.random() < 0.5:
            return xml_attacks.attack(kind, rng)[1]
        doc = kb.documents.get(telegram.replace("SET", "GET"))
        return doc if doc is not None else xml_attacks.ABSURD[kind](kind, rng)
    is_key = telegram in ("CMD_SET_PLTF_PARAM", "CMD_GET_PLTF_PARAM") and f.name == "key"
    if is_key and kb.param_keys and rng.random() < 0.8:
        return rng.choice(kb.param_keys).encode("latin-1")
    if telegram == "CMD_MOVE_TO_STATION" and kb.stations and rng.random() < 0.7:
        return rng.choice(kb.stations).encode("latin-1")
    if rng.random() < 0.01:
        return b"B" * rng.choice(BIG_STRING_SIZES)
    return rng.choice(STRINGS)


def field_values(tdef: TelegramDef, rng: random.Random, kb: Knowledge, hostility: float) -> tuple[list[Any], list[str]]:
    """Values for each user field of ``tdef``'s request and notes on the hostile ones."""
    values: list[Any] = []
    notes: list[str] = []
    for f in tdef.request or ():
        if f.const is not None:
            continue
        hostile = rng.random() < hostility
        if f.is_group:
            n = rng.choice((0, 1, 2, 8, 100))
            sub = [g for g in f.fields if g.const is None]
            items = tuple(tuple(_valid_scalar(g, rng) for g in sub) for _ in range(n))
            if tdef.name == "CMD_MOVE_PATH" and items and rng.random() < 0.5:  # near where the robot is
                x, y, a = kb.pose
                items = tuple((x + rng.randint(-2000, 2000), y + rng.randint(-2000, 2000), a) for _ in items)
            declared = None
            if hostile:
                declared = rng.choice((-1, I32_MIN, I32_MAX, n + 1, max(n - 1, 0) if n else 1, 0x40000000, 2**31))
                notes.append(f"{f.name}.count={declared - (2**32 if declared >= 2**31 else 0)} (items {n})")
            values.append(Group(items, declared))
        elif f.type in ("STRING", "XML"):
            data = _string(rng, kb, f, tdef.name)
            declared = None
            if hostile:
                declared = rng.choice((-1, I32_MIN, 0, len(data) + 1, len(data) - 1, I32_MAX, 2**31, 2**32 - 1))
                notes.append(f"{f.name}.length={declared} (bytes {len(data)})")
            values.append(Str(data, declared))
        elif hostile:
            if f.repeat:
                v, note = _hostile_scalar(f, rng)
                values.append([v] * f.repeat)
            else:
                v, note = _hostile_scalar(f, rng)
                values.append(v)
            notes.append(f"{f.name}={note}")
        elif f.repeat:
            values.append([_valid_scalar(f, rng) for _ in range(f.repeat)])
        else:
            values.append(_valid_scalar(f, rng))
    return values, notes


def gen_telegram(tdef: TelegramDef, rng: random.Random, kb: Knowledge, hostility: float, origin: str) -> Case:
    values, notes = field_values(tdef, rng, kb, hostility)
    data = pack_fields(tdef.id, tdef.request or (), values)
    tail = rng.random()
    if hostility and tail < 0.08:
        data += bytes(rng.randrange(256) for _ in range(rng.choice((1, 3, 8))))
        notes.append("trailing bytes")
    elif hostility and tail < 0.16 and len(data) > 1:
        data = data[: rng.randrange(1, len(data))]
        notes.append(f"data cut to {len(data)} bytes")
    return Case((frame(data),), origin, tdef.name, "; ".join(notes))


def gen_unknown_id(rng: random.Random, kb: Knowledge, forbidden: frozenset[int]) -> Case:
    ident = rng.choice(_free_ids(forbidden))
    payload = bytes(rng.randrange(256) for _ in range(rng.choice((0, 0, 1, 4, 8, 16))))
    return Case((frame(bytes([ident]) + payload),), "gen.any_id", f"id {ident}", f"payload {payload.hex()}")


def gen_length_field(rng: random.Random, kb: Knowledge, forbidden: frozenset[int]) -> Case:
    """A frame whose own length field lies (0, one short, one long, huge, over 2^31)."""
    return length_field_case(pick_telegram(rng, forbidden), rng, kb)


def length_field_case(tdef: TelegramDef, rng: random.Random, kb: Knowledge) -> Case:
    values, _ = field_values(tdef, rng, kb, 0.0)
    data = pack_fields(tdef.id, tdef.request or (), values)
    declared = rng.choice((0, len(data) - 1, len(data) + 1, 0x00FFFFFF, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFF))
    return Case((frame_lie(data, declared),), "gen.length_field", tdef.name, f"length={declared} (data {len(data)})")


Generator = Callable[[random.Random, Knowledge, frozenset[int]], Case]


def make_spec_generator(hostility: float, origin: str) -> Generator:
    def generate(rng: random.Random, kb: Knowledge, forbidden: frozenset[int]) -> Case:
        tdef = pick_telegram(rng, forbidden)
        return gen_telegram(tdef, rng, kb, hostility, origin)

    return generate


def gen_xml(rng: random.Random, kb: Knowledge, forbidden: frozenset[int]) -> Case:
    name = rng.choice(("CMD_SET_MAP", "CMD_SET_ROADMAP", "CMD_SET_PROGRAM"))
    kind = {"CMD_SET_MAP": "map", "CMD_SET_ROADMAP": "roadmap", "CMD_SET_PROGRAM": "program"}[name]
    attack, doc = xml_attacks.attack(kind, rng)
    tdef = next(t for t in request_defs() if t.name == name)
    if tdef.id in forbidden:
        return gen_unknown_id(rng, kb, forbidden)
    return Case((_xml_frame(tdef, doc),), f"xml.{attack}", name, f"{kind} document of {len(doc)} bytes")


_XML_FRAMES: dict[tuple[int, int], tuple[bytes, bytes]] = {}  # (telegram id, id(doc)) -> (doc, its frame)
XML_FRAMES_KEPT = 64  # frames of documents kept (the big documents are a handful, built once: xml_attacks)


def _xml_frame(tdef: TelegramDef, doc: bytes) -> bytes:
    """The frame of ``tdef`` carrying ``doc``; one frame object per document object and telegram, so that the
    scheduler's look at a big case (``pltf.fuzz.schedule``) is done once per document, not once per draw (a 6 MiB
    document took ~4 ms a draw to copy twice and scan twice)."""
    key = (tdef.id, id(doc))
    known = _XML_FRAMES.get(key)
    if known is not None and known[0] is doc:
        return known[1]
    values: list[Any] = [Str(doc)] if tdef.name == "CMD_SET_PROGRAM" else [Str(b"fuzz"), Str(doc)]
    data = frame(pack_fields(tdef.id, tdef.request or (), values))
    if len(_XML_FRAMES) >= XML_FRAMES_KEPT:
        _XML_FRAMES.clear()
    _XML_FRAMES[key] = (doc, data)
    return data


GENERATORS: dict[str, tuple[float, Generator]] = {
    # name: (weight, generator)
    "gen.boundary": (5.0, make_spec_generator(0.0, "gen.boundary")),
    "gen.hostile": (3.0, make_spec_generator(0.35, "gen.hostile")),
    "gen.any_id": (1.0, gen_unknown_id),
    "gen.length_field": (0.7, gen_length_field),
    "gen.xml": (0.15, gen_xml),
}
