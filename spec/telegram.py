"""Typed, immutable telegram objects.

A telegram is a tuple subclass built from the spec (one class per telegram and direction): fields are
attributes, values are plain ints, floats, strs and tuples, and equality includes the telegram type, so
``CMD_START() != CMD_STOP()`` although both are empty tuples.
"""

from __future__ import annotations

from collections import namedtuple
from typing import Any, ClassVar

from pltf.spec.model import Direction, FieldDef, TelegramDef


class Telegram(tuple):  # type: ignore[type-arg]
    """Base of every generated telegram class."""

    __slots__ = ()
    ID: ClassVar[int]
    NAME: ClassVar[str]
    DIRECTION: ClassVar[Direction]
    DEF: ClassVar[TelegramDef]
    _fields: ClassVar[tuple[str, ...]]

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other) and tuple.__eq__(self, other)

    def __ne__(self, other: object) -> bool:
        return not self.__eq__(other)

    def __hash__(self) -> int:
        return hash((self.NAME, self.DIRECTION, tuple(self)))

    def __repr__(self) -> str:
        body = ", ".join(f"{k}={v!r}" for k, v in zip(self._fields, self, strict=True))
        return f"{self.DIRECTION}.{self.NAME}({body})"

    def as_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (groups as lists of dicts, arrays as lists): the JSON shape."""
        return {name: plain(value) for name, value in zip(self._fields, self, strict=True)}

    def replace(self, **changes: Any) -> Telegram:
        return type(self)._make(changes.pop(n, v) for n, v in zip(self._fields, self, strict=True))  # type: ignore[attr-defined, no-any-return]


def plain(value: Any) -> Any:
    """A field's value as ``Telegram.as_dict`` gives it (groups as lists of dicts, arrays as lists, bytes as hex)."""
    if isinstance(value, tuple):
        fields = getattr(value, "_fields", None)
        if fields is not None:
            return {k: plain(v) for k, v in zip(fields, value, strict=True)}
        return [plain(v) for v in value]
    if isinstance(value, bytes):
        return value.hex()
    return value


def user_fields(fields: tuple[FieldDef, ...]) -> tuple[FieldDef, ...]:
    """The fields a user sets: everything but the constants the codec writes itself."""
    return tuple(f for f in fields if f.const is None)


def make_item_class(name: str, fields: tuple[FieldDef, ...]) -> type[tuple]:  # type: ignore[type-arg]
    """A group item (one of the guide's "n times" entries): a plain named tuple, equal to a plain tuple."""
    return namedtuple(name, [f.name for f in user_fields(fields)])


def make_telegram_class(tdef: TelegramDef, direction: Direction, field_names: list[str]) -> type[Telegram]:
    base = namedtuple(tdef.name, field_names)  # type: ignore[misc]
    ns = {
        "__slots__": (),
        "ID": tdef.id,
        "NAME": tdef.name,
        "DIRECTION": direction,
        "DEF": tdef,
        "__repr__": Telegram.__repr__,
        "__doc__": f"{tdef.name} ({direction}, id {tdef.id}): {tdef.summary} [guide {tdef.section}]",
        "__module__": f"spec.{direction}s",
    }
    return type(tdef.name, (base, Telegram), ns)
