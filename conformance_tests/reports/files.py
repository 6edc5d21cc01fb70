"""JUnit XML and JSON reports of a run (per case: requirement, verdict, messages and the wire log), and the
differential session's fields when one ran (``--differential``: a JSON section, a JUnit testsuite)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pltf.conformance_tests.catalogue import SECTIONS, Verdict
from pltf.conformance_tests.reports import first_line, write_atomic
from pltf.conformance_tests.runner import CaseResult, RunResult

if TYPE_CHECKING:
    from pltf.conformance_tests.reports.differential import Differential


def wire_lines(result: CaseResult) -> list[str]:
    return [f"{e.t:9.4f} {e.port:>3} {e.direction} {e.note:<28} {e.hex()}" for e in result.wire]


def case_dict(r: CaseResult) -> dict[str, Any]:
    c = r.case
    return {
        "id": c.id,
        "section": c.section,
        "group": c.group,
        "level": c.level.value,
        "tier": c.tier.name.lower(),
        "requirement": c.requirement,
        "errata": list(c.errata),
        "telegrams": list(c.telegrams),
        "flags": [f for f in ("moves_platform", "switches_outputs", "destructive", "abuse", "timing") if getattr(c, f)],
        "verdict": r.verdict.value,
        "message": r.message,
        "duration": round(r.duration, 4),
        "expected_failure": r.expected_failure,
        "attempts": [
            {"verdict": a.verdict.value, "message": a.message, "duration": round(a.duration, 4)} for a in r.attempts
        ],
        "deviations": [
            {"erratum": d.erratum, "reading": d.reading, "reading_text": d.reading_text, "detail": d.detail}
            for d in r.deviations
        ],
        "notes": list(r.notes),
        "wire": [
            {"t": round(e.t, 5), "port": e.port, "dir": e.direction, "note": e.note, "hex": e.hex()} for e in r.wire
        ],
    }


def run_dict(run: RunResult, differential: Differential | None = None) -> dict[str, Any]:
    cfg = run.config
    return {
        "target": f"{cfg.host}:{cfg.port}",
        "second_port": cfg.second_port,
        "profile": cfg.profile,
        "tier": cfg.tier.name.lower(),
        "time_scale": cfg.time_scale,
        "started": run.started,
        "duration": round(run.duration, 3),
        "exit_code": run.exit_code,
        "harness_error": run.harness_error,
        "counts": {v.value: n for v, n in run.counts().items()},
        "stale_baseline": run.stale,
        "notes": list(run.notes),
        "coverage": run.target.coverage.as_dict(),
        "differential": None if differential is None else differential.as_dict(),
        "cases": [case_dict(r) for r in run.results],
    }


def write_json(run: RunResult, path: str | Path, differential: Differential | None = None) -> None:
    write_atomic(path, json.dumps(run_dict(run, differential), indent=1) + "\n")


def _outcome(r: CaseResult) -> tuple[str, str] | None:
    """The JUnit element a result gets (tag, message) - or None for a pass. The testsuite's ``failures``,
    ``errors`` and ``skipped`` attributes count exactly these elements."""
    msg = first_line(r.message)
    if r.expected_failure:
        return "skipped", f"expected by the baseline: {r.verdict} {msg}"
    if r.blocking:  # FAIL, or INCONCLUSIVE of a MUST case: what fails the run
        return "failure", msg
    if r.verdict is Verdict.ERROR:
        return "error", msg
    if r.verdict in (Verdict.NA, Verdict.SKIPPED):
        return "skipped", f"{r.verdict}: {msg}"
    return None


def write_junit(run: RunResult, path: str | Path, differential: Differential | None = None) -> None:
    write_atomic(path, junit_text(run, differential))


def junit_text(run: RunResult, differential: Differential | None = None, title: str = "pltf conform") -> str:
    suites = ET.Element("testsuites", name=title, tests=str(len(run.results)), time=f"{run.duration:.3f}")
    by_section: dict[str, list[CaseResult]] = {}
    for r in run.results:
        by_section.setdefault(r.case.section, []).append(r)
    for section in sorted(by_section):
        results = by_section[section]
        outcomes = [_outcome(r) for r in results]
        tags = [o[0] for o in outcomes if o is not None]
        suite = ET.SubElement(
            suites,
            "testsuite",
            name=f"guide {section} {SECTIONS.get(section, '')}".strip(),
            tests=str(len(results)),
            failures=str(tags.count("failure")),
            errors=str(tags.count("error")),
            skipped=str(tags.count("skipped")),
            time=f"{sum(r.duration for r in results):.3f}",
        )
        for r, outcome in zip(results, outcomes, strict=True):
            tc = ET.SubElement(
                suite, "testcase", classname=f"guide.{section}.{r.case.group}", name=r.case.id, time=f"{r.duration:.3f}"
            )
            props = ET.SubElement(tc, "properties")
            for name, value in (
                ("level", r.case.level.value),
                ("verdict", r.verdict.value),
                ("requirement", r.case.requirement),
                ("errata", " ".join(r.case.errata)),
            ):
                ET.SubElement(props, "property", name=name, value=value)
            if outcome is not None:
                tag, msg = outcome
                attrs = {"message": msg} if tag == "skipped" else {"type": r.verdict.value, "message": msg}
                element = ET.SubElement(tc, tag, attrs)
                if tag != "skipped":
                    element.text = r.message
            out = [f"verdict: {r.verdict} ({r.case.level})", f"requirement: {r.case.requirement}"]
            out += [f"deviation: {d.describe()}" for d in r.deviations] + [f"note: {n}" for n in r.notes]
            out += ["wire log (t, port, dir, telegram, hex):", *wire_lines(r)]
            ET.SubElement(tc, "system-out").text = "\n".join(out)
    if differential is not None:
        _differential_suite(suites, differential)
    ET.indent(suites)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(suites, encoding="unicode") + "\n"


def _differential_suite(suites: ET.Element, differential: Differential) -> None:
    """One testcase per differing field (a failure: the differential fails the run), or one passing testcase."""
    groups = differential.groups()
    rows: list[tuple[str, str | None, str]] = [
        (f"{g.reply} {g.path}", g.describe(), g.documented.describe() if g.documented else "") for g in groups
    ]
    if differential.error:
        rows.append(("session", f"aborted: {differential.error}", ""))
    if not rows:
        rows = [("session", None, f"the target answered like the reference server ({differential.steps} steps)")]
    suite = ET.SubElement(
        suites,
        "testsuite",
        name="differential session against the reference server",
        tests=str(len(rows)),
        failures=str(sum(msg is not None for _, msg, _ in rows)),
        errors="0",
        skipped="0",
    )
    for name, msg, out in rows:
        tc = ET.SubElement(suite, "testcase", classname="differential", name=name)
        if msg is not None:
            ET.SubElement(tc, "failure", type="differs", message=msg).text = "\n".join(x for x in (msg, out) if x)
        if out:
            ET.SubElement(tc, "system-out").text = out
