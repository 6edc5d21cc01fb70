"""benchmarks/gui_ab_stats on made-up rounds: the pooled quantiles, the bootstrap CI over rounds and the paired
permutation p of an A/B of two GUI builds, and the command on a runs file as bench_gui_ab writes it."""

from __future__ import annotations

import json
import random
import subprocess
import sys
from pathlib import Path

from benchmarks.gui_ab_stats import compare, permutation_p

REPO = Path(__file__).resolve().parents[2]


def _rounds(seed: int, n: int = 8, scale: float = 1.0) -> list[list[float]]:
    rng = random.Random(seed)
    return [[scale * rng.uniform(18.0, 32.0) for _ in range(15)] for _ in range(n)]


def test_the_same_distribution_on_both_sides_is_not_called_a_change() -> None:
    p50, p95 = compare(_rounds(1), _rounds(2))
    for c in (p50, p95):
        assert c.low <= 1.0 <= c.high, c
        assert c.p > 0.05, c


def test_a_slower_new_side_is_found_and_measured() -> None:
    old, new = _rounds(1), _rounds(2, scale=1.5)
    p50, p95 = compare(old, new)
    assert 1.3 < p50.ratio < 1.7 and 1.3 < p95.ratio < 1.7
    assert p50.low > 1.0 and p95.low > 1.0
    # 8 paired rounds: 2^8 relabellings, only the measured one and its mirror are as far from 1
    assert p50.p == 2 / 256


def test_one_slow_round_is_not_significant() -> None:
    """What the rounds are for: an outlier spell of load in one round moves the pooled p95 but not the verdict."""
    old, new = _rounds(1), _rounds(2)
    new[3] = [x * 3 for x in new[3]]
    p95 = compare(old, new)[1]
    assert p95.ratio > 1.2
    assert p95.p > 0.05
    assert p95.low < 1.05  # the draws without that round: about as fast as the old side


def test_unpaired_rounds_are_refused() -> None:
    try:
        permutation_p(_rounds(1, 8), _rounds(2, 7), 0.95, random.Random(1))
    except ValueError as e:
        assert "paired rounds" in str(e)
    else:
        raise AssertionError("7 new rounds against 8 old ones were compared")


def _runs_file(tmp_path: Path) -> Path:
    runs = []
    for r in range(1, 5):
        for side, scale in (("old", 1.0), ("new", 2.0)):
            values = [scale * x for x in _rounds(r, 1)[0]]
            runs.append({"side": side, "round": r, "samples_ms": [{"subject": "move", "metric": "", "values": values}]})
    path = tmp_path / "runs.json"
    path.write_text(json.dumps({"edit": {"builds": {}, "runs": runs}}))
    return path


def test_the_command_prints_the_table_of_a_runs_file(tmp_path: Path) -> None:
    out = subprocess.run(
        [sys.executable, "-m", "benchmarks.gui_ab_stats", str(_runs_file(tmp_path))],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    rows = [line for line in out.splitlines() if line.startswith("| move")]
    assert [r.split("|")[2].strip() for r in rows] == ["p50", "p95"]
    assert all(r.split("|")[5].strip().startswith("2.") for r in rows), out  # new/old ratio about 2
    assert all(r.split("|")[7].strip() == "0.125" for r in rows), out  # 4 rounds: 2/16


def test_bad_input_is_said_in_one_line(tmp_path: Path) -> None:
    bad = tmp_path / "not.json"
    bad.write_text("{")
    cases = (([str(bad)], "not a runs file"), ([str(_runs_file(tmp_path)), "--benchmark", "pan"], "no benchmark"))
    for args, says in cases:
        cmd = [sys.executable, "-m", "benchmarks.gui_ab_stats", *args]
        proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, check=False)
        assert proc.returncode != 0 and says in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
