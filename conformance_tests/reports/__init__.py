"""Reports of a conformance run: the live console view, JUnit XML, JSON and a self-contained HTML page.

All of them read the same ``RunResult``; ``summary_rows`` is the one table by guide chapter and section that
the console and the HTML page show.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from pltf.conformance_tests.catalogue import SECTIONS, Verdict

ORDER = [
    Verdict.PASS,
    Verdict.FAIL,
    Verdict.NON_STRICT,
    Verdict.NA,
    Verdict.INCONCLUSIVE,
    Verdict.ERROR,
    Verdict.SKIPPED,
]


@dataclass
class Row:
    section: str
    title: str
    counts: dict[Verdict, int] = field(default_factory=lambda: dict.fromkeys(ORDER, 0))

    @property
    def total(self) -> int:
        return sum(self.counts.values())


def summary_rows(results: Iterable[object]) -> list[Row]:
    """One row per guide section that has cases, in section order, then a total row."""
    rows: dict[str, Row] = {}
    total = Row("all", "all sections")
    for r in results:
        section = r.case.section  # type: ignore[attr-defined]
        row = rows.setdefault(section, Row(section, SECTIONS.get(section, "")))
        row.counts[r.verdict] += 1  # type: ignore[attr-defined]
        total.counts[r.verdict] += 1  # type: ignore[attr-defined]
    return [rows[k] for k in sorted(rows)] + [total]


def first_line(text: str) -> str:
    return text.splitlines()[0] if text else ""


def write_atomic(path: str | Path, text: str) -> None:
    """Write a report whole or not at all: a temporary file beside it, renamed over it."""
    target = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", dir=target.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
