"""Field-by-field comparison of a recorded reply with a replayed one (sans-IO).

Rules: telegrams are compared in the JSON shape ``pltf decode`` prints (what the session file keeps); the
volatile-field table (spec/volatile.yaml) decides per top-level field: ignored, compared within a tolerance (a
group's tolerance applies to its items' numbers), or exact. A group whose item counts differ is one difference
(its count), not one per item. Enum values are named, long strings cut, so that a difference reads as what a
person would check: ``motion_mode: recorded MODE_MOTION_VEL (3), replayed MODE_MOTION_NO (0)``.

A watcher's replies (``diff_watched``, erratum E-REP-022): on a connection that only reads, a reply in
``WATCHED`` (the platform's state and motion: guide 6.4 CMD_GET_STATUS, CMD_GET_POSITION, CMD_GET_DEBUG_DATA)
tells where the platform stood when the watcher asked, and what another connection made it do by then; a
replay keeps each connection's timing, not the instant of another's motion, so such a reply is compared by
kind (its telegram) and by the fields that report a fault (``WATCHED``'s list), never by its other values.
Every other reply of a watcher (a parameter, the map) is compared as any other.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from pltf.spec.jsonio import telegram_to_json
from pltf.spec.telegram import Telegram
from pltf.spec.volatile import Rule, rule, values_differ

CUT = 60


@dataclass(frozen=True)
class FieldDiff:
    path: str  # "motion_mode", "scan (count)", "parameters[3].value", "us_distance[2]"
    recorded: str
    replayed: str


def _show(value: Any, name: str | None = None) -> str:
    if name is not None:
        return f"{name} ({value})"
    if isinstance(value, str):
        text = repr(value)
        return text if len(text) <= CUT else f"{text[:CUT]}... ({len(value)} characters)"
    return repr(value)


def _strings(a: str, b: str) -> tuple[str, str]:
    """Long strings that differ, shown around the first character where they do."""
    if len(a) <= CUT and len(b) <= CUT:
        return _show(a), _show(b)
    k = next((i for i, (x, y) in enumerate(zip(a, b, strict=False)) if x != y), min(len(a), len(b)))
    lo = max(0, k - 20)
    return (
        f"...{a[lo : k + 30]!r}... ({len(a)} characters, differs at {k})",
        f"...{b[lo : k + 30]!r}... ({len(b)} characters)",
    )


# A watcher's replies that depend on when it asked: the fields still compared (faults, not motion or time).
WATCHED: dict[str, tuple[str, ...]] = {
    "CMD_GET_STATUS": ("app_error", "emergency_state", "collision", "localization_lost"),
    "CMD_GET_POSITION": (),
    "CMD_GET_DEBUG_DATA": (),
}


def diff_watched(recorded: Telegram, replayed: Telegram) -> list[FieldDiff]:
    """``diff_telegrams`` for a connection that only reads: a ``WATCHED`` reply by its kind and fault fields."""
    only = WATCHED.get(recorded.NAME)
    return diff_telegrams(recorded, replayed, only)


def diff_telegrams(
    recorded: Telegram,
    replayed: Telegram,
    only: tuple[str, ...] | None = None,
    widen: Mapping[str, float] | None = None,
    exact: frozenset[str] = frozenset(),
) -> list[FieldDiff]:
    """The fields of two replies that differ beyond the volatile-field table (an empty list: the same reply);
    ``only``: just these fields (the telegram's kind always); ``widen``: wider tolerances for some fields (a
    replay wait's rates, erratum E-REP-023); ``exact``: fields compared exactly although the table ignores them
    (what a replay wait waited for, E-REP-024)."""
    if recorded.NAME != replayed.NAME:
        return [FieldDiff("(telegram)", recorded.NAME, replayed.NAME)]
    a, b = telegram_to_json(recorded), telegram_to_json(replayed)
    names = _Names(a.get("names", {}), b.get("names", {}))
    layout = recorded.DEF.layout(recorded.DIRECTION) if recorded.DEF.layout_known else None
    groups = {f.name for f in layout or () if f.is_group}
    out: list[FieldDiff] = []
    for field, va in a["fields"].items():
        vb = b["fields"][field]
        r = Rule() if field in exact else rule(recorded.NAME, field)
        if r.ignored or (only is not None and field not in only):
            continue
        if widen and field in widen:
            r = Rule(tolerance=max(r.tolerance or 0.0, widen[field]))
        if field in groups:
            out += _diff_group(field, va, vb, r.tolerance, names)
        elif isinstance(va, list):
            out += _diff_values(
                [(f"{field}[{i}]", f"{field}/{i}", x, y) for i, (x, y) in enumerate(zip(va, vb, strict=True))],
                r.tolerance,
                names,
            )
        elif isinstance(va, str) and isinstance(vb, str):
            if va != vb:
                out.append(FieldDiff(field, *_strings(va, vb)))
        else:
            out += _diff_values([(field, field, va, vb)], r.tolerance, names)
    return out


class _Names:
    """The enum names the JSON form gives beside values, by key, of the recorded and the replayed reply."""

    def __init__(self, recorded: dict[str, str], replayed: dict[str, str]) -> None:
        self.recorded, self.replayed = recorded, replayed


def _diff_values(pairs: list[tuple[str, str, Any, Any]], tolerance: float | None, names: _Names) -> list[FieldDiff]:
    """(shown name, names key, recorded value, replayed value) pairs that differ beyond ``tolerance``."""
    return [
        FieldDiff(shown, _show(x, names.recorded.get(key)), _show(y, names.replayed.get(key)))
        for shown, key, x, y in pairs
        if values_differ(x, y, tolerance)
    ]


def _diff_group(field: str, va: list[Any], vb: list[Any], tolerance: float | None, names: _Names) -> list[FieldDiff]:
    if len(va) != len(vb):
        return [FieldDiff(f"{field} (count)", str(len(va)), str(len(vb)))]
    pairs = [
        (f"{field}[{i}].{sub}", f"{field}/{i}/{sub}", x, ib[sub])
        for i, (ia, ib) in enumerate(zip(va, vb, strict=True))
        for sub, x in ia.items()
    ]
    return _diff_values(pairs, tolerance, names)
