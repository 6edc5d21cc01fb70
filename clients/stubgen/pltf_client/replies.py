"""``_enums.py`` and ``_replies.py``: the IntEnums, the typed reply classes and the items of repeated groups.

Rules:
- Flag/BOOL fields become ``bool``, enum fields the generated IntEnum, XML fields the document's ``bytes``
  (erratum E-WIRE-003). An item class is shared by every group with the same ``item`` name (same fields, or the
  generator stops).
- The text that is the same for every telegram is ``templates/pltf_client/_replies.py.tmpl``; this module
  renders the classes and the tables between its placeholders.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from pltf.stubgen import fill, template
from pltf.stubgen.model import Command, Field, commands, enums
from pltf.stubgen.pltf_client.layout import all_names, docstring, field_doc, imports, one_or_many, wrap
from pltf.stubgen.pltf_client.names import (
    SCALAR_PY,
    GeneratorError,
    check_unique,
    is_bool,
    item_name,
    py_name,
    reply_class_name,
    scalar_type,
)

# Hand-written bases (in pltf/client/_reply_extras.py) that add convenience properties to a reply class.
REPLY_EXTRAS: dict[str, str] = {
    "CMD_GET_STATUS": "StatusExtras",
    "CMD_GET_POSITION": "PositionExtras",
    "CMD_GET_PLTF_PARAM": "ParamExtras",
}


def render_enums(banner: str) -> str:
    blocks = []
    for name, e in enums().items():
        doc = docstring("    ", [f"{e.description.rstrip('.')} (guide {e.section})."], [])
        blocks += ["", "", f"class {name}(enum.IntEnum):", *doc, ""]
        blocks += [f"    {member} = {value}" for member, value in e.values.items()]
    return fill(
        template("pltf_client", "_enums.py.tmpl"),
        BANNER=banner,
        ALL="\n".join(all_names(enums())),
        ENUMS="\n".join(blocks),
    )


# ---------------------------------------------------------------------------------------------- items
@dataclass(frozen=True)
class Item:
    """A repeated group's item class, shared by every group with the same ``item`` name."""

    name: str
    fields: tuple[Field, ...]
    used_in: tuple[str, ...]

    @property
    def plain(self) -> bool:
        """True when the codec's values need no conversion (no bool, enum, XML or array)."""
        return not any(is_bool(f) or f.enum or f.type == "XML" or f.repeat for f in self.fields)


def collect_items() -> dict[str, Item]:
    """Every group item class, in the order of first use (by telegram, request before reply)."""
    items: dict[str, Item] = {}
    for command in commands():
        for message in [m for m in (command.request, command.reply) if m is not None]:
            for f in message.fields:
                if not f.is_group:
                    continue
                name = item_name(f)
                shape = [(py_name(g, name), g.type, g.enum, g.repeat) for g in f.user_fields]
                where = f"{message.name}.{f.name}"
                if name in items:
                    old = items[name]
                    if [(py_name(g, name), g.type, g.enum, g.repeat) for g in old.fields] != shape:
                        raise GeneratorError(f"item {name} of {where} differs from its use in {old.used_in}")
                    items[name] = Item(name, old.fields, (*old.used_in, where))
                else:
                    check_unique([s[0] for s in shape], where)
                    items[name] = Item(name, f.user_fields, (where,))
    return items


# ---------------------------------------------------------------------------------------------- replies
def reply_expr(f: Field, var: str) -> str:
    """Expression converting the codec's value ``var`` of a reply field to its typed value."""
    if f.is_group:
        return f"tuple(map(_item_{item_name(f)}, {var}))"
    if is_bool(f):
        one = "bool({})"
    elif f.enum is not None:
        one = f.enum + "({})"
    elif f.type == "XML":
        one = "_document({})"
    else:
        one = SCALAR_PY[f.type] + "({})"
    if f.repeat:
        return f"tuple({one.format('_v')} for _v in {var})"
    return one.format(var)


def reply_type(f: Field) -> str:
    if f.is_group:
        return f"tuple[{item_name(f)}, ...]"
    scalar = scalar_type(f, "reply")
    return f"tuple[{scalar}, ...]" if f.repeat else scalar


def _item_class(item: Item) -> list[str]:
    attrs = [(py_name(f, item.name), field_doc(f)) for f in item.fields]
    if len(item.used_in) > 1:  # the descriptions name the first use only: say what the field is
        attrs = [
            (py_name(f, item.name), field_doc(replace(f, description=f.name.replace("_", " ").capitalize())))
            for f in item.fields
        ]
    lines = ["", "", f"class {item.name}(NamedTuple):"]
    lines += docstring("    ", [f"One item of the repeated group {', '.join(item.used_in)}."], [("Attributes", attrs)])
    lines += ["", *[f"    {py_name(f, item.name)}: {reply_type(f)}" for f in item.fields], "", ""]
    lines.append(f"def _item_{item.name}(raw: Any) -> {item.name}:")
    if item.plain:
        return [*lines, f"    return {item.name}._make(raw)"]
    args = [reply_expr(f, f"raw[{i}]") for i, f in enumerate(item.fields)]
    return lines + one_or_many(
        f"    return {item.name}({', '.join(args)})",
        [f"    return {item.name}(", *[f"        {a}," for a in args], "    )"],
    )


def _reply_class(command: Command) -> list[str]:
    assert command.reply is not None
    name, cls, fields = command.reply.name, reply_class_name(command.reply.name), command.reply.user_fields
    check_unique([py_name(f) for f in fields], name)
    base = f"({REPLY_EXTRAS[name]})" if name in REPLY_EXTRAS else ""
    lines = ["", "", "@dataclass(frozen=True)", f"class {cls}{base}:"]
    intro = f"The reply to {name} (id {command.reply.id}; guide {command.reply.section})."
    lines += docstring("    ", [intro], [("Attributes", [(py_name(f), field_doc(f)) for f in fields])])
    lines += ["", *[f"    {py_name(f)}: {reply_type(f)}" for f in fields], ""]
    lines += ["    @classmethod", f"    def from_telegram(cls, telegram: Telegram) -> {cls}:"]
    lines.append(f'        """Convert a decoded {name} reply telegram (InvalidArgument for any other telegram)."""')
    lines += [f'        _expect(telegram, "{name}")', "        return cls("]
    lines += [f"            {py_name(f)}={reply_expr(f, f'telegram[{i}]')}," for i, f in enumerate(fields)]
    return [*lines, "        )"]


def render_replies(banner: str, items: dict[str, Item]) -> str:
    answered = [c for c in commands() if c.reply is not None]
    enums_used = {
        f.enum
        for c in answered
        for top in (c.reply.fields if c.reply else ())
        for f in (*top.fields, top)
        if f.enum is not None and not is_bool(f)
    }
    classes = [reply_class_name(c.request.name) for c in answered]
    check_unique(classes + list(items) + list(enums()), "class names")
    extras = {REPLY_EXTRAS[c.request.name] for c in answered if c.request.name in REPLY_EXTRAS}
    blocks = [line for item in items.values() for line in _item_class(item)]
    blocks += [line for c in answered for line in _reply_class(c)]
    return fill(
        template("pltf_client", "_replies.py.tmpl"),
        BANNER=banner,
        IMPORTS="\n".join([*imports("pltf.client._enums", enums_used), *imports("pltf.client._reply_extras", extras)]),
        ALL="\n".join(all_names([*classes, *items, "Reply", "typed_reply"])),
        CLASSES="\n".join(blocks),
        UNION="\n".join(wrap(" | ".join(classes), "    ")),
        FACTORIES="\n".join(
            f'    "{c.request.name}": {cls}.from_telegram,' for c, cls in zip(answered, classes, strict=True)
        ),
    )
