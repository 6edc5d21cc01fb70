"""Verdict rules (outcome.py, runner._resolve) and the known-failures baseline."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from pltf.conformance_tests.baseline import Baseline, BaselineError
from pltf.conformance_tests.catalogue import REGISTRY, Level, Verdict, load_all
from pltf.conformance_tests.outcome import Deviation, deviation_verdict, verdict_for_level, worst
from pltf.conformance_tests.runner import Attempt, _resolve

load_all()


def test_levels_map_to_verdicts() -> None:
    assert verdict_for_level(Level.MUST) is Verdict.FAIL
    assert verdict_for_level(Level.SHOULD) is Verdict.NON_STRICT
    assert verdict_for_level(Level.MAY) is Verdict.NA
    assert worst(Verdict.PASS, Verdict.NA, Verdict.FAIL, Verdict.NON_STRICT) is Verdict.FAIL


@pytest.mark.parametrize(
    ("erratum", "reading", "strict", "original"),
    [
        ("E-REP-009", 0, Verdict.FAIL, Verdict.NON_STRICT),  # MUST, alternative accepted by the original profile
        ("E-WIRE-001", 1, Verdict.FAIL, Verdict.FAIL),  # MUST, alternative rejected
        ("E-WIRE-007", 0, Verdict.NON_STRICT, Verdict.NON_STRICT),  # SHOULD
        ("E-REP-010", 0, Verdict.PASS, Verdict.NON_STRICT),  # MAY: informative under strict
        ("E-WIRE-006", None, Verdict.NON_STRICT, Verdict.NON_STRICT),  # a reading the register does not list
    ],
)
def test_deviations_by_profile(erratum: str, reading: int | None, strict: Verdict, original: Verdict) -> None:
    dev = Deviation(erratum, reading, "observed")
    assert deviation_verdict(dev, "strict") is strict
    assert deviation_verdict(dev, "original") is original
    assert erratum in dev.describe()


def _a(v: Verdict, msg: str = "") -> Attempt:
    return Attempt(v, msg, 0.1, [], [], [])


def test_attempts_that_disagree_are_inconclusive() -> None:
    verdict, msg = _resolve([_a(Verdict.FAIL, "late"), _a(Verdict.PASS)])
    assert verdict is Verdict.INCONCLUSIVE and "flaky" in msg and "late" in msg
    assert _resolve([_a(Verdict.INCONCLUSIVE), _a(Verdict.PASS)]) == (Verdict.PASS, "passed on attempt 2")
    assert _resolve([_a(Verdict.INCONCLUSIVE, "noise")] * 3) == (Verdict.INCONCLUSIVE, "noise")
    assert _resolve([_a(Verdict.FAIL, "x"), _a(Verdict.FAIL, "y")]) == (Verdict.FAIL, "y")


def _result(case_id: str, verdict: Verdict) -> SimpleNamespace:
    return SimpleNamespace(case=REGISTRY[case_id], verdict=verdict, message="m")


def test_baseline_expects_failures_and_reports_stale_entries() -> None:
    b = Baseline.parse("""
        # comment line
        6.2/framing/huge-length  NON-STRICT   # firmware waits
        6.3/CMD_SET_MODE/in-running           # any failure
        6.1/ports/reconnect
        9.9/no/such-case
    """)
    ran = {
        "6.2/framing/huge-length": _result("6.2/framing/huge-length", Verdict.NON_STRICT),
        "6.3/CMD_SET_MODE/in-running": _result("6.3/CMD_SET_MODE/in-running", Verdict.FAIL),
        "6.1/ports/reconnect": _result("6.1/ports/reconnect", Verdict.PASS),
    }
    assert b.expects(ran["6.2/framing/huge-length"]) and b.expects(ran["6.3/CMD_SET_MODE/in-running"])
    stale = b.stale(ran)
    assert any(s.startswith("6.1/ports/reconnect: expected") for s in stale)
    assert any(s.startswith("9.9/no/such-case: no such case") for s in stale)
    assert len(stale) == 2
    rendered = Baseline.render(ran.values())
    assert "6.3/CMD_SET_MODE/in-running  FAIL" in rendered and "reconnect" not in rendered


def test_baseline_refuses_unknown_verdicts_and_pass() -> None:
    with pytest.raises(BaselineError, match="unknown verdict"):
        Baseline.parse("6.1/ports/reconnect MAYBE")
    with pytest.raises(BaselineError, match="not PASS"):
        Baseline.parse("6.1/ports/reconnect PASS")
