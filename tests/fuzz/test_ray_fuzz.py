"""``pltf fuzz --jobs 2 --ray ADDRESS`` on a real local Ray cluster (tests/ray_cluster.py: a head and one more
node, both on 127.0.0.1): the campaign of tests/fuzz/test_parallel.py with its workers as actors, and a worker
killed mid-campaign."""

from __future__ import annotations

import json
import os
import signal
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from pltf.fuzz.options import Options
from tests.emulator_gate import emulator_or_skip
from tests.fuzz.test_parallel import kills_a_fresh_instance, parallel_campaign
from tests.ray_cluster import ray_cluster  # noqa: F401 (the fixture)

pytestmark = pytest.mark.ray


@pytest.mark.timeout(400)
def test_the_campaign_on_ray_finds_the_planted_bug_once(ray_cluster: Any, tmp_path: Path) -> None:  # noqa: F811
    """Two actors, one on each node, each with its own target: one finding, its reproducer kills a fresh
    instance, the workers shared their inputs."""
    out = tmp_path / "out"
    run, summary = parallel_campaign(out, ("--ray", ray_cluster.address))
    assert run.returncode == 1, run.stderr
    assert summary is not None and len(summary["findings"]) == 1, summary and summary["findings"]
    workers = summary["workers"]
    assert len({w["where"] for w in workers}) == 2, workers  # spread over both nodes
    assert any(w["used"] for w in workers), [(w["imported"], w["used"]) for w in workers]
    kills_a_fresh_instance(Path(summary["findings"][0]["dir"]))


@pytest.mark.timeout(400)
def test_a_worker_killed_mid_campaign_is_reported_and_the_campaign_goes_on(
    ray_cluster: Any,  # noqa: F811
    tmp_path: Path,
) -> None:
    from pltf.fuzz.ray_fuzz import RayCampaign

    binary = emulator_or_skip()
    opts = Options(
        host="127.0.0.1",
        port=0,
        second_port=0,
        duration=25.0,
        seed=1,
        out=tmp_path / "out",
        allow_motion=True,
        launch=f"{binary} --ports {{ports}} --data-dir {{tmpdir}}",
        deadline=3.0,
    )
    campaign = RayCampaign(opts, 2, ray_cluster.address)
    campaign.start()
    result: dict[str, Any] = {}
    driver = threading.Thread(target=lambda: result.update(code=campaign.run()), daemon=True)
    driver.start()
    view = campaign.view
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not all(w.figures.get("cases", 0) > 0 for w in view.workers):
        time.sleep(0.2)
    assert all(w.figures.get("cases", 0) > 0 for w in view.workers), [w.figures for w in view.workers]
    killed, before = campaign.pids[1], view.workers[0].figures["cases"]
    os.kill(killed, signal.SIGKILL)
    driver.join(timeout=300)
    assert not driver.is_alive()
    assert result["code"] == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert len(summary["lost_workers"]) == 1 and summary["lost_workers"][0].startswith("worker 1 (seed 2)")
    assert "started again" in summary["lost_workers"][0], summary["lost_workers"]
    w0, w1 = summary["workers"]
    assert w0["starts"] == 1 and w0["cases"] > before  # the other worker went on
    assert w1["starts"] == 2 and w1["status"] == "done" and w1["cases"] > 0  # and the lost one ran again
