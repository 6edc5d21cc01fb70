"""Telegrams <-> the JSON shape of ``pltf decode`` / ``pltf encode``.

``{"telegram": NAME, "id": N, "fields": {...}, "names": {...}}``: numbers stay numbers, groups are lists of
objects, fixed arrays are lists, OPAQUE payloads are hex strings. ``names`` maps the path of every enum
field (``mode``, ``graphics/0/type``) to its enum name, beside the number. ``fields_to_telegram`` accepts
exactly the ``fields`` object ``telegram_to_json`` produces, so encode(decode(x)) == x.
"""

from __future__ import annotations

from typing import Any

from pltf.spec import errors
from pltf.spec.codec import build, telegram_set
from pltf.spec.model import Direction, FieldDef, load_enums
from pltf.spec.telegram import Telegram, user_fields


def _enum_names(fields: tuple[FieldDef, ...], values: dict[str, Any], prefix: str, out: dict[str, str]) -> None:
    enums = load_enums()
    for f in user_fields(fields):
        value = values[f.name]
        if f.is_group:
            for i, item in enumerate(value):
                _enum_names(f.fields, item, f"{prefix}{f.name}/{i}/", out)
        elif f.enum is not None:
            names = {v: k for k, v in enums[f.enum].values.items()}
            if f.repeat:
                for i, v in enumerate(value):
                    out[f"{prefix}{f.name}/{i}"] = names.get(v, "?")
            else:
                out[f"{prefix}{f.name}"] = names.get(value, "?")


def telegram_to_json(t: Telegram) -> dict[str, Any]:
    fields = t.as_dict()
    out: dict[str, Any] = {"telegram": t.NAME, "id": t.ID, "fields": fields}
    layout = t.DEF.layout(t.DIRECTION) if t.DEF.layout_known else None
    if layout:
        names: dict[str, str] = {}
        _enum_names(layout, fields, "", names)
        if names:
            out["names"] = names
    return out


def _from_json(f: FieldDef, value: Any, where: str) -> Any:
    if f.is_group:
        if not isinstance(value, list):
            raise errors.FieldValueError(f"{where}: expected a list of objects")
        sub = user_fields(f.fields)
        items = []
        for i, item in enumerate(value):
            if not isinstance(item, dict) or set(item) != {g.name for g in sub}:
                raise errors.FieldValueError(f"{where}[{i}]: expected an object with {[g.name for g in sub]}")
            items.append(tuple(_from_json(g, item[g.name], f"{where}[{i}].{g.name}") for g in sub))
        return tuple(items)
    if f.repeat:
        if not isinstance(value, list):
            raise errors.FieldValueError(f"{where}: expected a list of {f.repeat} numbers")
        return tuple(value)
    return value


def fields_to_telegram(direction: Direction, name: str, fields: dict[str, Any]) -> Telegram:
    """Build a telegram from the ``fields`` object of ``telegram_to_json``."""
    cls = telegram_set(direction).by_name.get(name)
    if cls is None:
        raise errors.FieldValueError(f"no {direction} telegram named {name!r}")
    if not isinstance(fields, dict):
        raise errors.FieldValueError("fields must be a JSON object")
    tdef = cls.DEF
    if not tdef.layout_known or tdef.layout(direction) is None:
        payload = fields.get("payload", "")
        if set(fields) - {"payload"} or not isinstance(payload, str):
            raise errors.FieldValueError(f'{name}: layout unknown; give {{"payload": HEX}}')
        try:
            return build(direction, name, payload=bytes.fromhex(payload))
        except ValueError as exc:
            raise errors.FieldValueError(f"{name}.payload: {exc}") from None
    layout = user_fields(tdef.layout(direction) or ())
    values = {}
    for f in layout:
        if f.name in fields:
            values[f.name] = _from_json(f, fields[f.name], f"{name}.{f.name}")
    return build(direction, name, **{**values, **{k: v for k, v in fields.items() if k not in values}})
