"""What every language module renders the same way, driven by that language's tables.

Rules:
- A language module says how its language spells things (a ``Spelling``, conversion tables keyed by
  ``kind``, one-line shell commands); the loops over fields, telegrams, commands and scripts live here once.
- Text that is the same for every telegram stays in ``templates/`` (``templates/shell/`` for the scripts that
  every language has); nothing here knows one language's syntax.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from pltf.stubgen import banner, fill, template
from pltf.stubgen.model import (
    ERRORS,
    Command,
    Field,
    Message,
    camel,
    commands,
    enums,
    field_doc,
    item_types,
    messages,
    snake,
)

DIRECTIONS = ("request", "reply")

# The optional attributes of a field descriptor, in the order every language writes them, and when each is there.
ATTRIBUTES: dict[str, Callable[[Field], bool]] = {
    "repeat": lambda f: bool(f.repeat),
    "const": lambda f: f.const is not None,
    "min": lambda f: f.min is not None,
    "max": lambda f: f.max is not None,
    "allowed": lambda f: f.allowed is not None,
    "group": lambda f: f.is_group,
    "convert": lambda f: not f.is_group and (f.enum is not None or f.type == "BOOL"),  # the host type, if not plain
    "run": lambda f: bool(f.run),
}

# The attributes as chained builder calls, spelled alike by the languages that build descriptors that way.
BUILDER = {
    "repeat": ".repeat({f.repeat})",
    "const": ".constant({f.const})",
    "min": ".min({f.min})",
    "max": ".max({f.max})",
    "run": ".run({f.run})",
}


@dataclass(frozen=True)
class Spelling:
    """How one language writes a field's type, a field descriptor and a table of descriptors.

    The descriptor's ``head`` and ``attrs`` are ``str.format`` templates over ``f`` (the Field) and the keys of
    ``_values``: ``type`` (``type_name`` of the spec type), ``allowed`` (comma-separated), ``allowed_repr``,
    ``item`` / ``item_snake`` / ``ITEM`` (the group item type), ``prop`` (camelCase name) and ``convert``.
    """

    scalars: Mapping[str, str]  # spec type -> the language's type of one value
    group: str  # a group's type, from {item}
    array: str  # a fixed array's type, from {base} and {repeat}
    head: str  # the descriptor's first part
    attrs: Mapping[str, str]  # ATTRIBUTES this language writes -> their template
    empty: str  # a table without fields
    open: str  # a table's first line
    close: str  # after a table's rows, from {indent}
    step: str  # a row's indent beyond the table's
    trailing: bool = True  # a comma after the last row too
    sep: str = ", "  # between the head and the attributes
    wrap: tuple[str, str] = ("", "")  # around the descriptor
    type_name: Callable[[str], str] = str
    member: str = ""  # a field's declaration in a type, from {name}, {type}, {doc} and {default}
    field_name: Callable[[str], str] = str  # a field's name in the language

    def type(self, f: Field, prefix: str = "") -> str:
        """The field's type; ``prefix`` qualifies the names the spec defines (an enum, a group item)."""
        if f.is_group:
            return self.group.format(item=f"{prefix}{f.item}")
        base = f"{prefix}{f.enum}" if f.enum else self.scalars[f.type]
        return self.array.format(base=base, repeat=f.repeat) if f.repeat else base

    def members(
        self, fields: Sequence[Field], member: str | None = None, default: Callable[[Field], str] = lambda f: ""
    ) -> list[str]:
        """The declarations of the user fields (``member``: this spelling's by default)."""
        spelled = self.member if member is None else member
        return [
            spelled.format(name=self.field_name(f.name), type=self.type(f), doc=field_doc(f), default=default(f))
            for f in fields
            if f.user
        ]

    def descriptor(self, f: Field) -> str:
        values = _values(f, self.type_name)
        parts = [self.head.format(**values)]
        parts += [
            self.attrs[attr].format(**values)
            for attr, present in ATTRIBUTES.items()
            if attr in self.attrs and present(f)
        ]
        return self.wrap[0] + self.sep.join(parts) + self.wrap[1]

    def table(self, fields: Sequence[Field], indent: str = "") -> str:
        if not fields:
            return self.empty
        rows = [f"{indent}{self.step}{self.descriptor(f)}" for f in fields]
        body = "".join(row + ",\n" for row in rows) if self.trailing else ",\n".join(rows)
        return f"{self.open}\n{body}{self.close.format(indent=indent)}"


def _values(f: Field, type_name: Callable[[str], str]) -> dict[str, Any]:
    item = f.item or ""
    return {
        "f": f,
        "type": type_name(f.type),
        "allowed": ", ".join(map(str, f.allowed or ())),
        "allowed_repr": repr(f.allowed),
        "item": item,
        "item_snake": snake(item),
        "ITEM": snake(item).upper(),
        "prop": camel(f.name),
        "convert": f.enum or "bool",
    }


def kind(f: Field) -> str:
    """The key of a field in a language's conversion tables (``convert``)."""
    if f.is_group:
        return "group"
    if f.repeat:
        return "enum_array" if f.enum else f"array_{f.type}"
    return "enum" if f.enum else f.type


# A conversion table falls back from the specific key to the general one (a table lists only what it spells).
FALLBACK = {
    "enum_array": "array",
    "array_BYTE": "array",
    "array_INT16": "array",
    "array_INT": "array",
    "STRING": "text",
    "XML": "text",
    "enum": "int",
    "BYTE": "int",
    "INT16": "int",
    "INT": "int",
}


def convert(table: Mapping[str, str], f: Field, **values: str) -> str:
    """The table's template for ``kind(f)`` (or its fallback), formatted with ``f``, ``enum``, ``item`` and values."""
    key = kind(f)
    while key not in table:
        key = FALLBACK[key]
    return table[key].format(f=f, enum=f.enum, item=f.item, **values)


# ---------------------------------------------------------------------------------------------- modules


def protocol(
    head: Sequence[str],
    enum: Callable[[str], str],
    item: Callable[[str, tuple[Field, ...]], str],
    telegram: Callable[[Message], str],
    registry: Callable[[str, tuple[Message, ...]], str],
    after_enums: Iterable[str] = (),
    end: str = "\n",
) -> str:
    """A protocol module: ``head``, then enums, group items, telegrams and one registry a direction, one
    section a line apart, and ``end`` after the last."""
    sections = [
        *head,
        *map(enum, enums()),
        *after_enums,
        *(item(name, fields) for name, fields in item_types().items()),
        *(telegram(m) for direction in DIRECTIONS for m in messages(direction)),
        *(registry(direction, messages(direction)) for direction in DIRECTIONS),
    ]
    return "\n".join(sections).rstrip("\n") + end


def error_classes(spelled: str, root: str, end: str = "", **roots: tuple[str, str]) -> str:
    """One class per error of ``ERRORS``, a blank line apart, then ``end``: ``spelled`` formatted with ``name``,
    ``doc``, ``base`` (the parent; ``root`` for the family's root), ``base_name`` (its last ``::`` part) and each of
    ``roots`` (its first value for the root class, its second for the others)."""
    classes = []
    for name, parent, doc in ERRORS:
        base = parent or root
        extra = {key: values[parent is not None] for key, values in roots.items()}
        classes.append(spelled.format(name=name, doc=doc, base=base, base_name=base.rsplit("::")[-1], **extra))
    return "\n".join(classes).rstrip("\n") + end


def arguments(
    m: Message, payload: tuple[str, str], field: Callable[[Field], tuple[str, str]]
) -> tuple[list[str], list[str]]:
    """A client method's parameters and the request's arguments: ``payload`` for an opaque telegram, else one
    ``field(f)`` pair per user field."""
    pairs = [payload] if m.opaque else [field(f) for f in m.user_fields]
    return [p for p, _ in pairs], [a for _, a in pairs]


def methods(
    parts: Callable[[Message], dict[str, str]], spelled: tuple[str, str], lead: str = "\n", end: str = ""
) -> str:
    """The client's methods, one per command, as one block between ``lead`` and ``end``.

    ``spelled``: the templates of a method without reply and with one, formatted with ``m`` (the request),
    ``reply`` (the reply type's name) and ``parts(m)`` (the language's name, parameters, request, doc ...).
    """

    def method(c: Command) -> str:
        reply = "" if c.reply is None else c.reply.type_name
        return spelled[c.reply is not None].format(m=c.request, reply=reply, **parts(c.request))

    return lead + "\n".join(map(method, commands())).rstrip("\n") + end


# ---------------------------------------------------------------------------------------------- files


def scripts(lang: str, build: str, smoke: str, vectors: str, ignore: str) -> dict[str, str]:
    """build.sh (its one-line description ``build`` and ``templates/<lang>/build.sh.tmpl``), smoke.sh and
    vectors.sh (running the commands ``smoke`` and ``vectors``), and .gitignore (the lines ``ignore``)."""
    head = banner("# ")
    return {
        "build.sh": fill(
            template("shell", "build.sh.tmpl"), BANNER=head, WHAT=build, STEPS=template(lang, "build.sh.tmpl")
        ),
        "smoke.sh": fill(template("shell", "smoke.sh.tmpl"), BANNER=head, RUN=smoke),
        "vectors.sh": fill(template("shell", "vectors.sh.tmpl"), BANNER=head, RUN=vectors),
        ".gitignore": head + ignore,
    }


def static(lang: str, head: str, files: Mapping[str, str]) -> dict[str, str]:
    """Files copied from ``templates/<lang>/`` (output path -> template name), each after ``head``."""
    return {path: head + template(lang, name) for path, name in files.items()}
