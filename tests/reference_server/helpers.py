"""Helpers shared by the reference server tests (no server needed)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from pltf.spec.compiler import allowed_values, value_range
from pltf.spec.telegram import Telegram, user_fields

REPO = Path(__file__).resolve().parents[2]


def sample(cls: type[Telegram], **overrides: Any) -> Telegram:
    """A valid instance of a request class: the first allowed value of every field, empty strings and groups."""
    tdef = cls.DEF
    if not tdef.layout_known:
        return cls._make((b"",))  # type: ignore[attr-defined, no-any-return]
    values: dict[str, Any] = {}
    for f in user_fields(tdef.request or ()):
        if f.is_group:
            value: Any = ()
        elif f.type in ("STRING", "XML"):
            value = ""
        else:
            allowed = allowed_values(f)
            rng = value_range(f)
            value = min(allowed) if allowed else (rng[0] if rng else 0)
            value = 0.0 if f.type == "DOUBLE" else value
            if f.repeat:
                value = (value,) * f.repeat
        values[f.name] = value
    values.update(overrides)
    return cls(**values)


def wait_for(predicate: Any, timeout: float = 5.0, interval: float = 0.01) -> Any:
    deadline = time.monotonic() + timeout
    while True:
        result = predicate()
        if result:
            return result
        if time.monotonic() > deadline:
            raise AssertionError(f"condition not met within {timeout} s")
        time.sleep(interval)
