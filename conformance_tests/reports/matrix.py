"""The fleet's reports (``pltf conform --targets``): a matrix target x case, as Autobahn|Testsuite shows many
implementations in one report.

Rules:
- A row is a case; a cell is one target's verdict (its message on hover in the HTML). A row whose verdicts are not
  all the same is a difference between targets: highlighted, and named - each erratum the case or the differing
  cells' deviations cite, with its section from the errata register and, when zoo/emulator_differences.yaml
  gives it as a reason the Go emulator answers otherwise, that entry. A difference that cites no erratum is named
  "undocumented".
- Each target's differential session (``--differential``), grouped by field, follows the matrix.
- Files: one JSON (``write_json``: every target's whole single-run report, the matrix), one JUnit file per target
  (``write_junit_dir``: DIR/NAME.xml) and one self-contained HTML page (``write_html``); all written atomically.
"""

from __future__ import annotations

import functools
import json
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from html import escape
from pathlib import Path
from typing import Any

import yaml

from pltf.conformance_tests.catalogue import Verdict
from pltf.conformance_tests.fleet import FleetTarget, TargetRun, as_plain
from pltf.conformance_tests.reports import ORDER, first_line, write_atomic
from pltf.conformance_tests.reports.html import COLOURS, CSS


@dataclass(frozen=True)
class Cell:
    verdict: str
    message: str
    errata: tuple[str, ...]  # the deviations' errata in this cell


@dataclass(frozen=True)
class Row:
    case: str
    level: str
    errata: tuple[str, ...]  # the case's own
    cells: dict[str, Cell | None]  # by target name; None: the case did not run against that target

    @property
    def differs(self) -> bool:
        return len({c.verdict if c else None for c in self.cells.values()}) > 1

    def odd(self) -> list[str]:
        """The targets whose verdict is not the row's most common one (all of them in a tie)."""
        counts = Counter(c.verdict if c else None for c in self.cells.values())
        top = counts.most_common()
        if len(top) > 1 and top[0][1] == top[1][1]:
            return list(self.cells)
        return [n for n, c in self.cells.items() if (c.verdict if c else None) != top[0][0]]

    def named(self) -> list[str]:
        """What documents this difference: each erratum cited, with where it is written down."""
        if not self.differs:
            return []
        ids: list[str] = list(self.errata)
        for name in self.odd():
            cell = self.cells[name]
            ids += [e for e in (cell.errata if cell else ()) if e not in ids]
        return [describe_erratum(i) for i in ids] or ["undocumented: the case cites no erratum"]


@functools.cache
def _emulator_entries() -> dict[str, list[str]]:
    """Erratum id -> the zoo/emulator_differences.yaml entries that give it as a reason."""
    import pltf.zoo

    path = Path(pltf.zoo.__file__).resolve().parent / "emulator_differences.yaml"
    out: dict[str, list[str]] = {}
    for e in (yaml.safe_load(path.read_text(encoding="utf-8")) if path.is_file() else None) or []:
        for erratum in e.get("errata", ()):
            out.setdefault(erratum, []).append(f"{e['reply']} {e['field']}")
    return out


def describe_erratum(erratum: str) -> str:
    from pltf.spec.errata import load_errata

    entry = load_errata().get(erratum)
    text = f"{erratum} (errata register, {entry.topic}.yaml: guide {entry.section})" if entry else erratum
    emu = _emulator_entries().get(erratum)
    if emu:
        text += f"; the Go emulator's documented difference (zoo/emulator_differences.yaml: {'; '.join(emu)})"
    return text


def rows(runs: Sequence[TargetRun]) -> list[Row]:
    """One row per case any target ran, in the order first seen."""
    meta: dict[str, tuple[str, tuple[str, ...]]] = {}
    cells: dict[str, dict[str, Cell]] = {}
    for run in runs:
        for c in run.report.get("cases", []):
            meta.setdefault(c["id"], (c["level"], tuple(c["errata"])))
            errata = tuple(dict.fromkeys(d["erratum"] for d in c["deviations"]))
            cells.setdefault(c["id"], {})[run.name] = Cell(c["verdict"], c["message"], errata)
    return [Row(case, *meta[case], {r.name: cells[case].get(r.name) for r in runs}) for case in meta]


def counts(run: TargetRun) -> dict[str, int]:
    return dict(run.report.get("counts", {}))


# ---- JSON and JUnit
def fleet_dict(fleet: str, targets: Sequence[FleetTarget], runs: Sequence[TargetRun], code: int) -> dict[str, Any]:
    table = rows(runs)
    return {
        "fleet": fleet,
        "exit_code": code,
        "targets": [
            {"name": r.name, "address": r.address, "exit_code": r.exit_code, "error": r.error, "settings": as_plain(t)}
            | {"report": r.report}
            for t, r in zip(targets, runs, strict=True)
        ],
        "differences": sum(row.differs for row in table),
        "matrix": [
            {
                "case": row.case,
                "level": row.level,
                "verdicts": {n: (c.verdict if c else None) for n, c in row.cells.items()},
                "differs": row.differs,
                "odd": row.odd() if row.differs else [],
                "documented": row.named(),
            }
            for row in table
        ],
    }


def write_json(fleet: str, targets: Sequence[FleetTarget], runs: Sequence[TargetRun], code: int, path: str) -> None:
    write_atomic(path, json.dumps(fleet_dict(fleet, targets, runs, code), indent=1) + "\n")


def write_junit_dir(runs: Sequence[TargetRun], directory: str) -> list[Path]:
    """DIR/NAME.xml per target (a target that could not be run gets a report with its error as one failure)."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for r in runs:
        path = out / f"{r.name}.xml"
        write_atomic(path, r.junit or _junit_error(r))
        written.append(path)
    return written


def _junit_error(r: TargetRun) -> str:
    import xml.etree.ElementTree as ET

    suites = ET.Element("testsuites", name=f"pltf conform {r.name}", tests="1")
    suite = ET.SubElement(suites, "testsuite", name=f"target {r.address}", tests="1", failures="0", errors="1")
    tc = ET.SubElement(suite, "testcase", classname="fleet", name="run")
    ET.SubElement(tc, "error", type="harness", message=r.error).text = r.error
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(suites, encoding="unicode") + "\n"


# ---- HTML
_MATRIX_CSS = """
.m td.c{text-align:center;color:#fff;font-weight:600;font-size:12px}.m tr.d td:first-child{background:#fff3cd}
.m tr.d{outline:2px solid #ef6c00}.m td.doc{text-align:left;font-size:12px;max-width:40em}
"""
_MATRIX_JS = """
function only(d){document.querySelectorAll('table.m tr.r').forEach(function(t){
t.style.display=(!d||t.classList.contains('d'))?'':'none';});}
"""


def _cell(c: Cell | None) -> str:
    if c is None:
        return '<td class="c" style="background:#bbb">-</td>'
    colour = COLOURS.get(Verdict(c.verdict), "#000")
    return f'<td class="c" style="background:{colour}" title="{escape(first_line(c.message))}">{escape(c.verdict)}</td>'


def _summary(targets: Sequence[FleetTarget], runs: Sequence[TargetRun]) -> str:
    head = "<tr><th>target</th><th>address</th><th>profile</th><th>time scale</th>"
    head += "".join(f"<th>{escape(v.value)}</th>" for v in ORDER) + "<th>exit</th></tr>"
    body = "".join(
        f"<tr><td>{escape(r.name)}</td><td>{escape(r.address)}</td><td>{escape(t.profile)}</td>"
        f"<td>{t.time_scale:g}</td>"
        + "".join(f"<td>{counts(r).get(v.value) or ''}</td>" for v in ORDER)
        + f"<td>{r.exit_code}</td></tr>"
        + (f'<tr><td></td><td class="l" colspan="{len(ORDER) + 4}">{escape(r.error)}</td></tr>' if r.error else "")
        for t, r in zip(targets, runs, strict=True)
    )
    return f"<table>{head}{body}</table>"


def _differential(runs: Sequence[TargetRun]) -> str:
    parts = []
    for r in runs:
        d = r.report.get("differential")
        if d is None:
            continue
        items = "".join(
            f"<tr><td class='l'>{escape(f['reply'])}</td><td class='l'>{escape(f['field'])}</td><td class='l'>"
            + escape("; ".join(f"{v['reference']!r} / {v['target']!r}"[:120] for v in f["values"]))
            + f"</td><td>{f['count']}</td><td class='l'>"
            + escape(", ".join(f["documented"]["errata"]) + ": " + f["documented"]["why"] if f["documented"] else "")
            + "</td></tr>"
            for f in d["fields"]
        )
        what = d["error"] or (f"{len(d['fields'])} field(s) differ" if d["fields"] else "answers like the reference")
        parts.append(f"<h3>{escape(r.name)}: {escape(what)} ({d['steps']} steps)</h3>")
        if items:
            parts.append(
                "<table><tr><th>reply</th><th>field</th><th>reference / target</th><th>times</th>"
                f"<th>documented</th></tr>{items}</table>"
            )
    return "<h2>Differential sessions against the reference server</h2>" + "".join(parts) if parts else ""


def render(fleet: str, targets: Sequence[FleetTarget], runs: Sequence[TargetRun], code: int) -> str:
    table = rows(runs)
    names = [r.name for r in runs]
    head = "<tr><th>case</th><th>level</th>" + "".join(f"<th>{escape(n)}</th>" for n in names)
    head += "<th>difference named</th></tr>"
    body = "".join(
        f'<tr class="r{" d" if row.differs else ""}"><td><code>{escape(row.case)}</code></td><td>{row.level}</td>'
        + "".join(_cell(row.cells[n]) for n in names)
        + f'<td class="doc">{"<br>".join(escape(x) for x in row.named())}</td></tr>'
        for row in table
    )
    differing = sum(row.differs for row in table)
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>pltf conform - fleet {escape(fleet)}</title>
<style>{CSS}{_MATRIX_CSS}</style><script>{_MATRIX_JS}</script></head><body>
<h1>PlatformCtrl conformance report: {len(runs)} targets</h1>
<p>Fleet <b>{escape(fleet)}</b>; {len(table)} cases; <b>{differing}</b> case(s) where the targets' verdicts differ
(highlighted); exit status <b>{code}</b>.</p>
{_summary(targets, runs)}
<h2>Matrix: target x case</h2>
<p><button onclick="only(false)">all cases</button><button onclick="only(true)">only differences</button></p>
<table class="m">{head}{body}</table>
{_differential(runs)}
</body></html>
"""


def write_html(fleet: str, targets: Sequence[FleetTarget], runs: Sequence[TargetRun], code: int, path: str) -> None:
    write_atomic(path, render(fleet, targets, runs, code))
