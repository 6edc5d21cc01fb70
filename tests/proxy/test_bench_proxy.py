"""Smoke test of benchmarks/bench_proxy.py (no timing asserted: --quick figures mean nothing), and the capture it
times: what it says, telegram for telegram."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

from benchmarks.bench_proxy import C_FLOOR, PY_FLOOR, write_capture
from tests.proxy.tshark import run_tshark, telegrams

ROOT = Path(__file__).resolve().parents[2]


def test_proxy_benchmarks_run_and_write_their_rows(tmp_path: Path) -> None:
    out = tmp_path / "bench.json"
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks", "--quick", "--only", "proxy", "--json", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rows = json.loads(out.read_text())["rows"]
    keys = {(r["benchmark"], r["subject"], r["metric"]) for r in rows}
    position = {
        ("proxy.get_position", s, m)
        for s in ("direct", "pltf proxy (recording)")
        for m in ("latency_p50", "latency_p99", "round_trip_rate", "pipelined_rate")
    }
    assert position <= keys
    floors = (PY_FLOOR, C_FLOOR) if shutil.which("cc") else (PY_FLOOR,)  # without cc the C rows are left out
    floor_rows = [r for r in rows if r["subject"] in (PY_FLOOR, C_FLOOR)]
    assert {(r["subject"], r["metric"]) for r in floor_rows} == {
        (s, m) for s in floors for m in ("latency_p50", "round_trip_rate")
    }
    assert all(r["baseline_subject"] == "direct" and r["ratio"] > 0 for r in floor_rows)
    assert {("proxy.tshark", s, "seconds") for s in ("tshark + pltf.lua", "tshark (TCP only)")} <= keys
    assert all(r["value"] > 0 for r in rows)
    targets = {(r["metric"], r["target"]) for r in rows if r["target"]}
    assert targets == {
        ("latency_p50", "ratio <= 1.5"),
        ("round_trip_rate", "ratio <= 2"),
        ("pipelined_rate", "ratio <= 2"),
    }


def test_the_capture_holds_the_telegrams_it_says(tmp_path: Path) -> None:
    path = tmp_path / "c.pcapng"
    write_capture(path, 1000)
    shown = telegrams(run_tshark(path))
    assert len(shown) == 1000
    assert all("CMD_GET_POSITION" in s.label and "[" not in s.label for s in shown)
    assert sum("PlatformCtrl request:" in s.label for s in shown) == 500
