"""Every case can fail: a mutant derived from the case's requirement makes it FAIL (NON-STRICT for a SHOULD, N/A
for a MAY). The default tier checks a sample across all groups; the slow tier checks every case."""

from __future__ import annotations

import pytest

from pltf.conformance_tests.catalogue import Case, Tier, load_all, select
from pltf.conformance_tests.mutants.matrix import NOT_ON_REFERENCE, candidates, find_killer
from pltf.conformance_tests.mutants.run import Bench

RUNNABLE = [c for c in select(load_all().values(), tier=Tier.STANDARD) if c.id not in NOT_ON_REFERENCE]
# one case of every group, and the cases whose killer is not a generic fault
SAMPLE_IDS = list(
    dict.fromkeys(
        [next(c.id for c in RUNNABLE if c.group == g) for g in dict.fromkeys(c.group for c in RUNNABLE)]
        + [
            "6.3/CMD_START/in-breaked",
            "6.3/CMD_SET_PLTF_PARAM/malformed-refused",
            "6.2/framing/half-close-partial",
            "6.3/CMD_MOVE_VEL/only-in-running",
        ]
    )
)


def test_every_runnable_case_has_candidates() -> None:
    assert len(RUNNABLE) >= 170
    for c in RUNNABLE:
        assert candidates(c), c.id


@pytest.mark.parametrize("case", [load_all()[i] for i in SAMPLE_IDS], ids=lambda c: c.id)
def test_sampled_cases_can_fail(case: Case) -> None:
    mutant, result = find_killer(Bench(10.0), case)
    assert mutant is not None, f"no mutant kills {case.id} (last verdict {result.verdict if result else None})"


@pytest.mark.slow
@pytest.mark.parametrize("case", RUNNABLE, ids=lambda c: c.id)
def test_every_case_can_fail(case: Case) -> None:
    mutant, result = find_killer(Bench(10.0), case)
    assert mutant is not None, f"no mutant kills {case.id} (last verdict {result.verdict if result else None})"
