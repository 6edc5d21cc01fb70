"""Stateful testing: the state machine passes the reference server, finds and shrinks a broken state chart, and
the replay script it leaves reproduces the failure against the broken server only."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from pltf.conformance_tests.stateful import run_stateful
from pltf.conformance_tests.target import Config
from pltf.harness import launch


def _replay(script: Path, port: int) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-I", str(script), "127.0.0.1", str(port)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )


@pytest.mark.slow  # a property tier: 180 examples and a shrink against live servers, 2-3 minutes (make test-slow);
# make test keeps tests/conformance_tests/test_cli.py's `pltf conform --stateful` against the reference server
def test_stateful_machine_passes_the_reference_and_shrinks_a_broken_chart(tmp_path: Path) -> None:
    with launch.reference(time_scale=10.0) as ref:
        assert (
            run_stateful(Config("127.0.0.1", ref.ports[0], time_scale=10.0), 30, tmp_path / "ok", derandomize=True) == 0
        )
        assert not (tmp_path / "ok").exists()
        with launch.reference(time_scale=10.0, mutant="set_mode_anywhere") as broken:
            assert (
                run_stateful(
                    Config("127.0.0.1", broken.ports[0], time_scale=10.0), 150, tmp_path / "bad", derandomize=True
                )
                == 1
            )
            script = tmp_path / "bad" / "replay_stateful.py"
            text = script.read_text()
            assert "import socket" in text and "conformance_tests" not in text.split('"""', 2)[2]
            on_broken = _replay(script, broken.ports[0])
        on_reference = _replay(script, ref.ports[0])
    assert on_broken.returncode == 1 and "EXPECTED" in on_broken.stdout
    last = on_broken.stdout.strip().splitlines()[-1]
    assert "CMD_SET_MODE" in last  # shrunk: the failing step is the mode change in a non-Ready state
    steps = [line for line in on_broken.stdout.splitlines() if line.startswith("step")]
    assert len(steps) <= 12, on_broken.stdout
    assert on_reference.returncode == 0, on_reference.stdout + on_reference.stderr
