"""Smoke test of benchmarks/bench_gui.py (no timing asserted: --quick figures mean nothing)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from benchmarks.bench_gui import big_map, zero_reply
from pltf.spec.codec import decode_frame

REPO = Path(__file__).resolve().parents[2]


def test_the_status_latency_benchmark_runs_and_writes_its_rows(tmp_path: Path) -> None:
    out = tmp_path / "bench.json"
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks", "--quick", "--only", "gui.status_latency", "--json", str(out)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rows = json.loads(out.read_text())["rows"]
    main = [r for r in rows if not r["subject"].startswith(("stage: ", "page main thread"))]
    assert {(r["metric"], r["target"]) for r in main} == {("p50", None), ("p95", "value <= 100")}
    assert all(r["value"] > 0 and r["baseline_value"] > 0 for r in main)
    # where the time went: the three stages add up to the whole (each sample's, so the medians roughly)
    busy = {r["subject"]: r["value"] for r in rows if r["subject"].startswith("page main thread")}
    # ms of each second: the page ran tasks while it watched; a quick run's 2 s may hold no layout at all (hog run
    # 15: layout 0.0 under load), so only the whole is asserted above 0
    assert len(busy) == 3 and all(0 <= v <= 1000 for v in busy.values()), busy
    assert busy["page main thread, watching: all tasks"] > 0, busy
    assert {r["subject"] for r in rows} - {r["subject"] for r in main} - set(busy) == {
        "stage: waiting for the poll",
        "stage: GET_STATUS round trip (page, gateway, server)",
        "stage: reply to screen",
    }


def test_the_benchmark_map_and_the_fake_platform_s_replies_are_what_they_claim() -> None:
    xml = big_map(1000)
    assert xml.count("<line>") == 1000
    reply = decode_frame(zero_reply("CMD_GET_MAP", xml=xml, name="m"), "reply")
    assert reply.xml == xml and reply.name == "m"
