"""The language-neutral view of the spec that every language module renders.

Rules:
- Only this module reads ``pltf.spec.model``; the language modules see ``Message``/``Field`` and the name helpers.
- Everything a generated decoder needs to behave exactly like ``pltf.spec.codec`` is precomputed here, so the
  generated runtimes stay small and identical in logic: the allowed values of enum and BOOL fields, the byte
  size of each run of fixed-size fields (checked whole before the run is read, as ``struct.unpack_from``
  does), and the fewest bytes a group item can take (a count is refused before any allocation).
- The canonical value dump (``dump``) is the one text the vector runners of all languages compare.
"""

from __future__ import annotations

import functools
import math
import re
import struct
from dataclasses import dataclass
from typing import Any

from pltf.spec.model import EnumDef, FieldDef, TelegramDef, load_enums, load_telegrams

GENERATOR = "pltf.stubgen (pltf stubs)"
SCALAR_SIZE = {"BYTE": 1, "BOOL": 1, "INT16": 2, "INT": 4, "DOUBLE": 8}
INT_BOUNDS = {"BYTE": (0, 255), "BOOL": (0, 1), "INT16": (-(2**15), 2**15 - 1), "INT": (-(2**31), 2**31 - 1)}
TYPE_CODES = ("BYTE", "BOOL", "INT16", "INT", "DOUBLE", "STRING", "XML", "GROUP")

# (name, parent, doc): the error family of spec/errors.py, rendered into every language.
ERRORS: tuple[tuple[str, str | None, str], ...] = (
    ("ProtocolError", None, "Base of every codec error."),
    ("LocalProtocolError", "ProtocolError", "We tried to encode a telegram the protocol does not allow."),
    ("FieldValueError", "LocalProtocolError", "A field value is of the wrong type or outside its range."),
    ("RemoteProtocolError", "ProtocolError", "The peer sent bytes the protocol does not allow."),
    ("BadHeader", "RemoteProtocolError", "The frame does not start with FF 01 FE 02 (guide 6.2)."),
    ("FrameTooLarge", "RemoteProtocolError", "The frame's length is over the maximum (checked before buffering)."),
    ("Truncated", "RemoteProtocolError", "The stream ended inside a frame, or a telegram is shorter than its layout."),
    ("TrailingBytes", "RemoteProtocolError", "Bytes are left after the last field, or after the frame."),
    ("UnknownTelegram", "RemoteProtocolError", "The telegram identifier is not in the spec (or there is none)."),
    ("FieldOutOfRange", "RemoteProtocolError", "A decoded field is outside its enum, its range or its constant."),
    ("LengthMismatch", "RemoteProtocolError", "A length or count is negative or larger than the bytes left."),
)
LEAF_ERRORS = tuple(
    name for name, _, _ in ERRORS if name not in {"ProtocolError", "LocalProtocolError", "RemoteProtocolError"}
)


@dataclass(frozen=True)
class Field:
    name: str
    type: str
    description: str
    unit: str | None
    enum: str | None
    repeat: int  # 0: a single value
    const: int | None
    min: int | None
    max: int | None
    allowed: tuple[int, ...] | None  # enum values, or (0, 1) for BOOL
    item: str | None  # group item type name
    fields: tuple[Field, ...]  # group item fields (constants included)
    run: int  # bytes of the run of fixed-size fields that starts here; 0 when no run starts here
    item_min: int  # group: the fewest bytes one item takes

    @property
    def user(self) -> bool:
        return self.const is None

    @property
    def is_group(self) -> bool:
        return self.type == "GROUP"

    @property
    def is_text(self) -> bool:
        return self.type in ("STRING", "XML")

    @property
    def user_fields(self) -> tuple[Field, ...]:
        return tuple(f for f in self.fields if f.user)

    @property
    def code(self) -> int:
        return TYPE_CODES.index(self.type)


@dataclass(frozen=True)
class Message:
    """One telegram in one direction."""

    name: str
    id: int
    direction: str
    opaque: bool
    fields: tuple[Field, ...]
    summary: str
    section: str

    @property
    def user_fields(self) -> tuple[Field, ...]:
        return tuple(f for f in self.fields if f.user)

    @property
    def base(self) -> str:
        """The name without its CMD_ prefix, e.g. GET_POSITION."""
        return self.name.removeprefix("CMD_")

    @property
    def type_name(self) -> str:
        return pascal(self.base) + ("Request" if self.direction == "request" else "Reply")

    @property
    def doc(self) -> str:
        """The one-line description every language's doc comment of the telegram type carries."""
        summary, section = doc_line(self.summary), doc_line(self.section)
        return f"{self.name} ({self.direction}, id {self.id}): {summary} [guide {section}]"


@dataclass(frozen=True)
class Command:
    """One client method: the request and, for GET_* telegrams the server answers, the reply."""

    request: Message
    reply: Message | None


def _fixed_size(f: FieldDef) -> int | None:
    return SCALAR_SIZE[f.type] * (f.repeat or 1) if f.type in SCALAR_SIZE else None


def _min_size(f: FieldDef) -> int:
    size = _fixed_size(f)
    return 4 if size is None else size


def _allowed(f: FieldDef) -> tuple[int, ...] | None:
    if f.enum is not None:
        return tuple(sorted(load_enums()[f.enum].values.values()))
    return (0, 1) if f.type == "BOOL" else None


def _convert(defs: tuple[FieldDef, ...]) -> tuple[Field, ...]:
    out = []
    for i, f in enumerate(defs):
        run = 0
        if _fixed_size(f) is not None and (i == 0 or _fixed_size(defs[i - 1]) is None):
            for g in defs[i:]:
                size = _fixed_size(g)
                if size is None:
                    break
                run += size
        out.append(
            Field(
                name=f.name,
                type=f.type,
                description=f.description,
                unit=f.unit,
                enum=f.enum,
                repeat=f.repeat or 0,
                const=f.const,
                min=f.min,
                max=f.max,
                allowed=_allowed(f),
                item=f.item,
                fields=_convert(f.fields),
                run=run,
                item_min=sum(_min_size(g) for g in f.fields) if f.is_group else 0,
            )
        )
    return tuple(out)


def _message(t: TelegramDef, direction: str) -> Message:
    layout = t.layout(direction)  # type: ignore[arg-type]
    opaque = not t.layout_known or layout is None
    return Message(t.name, t.id, direction, opaque, () if opaque else _convert(layout or ()), t.summary, t.section)


@functools.cache
def messages(direction: str) -> tuple[Message, ...]:
    """Every telegram of one direction, by id (the sets of ``pltf.spec.codec``: opaque ones are in both)."""
    return tuple(
        _message(t, direction)
        for t in load_telegrams()
        if direction == "request" or t.reply is not None or not t.layout_known
    )


@functools.cache
def commands() -> tuple[Command, ...]:
    replies = {m.id: m for m in messages("reply")}
    answered = {t.id for t in load_telegrams() if t.answered}
    return tuple(Command(m, replies[m.id] if m.id in answered else None) for m in messages("request"))


@functools.cache
def item_types() -> dict[str, tuple[Field, ...]]:
    """Group item types by name, each once (the same name always has the same fields)."""
    out: dict[str, tuple[Field, ...]] = {}
    for direction in ("request", "reply"):
        for m in messages(direction):
            for f in m.fields:
                if f.is_group:
                    assert f.item, f"{m.name}.{f.name}: group without item name"
                    sig = tuple((g.name, g.type, g.enum, g.repeat, g.const) for g in f.fields)
                    if f.item in out:
                        old = tuple((g.name, g.type, g.enum, g.repeat, g.const) for g in out[f.item])
                        if old != sig:
                            raise ValueError(f"group item {f.item} has two layouts; rename one in the spec")
                    out[f.item] = f.fields
    return out


def enums() -> dict[str, EnumDef]:
    return load_enums()


def enum_doc(name: str) -> str:
    """The one-line description of an enum type, for its doc comment."""
    e = load_enums()[name]
    return f"{doc_line(e.description)} [guide {doc_line(e.section)}]"


# ---------------------------------------------------------------------------------------------- names


def words(name: str) -> list[str]:
    return [w for w in re.split(r"[_\s]+", name) if w]


def pascal(name: str) -> str:
    return "".join(w[:1].upper() + w[1:].lower() for w in words(name))


def camel(name: str) -> str:
    p = pascal(name)
    return p[:1].lower() + p[1:]


def snake(name: str) -> str:
    return "_".join(w.lower() for w in words(name))


def safe(name: str, keywords: frozenset[str], suffix: str = "_") -> str:
    return name + suffix if name in keywords else name


def doc_line(text: str) -> str:
    """One line of documentation text, safe inside any language's comment."""
    return " ".join(text.split()).replace("*/", "* /")


def field_doc(f: Field) -> str:
    unit = f" [{f.unit}]" if f.unit else ""
    enum = f" ({f.enum})" if f.enum else ""
    return doc_line(f"{f.description}{unit}{enum}")


# ---------------------------------------------------------------------------------------------- dump


def dump_value(f: Field, value: Any) -> str:
    """The canonical text of one field value (see ``dump``)."""
    if f.is_group:
        parts = [f"#{len(value)}"]
        for item in value:
            parts.extend(f"{g.name}={dump_value(g, item[g.name])}" for g in f.user_fields)
        return " ".join(parts)
    if f.repeat:
        return ",".join(_scalar_text(f.type, v) for v in value)
    return _scalar_text(f.type, value)


def _scalar_text(ftype: str, v: Any) -> str:
    if ftype in ("STRING", "XML"):
        return "s" + str(v).encode("latin-1").hex()
    if ftype == "DOUBLE":
        v = float(v)
        return "nan" if math.isnan(v) else struct.pack(">d", v).hex()
    return str(int(v))


def dump(message: Message, fields: dict[str, Any]) -> str:
    """The canonical, language-neutral text of a telegram's field values.

    ``name=value`` tokens separated by one space, in layout order: integers in decimal, DOUBLE as the 16 hex
    digits of its IEEE-754 bits (``nan`` for any NaN), STRING/XML as ``s`` + the hex of its Latin-1 bytes,
    fixed arrays comma-separated, a group as ``#count`` followed by each item's tokens, an opaque payload as
    ``payload=`` + hex. Every generated runtime has the same function; the vector runners compare its text.
    """
    if message.opaque:
        return f"payload={fields.get('payload', '')}"
    return " ".join(f"{f.name}={dump_value(f, fields[f.name])}" for f in message.user_fields)
