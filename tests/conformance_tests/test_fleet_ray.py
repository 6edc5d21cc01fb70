"""``pltf conform --targets FILE --ray ADDRESS`` (issue 34): the fleet of four with each target's suite as a Ray
task on a real local cluster (a head and one more node on 127.0.0.1, tests/ray_cluster.py) gives every target the
verdicts of a single run against it, as the threads do."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from pltf.harness import launch
from tests.conformance_tests.test_fleet import FEW, check_fleet_against_single_runs, four  # noqa: F401 (fixture)
from tests.ray_cluster import ray_cluster  # noqa: F401 (the fixture)


@pytest.mark.ray
@pytest.mark.timeout(900)
def test_the_fleet_on_ray_gives_the_single_run_verdicts(
    ray_cluster: Any,  # noqa: F811
    four: tuple[Path, dict[str, launch.Launched]],  # noqa: F811
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    fleet_file, started = four
    report = check_fleet_against_single_runs(fleet_file, started, FEW, tmp_path, "--ray", ray_cluster.address)
    assert "Ray at" in capsys.readouterr().out
    params = next(r for r in report["matrix"] if r["case"] == "5.9/parameters/errata-parameters")
    assert params["verdicts"]["emulator"] == "N/A" and "zoo/emulator_differences.yaml" in params["documented"][0]
