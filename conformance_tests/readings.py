"""Strict reply decoding, and the alternative readings of the errata register as reply layouts.

Rules:
- ``decode_reply`` first decodes with the spec's layout (spec.codec): no trailing bytes, counts consistent,
  enums and constants checked. Only when that fails does it try the alternative readings below, single ones
  first, then combinations; a reply that decodes under one is returned in the canonical shape together with
  the ``Deviation`` naming the erratum and the alternative (the profile decides what that costs).
- Each reading is data: a transformation of the spec's layout (retype, resize, drop or insert a field), compiled
  once with ``pltf.spec.compiler.compile_telegram`` like any telegram, or for the few readings a layout cannot
  express (DOUBLE bounds, trailing fields) a small decoder. Readings whose wire layout is identical to the
  decision (E-REP-003 line order, E-REP-012 units, E-REP-013 name-first, E-REP-014 program name) are judged
  by the cases from the values, not here.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
import re
import struct
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pltf.conformance_tests.outcome import BadReply, Deviation
from pltf.spec.codec import REPLIES
from pltf.spec.compiler import compile_telegram
from pltf.spec.errors import RemoteProtocolError, TrailingBytes
from pltf.spec.model import FieldDef, TelegramDef
from pltf.spec.telegram import Telegram, make_item_class, user_fields

Layout = tuple[FieldDef, ...]


def _retype(name: str, new_type: str) -> Callable[[Layout], Layout]:
    return lambda layout: tuple(
        dataclasses.replace(f, type=new_type, enum=None) if f.name == name else f for f in layout
    )


def _resize(name: str, repeat: int) -> Callable[[Layout], Layout]:
    return lambda layout: tuple(dataclasses.replace(f, repeat=repeat) if f.name == name else f for f in layout)


def _drop(name: str) -> Callable[[Layout], Layout]:
    return lambda layout: tuple(f for f in layout if f.name != name)


def _insert_before(name: str, new: FieldDef) -> Callable[[Layout], Layout]:
    def apply(layout: Layout) -> Layout:
        out: list[FieldDef] = []
        for f in layout:
            if f.name == name:
                out.append(new)
            out.append(f)
        return tuple(out)

    return apply


def _in_group(group: str, inner: Callable[[Layout], Layout]) -> Callable[[Layout], Layout]:
    return lambda layout: tuple(
        dataclasses.replace(f, fields=inner(f.fields)) if f.name == group else f for f in layout
    )


def _field(name: str, type_: str, description: str = "alternative reading") -> FieldDef:
    return FieldDef(name=name, type=type_, description=description)


@dataclass(frozen=True)
class Reading:
    erratum: str
    index: int  # into the erratum's alternatives
    telegram: str
    detail: str
    transform: Callable[[Layout], Layout] | None = None
    post: Callable[[dict[str, Any]], dict[str, Any]] | None = None
    decoder: Callable[[bytes], Telegram] | None = None  # a reading no layout can express
    trailing: bool = False  # the reply may carry further fields after the last one

    def deviation(self) -> Deviation:
        return Deviation(self.erratum, self.index, self.detail)


def _pairs_from_ints(plain: dict[str, Any]) -> dict[str, Any]:
    """E-REP-015 alt: the validation gate size counted INTs; pair them up into points."""
    values = [item["v"] for item in plain["validation_gate"]]
    if len(values) % 2:
        raise BadReply("validation gate: an odd number of INTs cannot be X/Y pairs")
    plain["validation_gate"] = [{"x": x, "y": y} for x, y in zip(values[::2], values[1::2], strict=True)]
    return plain


_PARAM_HEAD = struct.Struct(">BB")
_BOUNDS = {2: struct.Struct(">dd")}
_INT_BOUNDS = struct.Struct(">ii")


def _read_string(buf: bytes, pos: int) -> tuple[str, int]:
    (n,) = struct.unpack_from(">i", buf, pos)
    if n < 0 or pos + 4 + n > len(buf):
        raise BadReply(f"string length {n} at offset {pos} overruns the reply")
    return buf[pos + 4 : pos + 4 + n].decode("latin-1"), pos + 4 + n


def _param_entry(buf: bytes, pos: int) -> tuple[tuple[Any, ...], int]:
    key, pos = _read_string(buf, pos)
    value, pos = _read_string(buf, pos)
    category, data_type = _PARAM_HEAD.unpack_from(buf, pos)
    pos += 2
    st = _BOUNDS.get(data_type, _INT_BOUNDS)
    lo, hi = st.unpack_from(buf, pos)
    pos += st.size
    if data_type == 2:
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise BadReply("DOUBLE bounds are not finite")
        lo, hi = max(-(2**31), math.floor(lo)), min(2**31 - 1, math.ceil(hi))
    return (key, value, category, data_type, lo, hi), pos


def _double_bounds(name: str) -> Callable[[bytes], Telegram]:
    """E-REP-004 alt: min/max are DOUBLE for DOUBLE parameters (8+8 bytes instead of 4+4)."""
    cls = REPLIES[name]

    def decode(data: bytes) -> Telegram:
        try:
            if name == "CMD_GET_PLTF_PARAM":
                entry, pos = _param_entry(data, 1)
                items: Any = entry
            else:
                (n,) = struct.unpack_from(">i", data, 1)
                pos, entries = 5, []
                if n < 0 or n > len(data):
                    raise BadReply(f"parameter count {n}")
                for _ in range(n):
                    entry, pos = _param_entry(data, pos)
                    entries.append(entry)
                items = (tuple(entries),)
        except struct.error:
            raise BadReply("reply shorter than its entries") from None
        if pos != len(data):
            raise BadReply(f"{len(data) - pos} bytes after the last field")
        if name == "CMD_GET_PLTF_PARAM_VEC":
            item_cls = _item_class(name, "parameters")
            items = (tuple(item_cls(*e) for e in items[0]),)
        return cls._make(items)  # type: ignore[attr-defined, no-any-return]

    return decode


READINGS: tuple[Reading, ...] = (
    Reading(
        "E-REP-001",
        0,
        "CMD_GET_CAN_MESSAGES",
        "a DLC BYTE precedes the 8 data bytes of each CAN message",
        transform=_in_group("messages", _insert_before("data", _field("dlc", "BYTE"))),
    ),
    Reading("E-REP-002", 0, "CMD_GET_STATUS", "further fields follow the head drive position", trailing=True),
    Reading(
        "E-REP-007",
        0,
        "CMD_GET_STATUS",
        "the ultrasonic board's analogue inputs are 4 INTs, not 8",
        transform=_resize("us_analog_in", 4),
    ),
    Reading(
        "E-REP-009",
        0,
        "CMD_GET_STATUS",
        "the emergency state is a BYTE, not an INT",
        transform=_retype("emergency_state", "BYTE"),
    ),
    Reading(
        "E-REP-011",
        0,
        "CMD_GET_STATUS",
        "the head drive position is a BYTE, not an INT",
        transform=_retype("head_position", "BYTE"),
    ),
    Reading(
        "E-REP-004",
        0,
        "CMD_GET_PLTF_PARAM",
        "min/max are DOUBLE for DOUBLE parameters",
        decoder=_double_bounds("CMD_GET_PLTF_PARAM"),
    ),
    Reading(
        "E-REP-004",
        0,
        "CMD_GET_PLTF_PARAM_VEC",
        "min/max are DOUBLE for DOUBLE parameters",
        decoder=_double_bounds("CMD_GET_PLTF_PARAM_VEC"),
    ),
    Reading(
        "E-REP-013",
        0,
        "CMD_GET_MAP",
        "a BYTE 'number of characters' precedes the XML",
        transform=lambda layout: (_field("chars", "BYTE"), *layout),
    ),
    Reading(
        "E-REP-013",
        0,
        "CMD_GET_ROADMAP",
        "a BYTE 'number of characters' precedes the XML",
        transform=lambda layout: (_field("chars", "BYTE"), *layout),
    ),
    Reading(
        "E-REP-015",
        0,
        "CMD_GET_DEBUG_DATA",
        "the validation gate size counts INT values, not points",
        transform=lambda layout: tuple(
            dataclasses.replace(f, fields=(_field("v", "INT"),)) if f.name == "validation_gate" else f for f in layout
        ),
        post=_pairs_from_ints,
    ),
    Reading(
        "E-REP-017",
        0,
        "CMD_GET_DEBUG_DATA",
        "no 'INT 0' row follows the graphical objects",
        transform=_drop("reserved"),
    ),
    Reading(
        "E-REP-019",
        0,
        "CMD_GET_DEBUG_DATA",
        "an extra INT precedes the person clusters",
        transform=_insert_before("person_clusters", _field("extra", "INT")),
    ),
)


def readings_for(name: str) -> list[Reading]:
    return [r for r in READINGS if r.telegram == name]


@functools.cache
def _item_class(name: str, group: str) -> Any:
    """The canonical item class of a reply's group (the one the codec builds)."""
    f = next(f for f in user_fields(REPLIES[name].DEF.reply or ()) if f.name == group)
    return make_item_class(f.item or f.name, f.fields)


def _default(f: FieldDef) -> Any:
    if f.is_group:
        return ()
    if f.type in ("STRING", "XML"):
        return ""
    zero = 0.0 if f.type == "DOUBLE" else 0
    return (zero,) * f.repeat if f.repeat else zero


def _canonical_value(f: FieldDef, value: Any, name: str) -> Any:
    if f.is_group:
        item_cls = _item_class(name, f.name)
        sub = user_fields(f.fields)
        return tuple(item_cls(*(it.get(g.name, _default(g)) for g in sub)) for it in value)
    if f.repeat:
        vals = tuple(value)[: f.repeat]
        return vals + _default(f)[len(vals) :]
    return value


def _plain(t: Telegram) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in zip(t._fields, t, strict=True):
        if isinstance(v, tuple) and v and hasattr(v[0], "_asdict"):
            out[k] = [it._asdict() for it in v]
        else:
            out[k] = v
    return out


def canonical(name: str, plain: dict[str, Any]) -> Telegram:
    cls = REPLIES[name]
    layout = user_fields(cls.DEF.reply or ())
    return cls._make(_canonical_value(f, plain.get(f.name, _default(f)), name) for f in layout)  # type: ignore[attr-defined, no-any-return]


_TRAILING = re.compile(r"(\d+) bytes after the last field")


@functools.cache
def _combined_decoder(name: str, combo: tuple[Reading, ...]) -> Callable[[bytes], Telegram]:
    tdef: TelegramDef = REPLIES[name].DEF
    layout = tdef.reply or ()
    for r in combo:
        if r.transform is not None:
            layout = r.transform(layout)
    _cls, decode, _enc = compile_telegram(dataclasses.replace(tdef, reply=layout), "reply")
    trailing = any(r.trailing for r in combo)
    posts = [r.post for r in combo if r.post is not None]

    def run(data: bytes) -> Telegram:
        try:
            alt = decode(data)
        except TrailingBytes as exc:
            m = _TRAILING.search(str(exc))
            if not trailing or m is None:
                raise
            alt = decode(data[: len(data) - int(m.group(1))])
        plain = _plain(alt)
        for post in posts:
            plain = post(plain)
        return canonical(name, plain)

    return run


def _combinations(name: str) -> list[tuple[Reading, ...]]:
    layout_readings = [r for r in readings_for(name) if r.decoder is None]
    combos: list[tuple[Reading, ...]] = []
    for size in range(1, len(layout_readings) + 1):
        combos.extend(itertools.combinations(layout_readings, size))
    # The trailing-fields reading stands alone and comes last: combined with a shorter layout it would explain
    # any reply that is merely cut short ("head drive as BYTE, plus two bytes of further fields").
    combos = [c for c in combos if len(c) == 1 or not any(r.trailing for r in c)]
    return sorted(combos, key=lambda c: (any(r.trailing for r in c), len(c)))


def decode_reply(data: bytes, name: str) -> tuple[Telegram, list[Deviation]]:
    """Decode reply ``data`` (identifier first) of request ``name``: strictly, else by an alternative reading."""
    try:
        return REPLIES.decode_data(data), []
    except RemoteProtocolError as exc:
        strict_error = exc
    for r in readings_for(name):
        if r.decoder is not None:
            try:
                return r.decoder(data), [r.deviation()]
            except (RemoteProtocolError, BadReply):
                continue
    for combo in _combinations(name):
        try:
            telegram = _combined_decoder(name, combo)(data)
        except (RemoteProtocolError, BadReply):
            continue
        return telegram, [r.deviation() for r in combo]
    errata = sorted({r.erratum for r in readings_for(name)})
    hint = f" (alternative readings of {', '.join(errata)} tried too)" if errata else ""
    raise BadReply(f"{name} reply of {len(data)} bytes does not decode: {strict_error}{hint}")
