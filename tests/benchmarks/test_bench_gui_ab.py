"""Smoke test of benchmarks/bench_gui_ab.py, the GUI benchmarks as an A/B of two builds of gui/web in one run (no
timing asserted: --quick figures mean nothing). The "old" build is a copy of gui/static whose index.html differs
by a comment, so the gateway's check that it serves each side's own page tells whether PLTF_GUI_STATIC reached it."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from benchmarks.bench_gui_ab import Builds

REPO = Path(__file__).resolve().parents[2]
STATIC = REPO / "gui" / "static"
CHROMIUM = Path("/usr/bin/chromium")


def _run(tmp_path: Path, only: str, **env: str) -> tuple[subprocess.CompletedProcess[str], list[dict[str, Any]]]:
    out = tmp_path / "bench.json"
    clean = {k: v for k, v in os.environ.items() if not k.startswith("PLTF_GUI_AB_")}
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks", "--quick", "--only", only, "--json", str(out)],
        cwd=REPO,
        env={**clean, **env},
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    rows = json.loads(out.read_text())["rows"] if out.is_file() else []
    return proc, rows


def _old_build(tmp_path: Path) -> Path:
    if not CHROMIUM.exists():
        pytest.fail(f"{CHROMIUM} is missing: `make chromium` installs Debian's chromium")
    if not (STATIC / "index.html").is_file():
        pytest.fail(f"the GUI is not built in {STATIC}: `make gui`")
    old = tmp_path / "static_old"
    shutil.copytree(STATIC, old)
    with (old / "index.html").open("a") as page:
        page.write("<!-- the old side of the smoke test -->\n")
    return old


def _check_ab(tmp_path: Path, names: tuple[str, ...]) -> None:
    old, runs = _old_build(tmp_path), tmp_path / "runs.json"
    only = ",".join(f"gui_ab.{n}" for n in names)
    proc, rows = _run(tmp_path, only, PLTF_GUI_AB_OLD=str(old), PLTF_GUI_AB_RUNS=str(runs))
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    for name in names:
        mine = [r for r in rows if r["benchmark"] == f"gui_ab.{name}"]
        assert mine, f"no rows of gui_ab.{name}"
        for r in mine:
            assert r["subject"].endswith(" (new build)") and r["baseline_subject"].endswith(" (old build)"), r
            assert r["value"] >= 0 and r["baseline_value"] >= 0, r
        timed = [r for r in mine if r["unit"] == "ms" and r["baseline_value"] > 0]
        assert timed and all(r["ratio"] == pytest.approx(r["value"] / r["baseline_value"]) for r in timed)
    recorded = json.loads(runs.read_text())
    for name in names:
        side = recorded[name]
        assert [r["side"] for r in side["runs"]] == ["old", "new"]  # one round, old first
        assert side["builds"]["old"]["dir"] == str(old.resolve())
        assert side["builds"]["new"]["dir"] == str(STATIC.resolve())  # PLTF_GUI_AB_NEW defaults to gui/static


def test_one_round_of_status_to_screen_serves_each_build_and_gives_the_new_figures_the_old_as_baseline(
    tmp_path: Path,
) -> None:
    _check_ab(tmp_path, ("status_latency",))
    rows = json.loads((tmp_path / "bench.json").read_text())["rows"]
    subjects = {r["subject"] for r in rows}
    assert "status change to screen, GET_STATUS at 20 Hz (new build)" in subjects
    assert "page main thread, watching: all tasks (new build)" in subjects


@pytest.mark.slow
def test_one_round_of_pan_zoom_and_edits_runs_both_builds(tmp_path: Path) -> None:
    _check_ab(tmp_path, ("pan_zoom", "edit"))
    subjects = {r["subject"] for r in json.loads((tmp_path / "bench.json").read_text())["rows"]}
    assert {"pan: layer worker + culling (new build)", "all edits, 50,000 lines, to screen (new build)"} <= subjects


def test_without_an_old_build_the_ab_says_so_and_gives_no_rows(tmp_path: Path) -> None:
    proc, rows = _run(tmp_path, "gui_ab")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert rows == []
    assert "skipped (PLTF_GUI_AB_OLD names no build of gui/web" in proc.stdout


def test_a_directory_without_a_build_is_refused_with_its_name_and_no_traceback(tmp_path: Path) -> None:
    proc, _ = _run(tmp_path, "gui_ab.edit", PLTF_GUI_AB_OLD=str(tmp_path))
    assert proc.returncode != 0
    assert f"PLTF_GUI_AB_OLD={tmp_path}: no index.html there" in proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr


def test_the_rounds_alternate_which_build_goes_first() -> None:
    builds = Builds({"old": Path("a"), "new": Path("b")}, rounds=3)
    assert builds.order() == ["old", "new", "new", "old", "old", "new"]
