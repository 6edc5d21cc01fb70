"""Load the spec data (telegrams.yaml, enums.yaml) once, validated against its JSON Schema.

Rules: this module only reads the package's own data files; it builds plain frozen dataclasses that every
other part of the toolkit (codec, server dispatch, conformance catalogue, fuzzer, stub generator) reads.
"""

from __future__ import annotations

import enum
import functools
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import jsonschema
import yaml

SPEC_DIR = Path(__file__).resolve().parent

Direction = Literal["request", "reply"]
DIRECTIONS: tuple[Direction, Direction] = ("request", "reply")


class SpecError(Exception):
    """The spec data itself is invalid (a bug in spec/, never a peer's fault)."""


@dataclass(frozen=True)
class FieldDef:
    """One field of a telegram or of a repeated group."""

    name: str
    type: str
    description: str
    unit: str | None = None
    enum: str | None = None
    repeat: int | None = None
    const: int | None = None
    min: int | None = None
    max: int | None = None
    item: str | None = None
    fields: tuple[FieldDef, ...] = ()

    @property
    def is_group(self) -> bool:
        return self.type == "GROUP"


@dataclass(frozen=True)
class TelegramDef:
    """One telegram identifier with its request layout and, if answered, its reply layout."""

    name: str
    id: int
    category: str
    section: str
    summary: str
    layout_known: bool
    request: tuple[FieldDef, ...] | None
    reply: tuple[FieldDef, ...] | None
    aliases: tuple[str, ...] = ()

    @property
    def answered(self) -> bool:
        """Guide 6.1: the server "returns data only on request": only telegrams with a reply are answered."""
        return self.reply is not None and self.layout_known

    def layout(self, direction: Direction) -> tuple[FieldDef, ...] | None:
        return self.request if direction == "request" else self.reply


@dataclass(frozen=True)
class EnumDef:
    name: str
    section: str
    description: str
    values: dict[str, int]


def _load_yaml(name: str) -> Any:
    with (SPEC_DIR / name).open(encoding="utf-8") as fh:
        return yaml.load(fh, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))


def _validate(data: Any, schema_name: str) -> None:
    schema = json.loads((SPEC_DIR / schema_name).read_text(encoding="utf-8"))
    validator = jsonschema.Draft202012Validator(schema)
    errors = sorted(validator.iter_errors(data), key=lambda e: list(e.absolute_path))
    if errors:
        first = errors[0]
        where = "/".join(str(p) for p in first.absolute_path)
        raise SpecError(f"{schema_name}: {where}: {first.message}")


def _field(raw: dict[str, Any]) -> FieldDef:
    return FieldDef(
        name=raw["name"],
        type=raw["type"],
        description=raw["description"],
        unit=raw.get("unit"),
        enum=raw.get("enum"),
        repeat=raw.get("repeat"),
        const=raw.get("const"),
        min=raw.get("min"),
        max=raw.get("max"),
        item=raw.get("item"),
        fields=tuple(_field(f) for f in raw.get("fields", ())),
    )


def _fields(raw: list[dict[str, Any]] | None) -> tuple[FieldDef, ...] | None:
    return None if raw is None else tuple(_field(f) for f in raw)


def _check_names(tdef: TelegramDef, enums: dict[str, EnumDef]) -> None:
    def walk(fields: tuple[FieldDef, ...], where: str) -> None:
        seen: set[str] = set()
        for f in fields:
            if f.name in seen:
                raise SpecError(f"{where}: duplicate field {f.name}")
            seen.add(f.name)
            if f.enum is not None and f.enum not in enums:
                raise SpecError(f"{where}.{f.name}: unknown enum {f.enum}")
            if f.is_group:
                walk(f.fields, f"{where}.{f.name}")
                if any(g.is_group for g in f.fields):
                    raise SpecError(f"{where}.{f.name}: nested groups are not supported")

    for direction in DIRECTIONS:
        layout = tdef.layout(direction)
        if layout is not None:
            walk(layout, f"{tdef.name}.{direction}")


@functools.cache
def load_enums() -> dict[str, EnumDef]:
    raw = _load_yaml("enums.yaml")
    _validate(raw, "enums.schema.json")
    return {
        name: EnumDef(name, body["section"], body["description"], dict(body["values"]))
        for name, body in raw.items()
    }


@functools.cache
def load_telegrams() -> tuple[TelegramDef, ...]:
    raw = _load_yaml("telegrams.yaml")
    _validate(raw, "telegrams.schema.json")
    enums = load_enums()
    out: list[TelegramDef] = []
    ids: set[int] = set()
    names: set[str] = set()
    for t in raw["telegrams"]:
        known = t.get("layout", "known") == "known"
        tdef = TelegramDef(
            name=t["name"],
            id=t["id"],
            category=t["category"],
            section=t["section"],
            summary=t["summary"],
            layout_known=known,
            request=_fields(t.get("request")),
            reply=_fields(t.get("reply")),
            aliases=tuple(t.get("aliases", ())),
        )
        if tdef.id in ids or tdef.name in names:
            raise SpecError(f"{tdef.name}: duplicate id {tdef.id} or name")
        ids.add(tdef.id)
        names.add(tdef.name)
        _check_names(tdef, enums)
        out.append(tdef)
    return tuple(sorted(out, key=lambda d: d.id))


def telegram_def(name: str) -> TelegramDef:
    """The definition of the telegram called ``name`` (KeyError for an unknown name)."""
    return _telegrams_by_name()[name]


@functools.cache
def _telegrams_by_name() -> dict[str, TelegramDef]:
    return {t.name: t for t in load_telegrams()}


@functools.cache
def enum_classes() -> dict[str, type[enum.IntEnum]]:
    """Every enum table of the spec as an ``enum.IntEnum`` (names exactly as in the guide)."""
    return {
        name: enum.IntEnum(name, e.values, module=__name__)  # type: ignore[misc]
        for name, e in load_enums().items()
    }
