"""Hypothesis strategies derived from the spec: one strategy per telegram and direction.

Used by the property tests, the conformance suite's stateful tests and the in-process fuzzer. Values stay
inside each field's declared domain (enum values, BOOL 0/1, min/max, the wire type's range); strings are
Latin-1 text. ``hypothesis`` is a development dependency, so only tests and tools import this module.
"""

from __future__ import annotations

from hypothesis import strategies as st

from pltf.spec.codec import telegram_set
from pltf.spec.compiler import WIRE, allowed_values, value_range
from pltf.spec.model import Direction, FieldDef
from pltf.spec.telegram import Telegram, user_fields

_INT_BOUNDS = {"B": (0, 255), "h": (-(2**15), 2**15 - 1), "i": (-(2**31), 2**31 - 1)}
LATIN1 = st.characters(min_codepoint=0, max_codepoint=255)


def _scalar(f: FieldDef) -> st.SearchStrategy[object]:
    char = WIRE[f.type][0]
    if char == "d":
        return st.floats(allow_nan=False, width=64)
    allowed = allowed_values(f)
    if allowed is not None:
        return st.sampled_from(sorted(allowed))
    lo, hi = _INT_BOUNDS[char]
    rng = value_range(f)
    if rng is not None:
        lo, hi = max(lo, rng[0]), min(hi, rng[1])
    return st.integers(lo, hi)


def field_strategy(f: FieldDef, max_items: int = 8, max_text: int = 40) -> st.SearchStrategy[object]:
    if f.is_group:
        item = st.tuples(*(field_strategy(g, max_items, max_text) for g in user_fields(f.fields)))
        return st.lists(item, max_size=max_items).map(tuple)
    if f.type in ("STRING", "XML"):
        return st.text(LATIN1, max_size=max_text)
    scalar = _scalar(f)
    if f.repeat:
        return st.tuples(*([scalar] * f.repeat))
    return scalar


def telegram_strategy(cls: type[Telegram], max_items: int = 8) -> st.SearchStrategy[Telegram]:
    tdef = cls.DEF
    layout = tdef.layout(cls.DIRECTION) if tdef.layout_known else None
    if layout is None:
        return st.binary(max_size=64).map(lambda p: cls._make((p,)))  # type: ignore[attr-defined]
    fields = [field_strategy(f, max_items) for f in user_fields(layout)]
    return st.tuples(*fields).map(cls._make)  # type: ignore[attr-defined]


def any_telegram(direction: Direction, max_items: int = 8) -> st.SearchStrategy[Telegram]:
    return st.one_of([telegram_strategy(cls, max_items) for cls in telegram_set(direction)])
