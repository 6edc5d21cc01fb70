"""Smoke test of ``python -m benchmarks --only fleet_split`` (a fleet split over local shard processes): it runs as a
user runs it and reports every subject beside its one-process baseline. No figure is asserted (--quick)."""

from __future__ import annotations

from pathlib import Path

from tests.benchrun import quick


def test_every_split_is_reported_beside_the_fleet_in_one_process(tmp_path: Path) -> None:
    report = quick("fleet_split", tmp_path / "out.json", timeout=300)
    rows = report["rows"]
    subjects = {r["subject"] for r in rows}
    assert subjects == {"fleet of 4 in 2 processes (lag 1)", "fleet of 4 in 2 processes (lag 5)"}, subjects
    for r in rows:
        assert r["value"] >= 0, r
        if r["metric"] in ("realtime_factor", "cpu_per_platform_second"):
            assert r["value"] > 0 and r["baseline_subject"] == "fleet of 4 in one process", r
        else:
            assert r["metric"] == "share_of_wall_waiting_for_peers" and r["value"] < 1, r
