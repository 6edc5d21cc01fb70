"""The volatile-field table (spec/volatile.yaml): reply fields two correct implementations may disagree on.

Rules: loaded once; ``rule(telegram, field)`` says whether a reply field is ignored (a glob of the table's
``ignore`` list matches it; a group's name covers its items) or compared within a numeric tolerance; every
other field is compared exactly. The conformance suite's differential mode and ``pltf replay`` both judge by it.
``rates(telegram)`` names the fields that are rates of change (velocities), whose value at the end of a replay's
wait depends on where in a poll's period the poll fell (erratum E-REP-023). ``outcomes(telegram)`` names the
ignored fields that say how a command ended (target_reached): a replay's wait that ends on their change compares
them exactly (erratum E-REP-024).
``check_table`` names entries that match no reply telegram or no field (the table must not rot).
"""

from __future__ import annotations

import fnmatch
import functools
import math
from dataclasses import dataclass
from typing import Any

import yaml

from pltf.spec.model import SPEC_DIR, FieldDef, load_telegrams

VOLATILE_PATH = SPEC_DIR / "volatile.yaml"


@dataclass(frozen=True)
class Rule:
    ignored: bool = False
    tolerance: float | None = None  # numbers within +- tolerance are equal


EXACT = Rule()


@functools.cache
def volatile() -> dict[str, dict[str, Any]]:
    """The table as written: telegram -> {"ignore": [globs], "tolerance": {field: amount}}."""
    return yaml.safe_load(VOLATILE_PATH.read_text(encoding="utf-8")) or {}


@functools.cache
def rule(telegram: str, field: str) -> Rule:
    entry = volatile().get(telegram, {})
    if any(fnmatch.fnmatchcase(field, pat) for pat in entry.get("ignore", ())):
        return Rule(ignored=True)
    tol = entry.get("tolerance", {}).get(field)
    return EXACT if tol is None else Rule(tolerance=float(tol))


def rates(telegram: str) -> tuple[str, ...]:
    """The reply's fields that are rates of change (the table's ``rates`` list)."""
    return tuple(volatile().get(telegram, {}).get("rates", ()))


def outcomes(telegram: str) -> tuple[str, ...]:
    """The reply's ignored fields that tell how a command ended (the table's ``outcomes`` list)."""
    return tuple(volatile().get(telegram, {}).get("outcomes", ()))


def values_differ(a: Any, b: Any, tolerance: float | None) -> bool:
    """Exact comparison, or within ``tolerance`` for two numbers (never for a NaN or an infinity)."""
    if tolerance is not None and _number(a) and _number(b):
        return not (math.isfinite(a) and math.isfinite(b) and abs(a - b) <= tolerance)
    return bool(a != b)


def _number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def check_table() -> list[str]:
    """Problems of the table: unknown reply telegrams, globs and tolerances that match no field."""
    replies = {t.name: t.reply for t in load_telegrams() if t.reply is not None}
    problems = []
    for name, entry in volatile().items():
        layout: tuple[FieldDef, ...] | None = replies.get(name)
        if layout is None:
            problems.append(f"{name}: no reply telegram of that name")
            continue
        fields = [f.name for f in layout]
        for pat in entry.get("ignore", ()):
            if not fnmatch.filter(fields, pat):
                problems.append(f"{name}: ignore {pat!r} matches no field")
        for field, amount in entry.get("tolerance", {}).items():
            if field not in fields:
                problems.append(f"{name}: tolerance for unknown field {field!r}")
            elif not (_number(amount) and amount >= 0):
                problems.append(f"{name}.{field}: tolerance {amount!r} is not a number >= 0")
        for kind in ("rates", "outcomes"):
            problems += [f"{name}: {kind} names unknown field {f!r}" for f in entry.get(kind, ()) if f not in fields]
    return problems
