"""The differential session in the reports: the diffs grouped by reply and field, each group with its count and,
when zoo/emulator_differences.yaml documents it, why (the errata behind it). JSON, JUnit and HTML carry
``Differential.as_dict`` / ``groups``; the console prints ``print_differential``.
"""

from __future__ import annotations

import functools
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml
from rich.console import Console
from rich.table import Table

if TYPE_CHECKING:
    from pltf.conformance_tests.differential import Diff

DOCUMENTED_NAME = "zoo/emulator_differences.yaml"


@dataclass(frozen=True)
class Documented:
    """A difference the project documents (zoo/emulator_differences.yaml): why, and the errata behind it."""

    source: str
    why: str
    errata: tuple[str, ...]

    def describe(self) -> str:
        return f"documented in {self.source} ({', '.join(self.errata)}): {self.why}"


@functools.cache
def _documented_table() -> dict[tuple[str, str, str, str], Documented]:
    import pltf.zoo

    path = Path(pltf.zoo.__file__).resolve().parent / "emulator_differences.yaml"
    entries = yaml.safe_load(path.read_text(encoding="utf-8")) if path.is_file() else []
    return {
        (e["reply"], e["field"], repr(e["reference"]), repr(e["emulator"])): Documented(
            DOCUMENTED_NAME, " ".join(str(e["why"]).split()), tuple(e.get("errata", ()))
        )
        for e in entries or ()
    }


def documented(reply: str, path: str, reference: Any, target: Any) -> Documented | None:
    """The documented difference this one is (same reply, field and values on both sides), or None."""
    return _documented_table().get((reply, path, repr(reference), repr(target)))


@dataclass(frozen=True)
class DiffGroup:
    """One field of one reply that differs, however often: each distinct (reference, target) pair with its count."""

    reply: str
    path: str
    pairs: tuple[tuple[Any, Any, int], ...]
    steps: tuple[int, ...]
    documented: Documented | None

    @property
    def count(self) -> int:
        return len(self.steps)

    def describe(self) -> str:
        values = "; ".join(
            f"reference {_short(a)}, target {_short(b)}" + (f" ({n}x)" if len(self.pairs) > 1 else "")
            for a, b, n in self.pairs
        )
        return f"{self.reply} {self.path}: {values} - {self.count} time(s)"

    def as_dict(self) -> dict[str, Any]:
        return {
            "reply": self.reply,
            "field": self.path,
            "count": self.count,
            "values": [{"reference": _plain(a), "target": _plain(b), "count": n} for a, b, n in self.pairs],
            "steps": list(self.steps),
            "documented": None
            if self.documented is None
            else {"source": self.documented.source, "why": self.documented.why, "errata": list(self.documented.errata)},
        }


def _short(value: Any) -> str:
    return repr(value)[:50]


def _plain(value: Any) -> Any:
    """A value as JSON can hold it (tuples of named tuples as lists, anything else as its repr)."""
    if isinstance(value, (bool, int, float, str)) or value is None:
        return value
    return repr(value)[:200]


def _reply_name(request: str) -> str:
    return request.split("(", maxsplit=1)[0]


@dataclass
class Differential:
    """The outcome of a differential session: the diffs, or why the session was aborted (``error``)."""

    steps: int
    diffs: list[Diff] = field(default_factory=list)
    error: str = ""
    unreachable: bool = False  # the error is that the target could not be reached (a usage problem: exit 2)

    @property
    def exit_code(self) -> int:
        return 2 if self.unreachable else 1 if self.diffs or self.error else 0

    def groups(self) -> list[DiffGroup]:
        """The diffs by reply and field, in the order first seen."""
        by: dict[tuple[str, str], list[Diff]] = {}
        for d in self.diffs:
            by.setdefault((_reply_name(d.request), d.path), []).append(d)
        out = []
        for (reply, path), diffs in by.items():
            pairs = Counter((repr(d.reference), repr(d.target)) for d in diffs)
            first = {(repr(d.reference), repr(d.target)): d for d in reversed(diffs)}
            values = tuple((first[k].reference, first[k].target, n) for k, n in pairs.items())
            docs = {documented(reply, path, a, b) for a, b, _ in values}
            out.append(
                DiffGroup(reply, path, values, tuple(d.step for d in diffs), docs.pop() if len(docs) == 1 else None)
            )
        return out

    def summary(self) -> str:
        if self.error:
            return f"differential run aborted: FAIL {self.error}"
        if not self.diffs:
            return f"differential: the target answered like the reference server ({self.steps} steps)"
        groups = self.groups()
        known = sum(g.documented is not None for g in groups)
        return (
            f"differential: {len(groups)} field(s) differ from the reference server ({len(self.diffs)} "
            f"difference(s) in {self.steps} steps; {known} field(s) documented)"
        )

    def as_dict(self) -> dict[str, Any]:
        return {
            "steps": self.steps,
            "differences": len(self.diffs),
            "error": self.error,
            "exit_code": self.exit_code,
            "fields": [g.as_dict() for g in self.groups()],
        }


def print_differential(result: Differential, console: Console) -> None:
    """The console's view: one line per differing field, with its count and, when documented, why."""
    if not result.diffs:
        style = "bold red" if result.error else ""
        console.print(f"[{style}]{result.summary()}[/]" if style else result.summary(), highlight=False)
        return
    table = Table(title=result.summary())
    for col in ("reply", "field", "reference / target", "times", "documented"):
        table.add_column(col)
    for g in result.groups()[:200]:
        values = "; ".join(f"{_short(a)} / {_short(b)}" for a, b, _ in g.pairs)
        docs = ", ".join(g.documented.errata) if g.documented else ""
        table.add_row(g.reply, g.path, values, str(g.count), docs)
    console.print(table)
