"""Smoke test of benchmarks/bench_server.py (no timing asserted: --quick figures mean nothing)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from tests.reference_server.helpers import REPO


def test_server_benchmark_runs_and_writes_its_rows(tmp_path: Path) -> None:
    out = tmp_path / "bench.json"
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks", "--quick", "--only", "server", "--json", str(out)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rows = json.loads(out.read_text())["rows"]
    keys = {(r["subject"], r["metric"]) for r in rows}
    assert keys == {
        (s, m) for s in ("reference_server", "asyncio echo") for m in ("round_trip_rate", "latency_p50", "latency_p99")
    }
    assert all(r["value"] > 0 for r in rows)
    targets = {(r["metric"], r["target"]) for r in rows if r["subject"] == "reference_server" and r["target"]}
    assert targets == {("round_trip_rate", "ratio <= 2"), ("latency_p99", "value <= 2")}
