"""Smoke test of benchmarks/bench_server.py (no timing asserted: --quick figures mean nothing)."""

from __future__ import annotations

from pathlib import Path

from tests.benchrun import quick


def test_server_benchmark_runs_and_writes_its_rows(tmp_path: Path) -> None:
    rows = quick("server", tmp_path / "bench.json", timeout=120)["rows"]
    keys = {(r["subject"], r["metric"]) for r in rows}
    assert keys == {
        (s, m) for s in ("reference_server", "asyncio echo") for m in ("round_trip_rate", "latency_p50", "latency_p99")
    }
    assert all(r["value"] > 0 for r in rows)
    targets = {(r["metric"], r["target"]) for r in rows if r["subject"] == "reference_server" and r["target"]}
    assert targets == {("round_trip_rate", "ratio <= 2"), ("latency_p99", "value <= 2")}
