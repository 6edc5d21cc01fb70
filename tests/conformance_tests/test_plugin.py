"""The pytest plugin: the catalogue's cases as pytest items, -k by case id, verdicts as outcomes."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from pltf.harness import launch


def _pytest(tmp_path: Path, port: int, *args: str) -> subprocess.CompletedProcess[str]:
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    cmd = [
        sys.executable,
        "-m",
        "pytest",
        "-p",
        "pltf.conformance_tests.pytest_plugin",
        "-p",
        "no:cacheprovider",
        "--pltf-target",
        f"127.0.0.1:{port}",
        "--pltf-time-scale",
        "10",
        "--pltf-simulator",
        "-q",
        *args,
    ]
    return subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False)


def test_plugin_runs_selected_cases_and_maps_verdicts(reference: launch.Launched, tmp_path: Path) -> None:
    selection = "6.3/CMD_SET_MODE/in- or optional-modes or digout/sets"
    ok = _pytest(tmp_path, reference.ports[0], "-k", selection)
    assert ok.returncode == 0, ok.stdout + ok.stderr
    assert "7 passed" in ok.stdout and "skipped" not in ok.stdout  # the IO board is on the reference's CAN bus
    with launch.reference(time_scale=10.0, extra=["--no-hardware"]) as bare:
        na = _pytest(tmp_path, bare.ports[0], "-k", selection)
    assert na.returncode == 0, na.stdout + na.stderr
    assert "6 passed, 1 skipped" in na.stdout  # N/A (no IO board) is a skip
    with launch.reference(time_scale=10.0, mutant="set_mode_anywhere") as broken:
        bad = _pytest(tmp_path, broken.ports[0], "-k", "6.3/CMD_SET_MODE/in-running or 6.3/CMD_SET_MODE/in-ready")
    assert bad.returncode == 1
    assert "pltf-conformance::6.3/CMD_SET_MODE/in-running" in bad.stdout and "FAILED" in bad.stdout
    assert "requirement: guide 6.3 CMD_SET_MODE" in bad.stdout and "1 passed" in bad.stdout


def test_plugin_exits_2_when_the_target_is_unreachable(tmp_path: Path) -> None:
    import socket

    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    assert _pytest(tmp_path, port).returncode == 2
