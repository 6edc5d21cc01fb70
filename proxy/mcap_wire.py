"""The view's line of a telegram for the MCAP export's /pltf/wire, compiled once per telegram class (issue 35).

``pltf proxy`` shows a telegram as ``format_fields(telegram_to_json(t))`` (proxy/view.py): the whole telegram turned
into JSON's shape (a dict per group item, the enum names of every field) and then into words. For a status reply
(80 fields) that is ~100 us, as much as everything else the export does with it. Here each telegram class gets a
function, generated from its spec layout as the codec's are (spec/compiler.py), that writes the same words
straight from the tuple: ``name=repr(value)`` for a number, ``name=ENUM_NAME(value)`` for an enum, and the view's
own ``format_fields`` for the rest (groups, arrays, strings, payloads; a group cut to its first items by its
total count). Tested equal to the view's words for every telegram of the spec.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from typing import Any

from pltf.proxy.view import ITEMS_SHOWN, format_fields
from pltf.spec.model import FieldDef, load_enums
from pltf.spec.telegram import Telegram, plain, user_fields

Formatter = Callable[[Telegram, Mapping[str, int]], str]
NUMBERS = ("BYTE", "BOOL", "INT16", "INT", "DOUBLE")  # spec/compiler.py WIRE: shown as repr(value)


class Counted(list[Any]):
    """The first items of a group that says how many it has (the view prints ``[541: {..}, {..}, {..}, ...]``)."""

    def __init__(self, items: list[Any], total: int) -> None:
        super().__init__(items)
        self.total = total

    def __len__(self) -> int:
        return self.total


def _other(name: str, value: Any, counts: Mapping[str, int]) -> str:
    """The view's words for a field that is not a plain number: a group (cut to ITEMS_SHOWN items, with its total
    count), an array, a string, a payload."""
    if isinstance(value, tuple) and value and hasattr(value[0], "_fields"):
        total = counts.get(name, len(value))
        return format_fields({"fields": {name: Counted([plain(v) for v in value[:ITEMS_SHOWN]], total)}})
    return format_fields({"fields": {name: plain(value)}})


def _item_formatter(group: FieldDef) -> Callable[[Any], str] | None:
    """The view's ``{x=1 y=2}`` of one item of a group whose fields are all single numbers without enums (the
    view prints them as ``repr``), compiled; None for any other group."""
    if not all(f.type in NUMBERS and not f.repeat and f.enum is None and not f.is_group for f in group.fields):
        return None
    words = " ".join(f"{f.name}={{v[{i}]!r}}" for i, f in enumerate(group.fields))
    source = f"def item(v):\n    return f{'{{' + words + '}}'!r}\n"
    ns: dict[str, Any] = {}
    exec(compile(source, f"<mcap_wire:{group.name}>", "exec"), ns)
    return ns["item"]  # type: ignore[no-any-return]


def _group(name: str, value: tuple[Any, ...], counts: Mapping[str, int], item: Callable[[Any], str]) -> str:
    """The view's ``name=[541: {..}, {..}, {..}, ...]`` of a group of numbers (``_item_formatter``)."""
    total = counts.get(name, len(value))
    head = ", ".join(map(item, value[:ITEMS_SHOWN]))
    return f"{name}=[{total}: {head}{', ...' if total > ITEMS_SHOWN else ''}]"


@functools.cache
def formatter(cls: type[Telegram]) -> Formatter:
    """The function writing the view's words of a telegram of class ``cls`` (``counts``: the total of a group whose
    items the telegram holds only the first of)."""
    layout = cls.DEF.layout(cls.DIRECTION) if cls.DEF.layout_known else None
    fields = {f.name: f for f in user_fields(layout or ())}
    ns: dict[str, Any] = {"_other": _other, "_group": _group}
    words, names = [], []
    for i, name in enumerate(cls._fields):
        f, var = fields.get(name), f"v{i}"
        names.append(var)
        if f is not None and f.enum is not None and not f.repeat:
            ns[f"_E{i}"] = {v: k for k, v in load_enums()[f.enum].values.items()}
            words.append(f"{name}={{_E{i}.get({var}, '?')}}({{{var}}})")
        elif f is not None and f.type in NUMBERS and not f.repeat:
            words.append(f"{name}={{{var}!r}}")
        elif f is not None and f.type in NUMBERS:  # an array: the view's [1,2,3]
            words.append(f"{name}=[{{','.join(map(repr, {var}))}}]")
        elif f is not None and f.is_group and (item := _item_formatter(f)) is not None:
            ns[f"_G{i}"] = item
            words.append(f"{{_group({name!r}, {var}, counts, _G{i}) if {var} else {name + '=[]'!r}}}")
        elif f is not None and f.is_group:
            words.append(f"{{_other({name!r}, {var}, counts) if {var} else {name + '=[]'!r}}}")
        else:
            words.append(f"{{_other({name!r}, {var}, counts)}}")
    unpack = f"    {', '.join(names)}, = t\n" if names else ""
    source = f"def fmt(t, counts):\n{unpack}    return f{' '.join(words)!r}\n"
    exec(compile(source, f"<mcap_wire:{cls.NAME}.{cls.DIRECTION}>", "exec"), ns)
    return ns["fmt"]  # type: ignore[no-any-return]


def fields_text(t: Telegram, counts: Mapping[str, int] | None = None) -> str:
    """``format_fields(telegram_to_json(t))``, with ``counts`` the totals of groups ``t`` holds cut."""
    return formatter(type(t))(t, counts or {})
