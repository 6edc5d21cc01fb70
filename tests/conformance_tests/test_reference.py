"""The standard tier against the reference server: every case passes (but those of NOT_ON_REFERENCE, N/A there),
with full coverage of what a client can drive; the reports."""

from __future__ import annotations

import json
import time
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path

import pytest

from pltf.conformance_tests.catalogue import Tier, Verdict, load_all, select
from pltf.conformance_tests.mutants.matrix import NOT_ON_REFERENCE
from pltf.conformance_tests.reports.files import write_json, write_junit
from pltf.conformance_tests.reports.html import write_html
from pltf.conformance_tests.runner import Runner, RunResult
from pltf.conformance_tests.target import Config
from pltf.harness import launch

# Time scale 5, not 10: the timing cases judge windows of simulated time that are wall milliseconds at a high time
# scale (the velocity watchdog 0.5 s, a program's delay of 1.5 s). Under `make test`'s load (pytest -n 2, a browser
# on the other worker) two clean-clone runs of 2026-11-26 each voided or failed one of them at 10 (move-vel-wheel:
# no resend within 40 ms, three times; runs-on-start: the program's value seen too late to judge its delay). At 5
# the standard run takes 53 s instead of 36 s on a quiet machine.
TIME_SCALE = 5.0
MAY_BE_NA = NOT_ON_REFERENCE  # N/A there (each with its reason), never FAIL; the list only shrinks
# an attempt the suite itself voids (it could not resend a velocity within the watchdog) is re-run; under `make
# test`'s load the default two re-runs were once all void (a clean-clone run at time scale 10, 2026-11-26)
RERUNS = 5


def standard_run(**kw: object) -> RunResult:
    with launch.reference(time_scale=TIME_SCALE) as server:
        config = Config(
            "127.0.0.1",
            server.ports[0],
            server.ports[1],
            time_scale=TIME_SCALE,
            simulator=True,
            allow_shutdown=True,
            reruns=RERUNS,
            **kw,
        )  # type: ignore[arg-type]
        return Runner(config, select(load_all().values(), tier=Tier.STANDARD)).run()


@pytest.fixture(scope="module")
def run() -> Iterator[RunResult]:
    t0 = time.monotonic()
    result = standard_run()
    result.wall = time.monotonic() - t0  # type: ignore[attr-defined]
    yield result


def test_the_standard_tier_passes_the_reference_server(run: RunResult) -> None:
    bad = [
        f"{r.case.id}: {r.verdict} {r.message}"
        for r in run.results
        if r.verdict not in (Verdict.PASS, Verdict.NA) or (r.verdict is Verdict.NA and r.case.id not in MAY_BE_NA)
    ]
    assert not bad, "\n".join(bad)
    stale = [r.case.id for r in run.results if r.case.id in MAY_BE_NA and r.verdict is Verdict.PASS]
    assert not stale, f"passes on the reference server now, remove it from NOT_ON_REFERENCE: {stale}"
    assert run.exit_code == 0
    assert len(run.results) >= 180


def test_coverage_of_everything_a_client_can_drive_is_complete(run: RunResult) -> None:
    below = run.target.coverage.below(100.0)
    assert not below, [(m.name, m.missing[:5]) for m in below]
    names = {m.name for m in run.target.coverage.metrics()}
    assert {"request telegrams sent", "request enum values", "state-chart cells", "XSD elements sent"} <= names


def test_reports(run: RunResult, tmp_path: Path) -> None:
    write_junit(run, tmp_path / "r.xml")
    write_json(run, tmp_path / "r.json")
    write_html(run, tmp_path / "r.html")
    root = ET.parse(tmp_path / "r.xml").getroot()
    cases = root.findall(".//testcase")
    assert len(cases) == len(run.results) and not root.findall(".//failure")
    assert {s.get("name", "")[:9] for s in root.findall("testsuite")} >= {"guide 6.2", "guide 6.3", "guide 4.3"}
    one = next(c for c in cases if c.get("name") == "6.3/CMD_SET_MODE/in-running")
    assert "ff01fe02" in (one.findtext("system-out") or "")
    data = json.loads((tmp_path / "r.json").read_text())
    assert data["exit_code"] == 0 and data["counts"]["PASS"] > 150
    c = next(c for c in data["cases"] if c["id"] == "6.2/framing/coalesced")
    assert c["requirement"] and c["wire"] and c["wire"][1]["dir"] == "tx"
    html = (tmp_path / "r.html").read_text()
    assert html.count('<details class="case"') == len(run.results)
    assert "<script src" not in html and "<link" not in html and "http://" not in html.replace("http://www.w3.org", "")


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_twenty_standard_runs_in_a_row_have_no_flake() -> None:
    first = None
    for i in range(20):
        result = standard_run()
        verdicts = {r.case.id: r.verdict for r in result.results}
        bad = [
            f"{r.case.id} {r.verdict} {r.message}"
            for r in result.results
            if r.verdict not in (Verdict.PASS, Verdict.NA)
        ]
        assert result.exit_code == 0, f"run {i}: " + "; ".join(bad)
        assert not any(len(r.attempts) > 1 for r in result.results), f"run {i} needed re-runs"
        first = first or verdicts
        assert verdicts == first
