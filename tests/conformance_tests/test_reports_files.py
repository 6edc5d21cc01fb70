"""The JUnit report: each testsuite's failures/errors/skipped count exactly the elements written (issue 18: an
INCONCLUSIVE SHOULD case was counted as a failure but not written as one)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from pltf.conformance_tests.catalogue import REGISTRY, Level, Verdict, load_all
from pltf.conformance_tests.reports.files import write_junit
from pltf.conformance_tests.runner import CaseResult, RunResult
from pltf.conformance_tests.target import Config, Target

load_all()


def _one_of_each() -> list[CaseResult]:
    must = [c for c in REGISTRY.values() if c.section == "6.3" and c.level is Level.MUST]
    should = [c for c in REGISTRY.values() if c.section == "6.3" and c.level is Level.SHOULD]
    rows = [
        (must[0], Verdict.FAIL),
        (must[1], Verdict.INCONCLUSIVE),
        (should[0], Verdict.INCONCLUSIVE),
        (should[1], Verdict.NON_STRICT),
        (must[2], Verdict.ERROR),
        (must[3], Verdict.NA),
        (must[4], Verdict.SKIPPED),
        (must[5], Verdict.PASS),
        (must[6], Verdict.FAIL),
    ]
    results = [CaseResult(c, v, f"{v} because") for c, v in rows]
    results[-1].expected_failure = True  # listed in the baseline: written as skipped, not a failure
    return results


def test_junit_counts_are_the_elements_written(tmp_path: Path) -> None:
    config = Config("127.0.0.1", 1)
    run = RunResult(config, _one_of_each(), Target(config), 0.0, 1.0)
    write_junit(run, tmp_path / "r.xml")
    (suite,) = ET.parse(tmp_path / "r.xml").getroot()
    for tag, attr in (("failure", "failures"), ("error", "errors"), ("skipped", "skipped")):
        assert int(suite.get(attr, "-1")) == len(suite.findall(f"testcase/{tag}")), tag
    failed = {tc.get("name") for tc in suite.findall("testcase") if tc.find("failure") is not None}
    assert failed == {r.case.id for r in run.results if r.blocking}  # FAIL and INCONCLUSIVE MUST: exit status 1
    assert (suite.get("failures"), suite.get("errors"), suite.get("skipped")) == ("2", "1", "3")
