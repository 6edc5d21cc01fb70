"""A self-contained HTML report: one file, inline CSS and a few lines of script, no external resources.

Summary by guide section, the spec coverage, the differential session's fields when one ran, then one collapsible
block per case with its requirement, verdict, messages, deviations from the errata and the wire log of every byte
sent and received.
"""

from __future__ import annotations

import datetime
from html import escape
from pathlib import Path
from typing import TYPE_CHECKING

from pltf.conformance_tests.catalogue import Verdict
from pltf.conformance_tests.reports import ORDER, first_line, summary_rows, write_atomic
from pltf.conformance_tests.runner import CaseResult, RunResult

if TYPE_CHECKING:
    from pltf.conformance_tests.reports.differential import Differential

COLOURS = {
    Verdict.PASS: "#2e7d32",
    Verdict.FAIL: "#c62828",
    Verdict.NON_STRICT: "#ef6c00",
    Verdict.NA: "#00838f",
    Verdict.INCONCLUSIVE: "#6a1b9a",
    Verdict.ERROR: "#000",
    Verdict.SKIPPED: "#757575",
}

CSS = """
body{font:14px/1.4 system-ui,sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse;margin:.8em 0}td,th{border:1px solid #ccc;padding:.2em .5em;text-align:right}
td:first-child,th:first-child,td.l{text-align:left}
.v{display:inline-block;min-width:7.5em;color:#fff;border-radius:3px;padding:0 .4em;font-weight:600;
text-align:center}
details{border-bottom:1px solid #eee;padding:.2em 0}summary{cursor:pointer}
pre{background:#f6f6f6;padding:.5em;overflow-x:auto;font-size:12px}
.wire td{font:12px monospace;text-align:left;border:none;padding:0 .6em 0 0;vertical-align:top}
.wire td.hex{word-break:break-all}.tx{color:#1565c0}.rx{color:#2e7d32}.ev{color:#777}
#filters button{margin-right:.3em}
"""
_JS = """
function show(v){document.querySelectorAll('details.case').forEach(function(d){
d.style.display=(v==='all'||d.dataset.verdict===v)?'':'none';});}
"""


def _badge(v: Verdict) -> str:
    return f'<span class="v" style="background:{COLOURS[v]}">{escape(v.value)}</span>'


def _case(r: CaseResult) -> str:
    c = r.case
    parts = [
        f'<details class="case" data-verdict="{escape(r.verdict.value)}"><summary>{_badge(r.verdict)} '
        f"<code>{escape(c.id)}</code> <small>{c.level} &middot; {c.tier.name.lower()} &middot; "
        f"{r.duration:.2f} s</small> {escape(first_line(r.message))[:200]}</summary>",
        f"<p><b>Requirement</b> ({c.level}): {escape(c.requirement)}</p>",
    ]
    if c.errata:
        parts.append(f"<p><b>Errata</b>: {escape(', '.join(c.errata))}</p>")
    if r.message:
        parts.append(f"<pre>{escape(r.message)}</pre>")
    if r.expected_failure:
        parts.append("<p><i>Expected by the baseline.</i></p>")
    for d in r.deviations:
        parts.append(f"<p><b>Deviation</b> {escape(d.describe())}</p>")
    for n in r.notes:
        parts.append(f"<p><b>Note</b> {escape(n)}</p>")
    if len(r.attempts) > 1:
        parts.append("<p><b>Attempts</b>: " + ", ".join(escape(a.verdict.value) for a in r.attempts) + "</p>")
    if r.wire:
        rows = "".join(
            f'<tr class="{e.direction}"><td>{e.t:.4f}</td><td>{escape(e.port)}</td><td>{e.direction}</td>'
            f'<td>{escape(e.note)}</td><td class="hex">{escape(e.hex())}</td></tr>'
            for e in r.wire
        )
        parts.append(f'<table class="wire">{rows}</table>')
    parts.append("</details>")
    return "\n".join(parts)


def differential_section(differential: Differential | None) -> str:
    """The differential session: one row per differing field, with its count and why when documented."""
    if differential is None:
        return ""
    rows = "".join(
        f'<tr><td class="l">{escape(g.reply)}</td><td class="l">{escape(g.path)}</td><td class="l">'
        + escape("; ".join(f"{a!r} / {b!r}"[:120] for a, b, _ in g.pairs))
        + f'</td><td>{g.count}</td><td class="l">{escape(g.documented.describe()) if g.documented else ""}</td></tr>'
        for g in differential.groups()
    )
    table = (
        "<table><tr><th>reply</th><th>field</th><th>reference / target</th><th>times</th><th>documented</th></tr>"
        f"{rows}</table>"
        if rows
        else ""
    )
    return f"<h2>Differential session</h2><p>{escape(differential.summary())}</p>{table}"


def render(run: RunResult, differential: Differential | None = None) -> str:
    cfg = run.config
    when = datetime.datetime.fromtimestamp(run.started).isoformat(timespec="seconds")
    head = (
        "<tr><th>section</th><th></th>" + "".join(f"<th>{escape(v.value)}</th>" for v in ORDER) + "<th>cases</th></tr>"
    )
    body = "".join(
        f'<tr><td>{escape(row.section)}</td><td class="l">{escape(row.title)}</td>'
        + "".join(f"<td>{row.counts[v] or ''}</td>" for v in ORDER)
        + f"<td>{row.total}</td></tr>"
        for row in summary_rows(run.results)
    )
    cov = "".join(
        f"<tr><td>{escape(m.name)}{'' if m.enforced else ' (informative)'}</td><td>{m.covered}</td>"
        f'<td>{m.total}</td><td>{m.percent:.1f}</td><td class="l">{escape(", ".join(m.missing[:12]))}</td></tr>'
        for m in run.target.coverage.metrics()
    )
    filters = "".join(f"<button onclick=\"show('{v.value}')\">{escape(v.value)}</button>" for v in ORDER)
    stale = "".join(f"<li>{escape(s)}</li>" for s in run.stale)
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>pltf conform - {escape(cfg.host)}:{cfg.port}</title>
<style>{CSS}</style><script>{_JS}</script></head><body>
<h1>PlatformCtrl conformance report</h1>
<p>Target <b>{escape(cfg.host)}:{cfg.port}</b>{f" (second port {cfg.second_port})" if cfg.second_port else ""},
profile <b>{escape(cfg.profile)}</b>, tier <b>{cfg.tier.name.lower()}</b>, time scale {cfg.time_scale:g};
started {when}, {run.duration:.1f} s; exit status <b>{run.exit_code}</b>.</p>
{f"<p><b>Harness error:</b> {escape(run.harness_error)}</p>" if run.harness_error else ""}
{f"<h2>Stale baseline entries</h2><ul>{stale}</ul>" if stale else ""}
<h2>Results by guide section</h2><table>{head}{body}</table>
<h2>Spec coverage</h2><table><tr><th>metric</th><th>covered</th><th>total</th><th>%</th><th>missing</th></tr>
{cov}</table>
{differential_section(differential)}
<h2>Cases</h2><p id="filters"><button onclick="show('all')">all</button>{filters}</p>
{"".join(_case(r) for r in run.results)}
</body></html>
"""


def write_html(run: RunResult, path: str | Path, differential: Differential | None = None) -> None:
    write_atomic(path, render(run, differential))
