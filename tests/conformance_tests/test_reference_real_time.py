"""The suite against the reference server at time scale 1 - real time, as a real platform runs and as app developers
run the stand-in - where the default tier uses time scale 10 (slow tier: the standard tier takes minutes here).

Issue 23: at time scale 1 ``6.3/CMD_SHUTDOWN_PLTF/halts-motion`` was NON-STRICT (the case restarted the platform
while it still braked without its CAN bus, tests/reference_server/test_time_scale.py), at time scale 10 it passed.
"""

from __future__ import annotations

import pytest

from pltf.conformance_tests.catalogue import Tier, Verdict, load_all, select
from pltf.conformance_tests.mutants.matrix import NOT_ON_REFERENCE
from pltf.conformance_tests.runner import Runner, RunResult
from pltf.conformance_tests.target import Config
from pltf.harness import launch
from pltf.harness.launch import Launched

pytestmark = pytest.mark.slow


def run_against(server: Launched, keyword: str | None = None) -> RunResult:
    """The standard tier (or its cases matching ``keyword``) at time scale 1; the whole tier ends with CMD_EXIT."""
    config = Config(
        "127.0.0.1",
        server.ports[0],
        server.ports[1],
        time_scale=1.0,
        simulator=True,
        allow_shutdown=keyword is None,
        keyword=keyword,
    )
    return Runner(config, select(load_all().values(), tier=Tier.STANDARD, keyword=keyword)).run()


def not_passed(run: RunResult) -> list[str]:
    return [
        f"{r.case.id}: {r.verdict} {r.message}"
        for r in run.results
        if r.verdict is not Verdict.PASS and not (r.verdict is Verdict.NA and r.case.id in NOT_ON_REFERENCE)
    ]


@pytest.mark.timeout(600)
def test_the_platform_restarted_after_a_shutdown_does_not_move_three_times_in_a_row() -> None:
    with launch.reference(time_scale=1.0) as server:
        for i in range(3):
            run = run_against(server, "CMD_SHUTDOWN_PLTF/halts-motion")
            assert [r.case.id for r in run.results] == ["6.3/CMD_SHUTDOWN_PLTF/halts-motion"]
            assert not not_passed(run), f"run {i}: {not_passed(run)}"


@pytest.mark.timeout(1800)
def test_the_standard_tier_passes_the_reference_server_at_time_scale_1() -> None:
    with launch.reference(time_scale=1.0) as server:
        run = run_against(server)
    assert not not_passed(run), "\n".join(not_passed(run))
    assert run.exit_code == 0 and len(run.results) >= 180
