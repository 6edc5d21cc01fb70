"""Mutation testing of the suite: every mutant of the catalogue is killed by the case that names the broken
requirement, and each of those cases passes the unbroken server through the same (faithful) proxy."""

from __future__ import annotations

import pytest

from pltf.conformance_tests.catalogue import Verdict, load_all
from pltf.conformance_tests.mutants.catalogue import MUTANTS, Mutant
from pltf.conformance_tests.mutants.run import KILLED, Bench


@pytest.fixture(scope="module")
def bench() -> Bench:
    return Bench(time_scale=10.0)


@pytest.mark.parametrize("mutant", MUTANTS, ids=lambda m: m.id)
def test_each_mutant_is_killed_by_its_case(bench: Bench, mutant: Mutant) -> None:
    (result,) = bench.run(mutant, [load_all()[mutant.killer]])
    assert result.verdict in KILLED, f"{mutant.id} ({mutant.breaks}) survived {mutant.killer}: {result.verdict}"
    assert result.message, "a killing verdict must say what was broken"
    if result.verdict is Verdict.NON_STRICT:  # only a SHOULD requirement (or an accepted reading) may be non-strict
        assert result.case.level != "MUST" or result.deviations


def test_every_killer_passes_the_reference_server_through_the_faithful_proxy(bench: Bench) -> None:
    killers = list(dict.fromkeys(m.killer for m in MUTANTS))
    results = bench.run(None, [load_all()[k] for k in killers])
    bad = [f"{r.case.id}: {r.verdict} {r.message}" for r in results if r.verdict is not Verdict.PASS]
    assert not bad, "\n".join(bad)
