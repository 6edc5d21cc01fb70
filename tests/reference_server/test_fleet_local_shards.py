"""``pltf serve --fleet FILE --processes K``: the fleet's shards as K local processes (reference_server/fleet/
local_shards.py). Each test runs the real command line in a child process and looks at what a user sees: the
CLI's lines, its exit status, and the platforms' replies over TCP. The head-on scenario and its comparison with
one process are those of the Ray shards (test_fleet_ray.py), here without Ray."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.reference_server.conftest import Client
from tests.reference_server.test_fleet import OP_NOT_INIT
from tests.reference_server.test_fleet_ray import (  # served: the fixture
    HEAD_ON,
    Served,
    _answers,
    as_in_one_process,
    head_on,
    served,  # noqa: F401
)

SHARD = r"shard (\d+) \(pid (\d+)\) serves platforms ([\w, ]+)$"


def _shards(run: Served, count: int) -> dict[str, tuple[int, int]]:
    """platform name -> (shard, pid) from the driver's lines."""
    out: dict[str, tuple[int, int]] = {}
    for k in range(count):
        m = run.wait_for(SHARD.replace(r"(\d+)", str(k), 1))
        for name in m.group(2).split(", "):
            out[name] = (k, int(m.group(1)))
    return out


def test_head_on_across_two_processes_as_in_one(tmp_path: Path, served: list[Served]) -> None:  # noqa: F811
    (tmp_path / "split").mkdir()
    split = Served(tmp_path / "split", HEAD_ON, None, "--processes", "2")
    served.append(split)
    ports = split.platforms(["alpha", "bravo"])
    shards = _shards(split, 2)
    assert shards["alpha"][0] == 0 and shards["bravo"][0] == 1, shards
    assert shards["alpha"][1] != shards["bravo"][1], "both platforms in one process"
    assert len([line for line in split.lines if "server started at port" in line]) == 4
    across = head_on(ports)
    assert split.stop() == 0

    alone = as_in_one_process(tmp_path, served, across)
    assert 150 < across["gap"] < 900, across
    assert abs(across["gap"] - alone["gap"]) < 120, (across["gap"], alone["gap"])


def test_a_killed_process_takes_only_its_platforms(tmp_path: Path, served: list[Served]) -> None:  # noqa: F811
    run = Served(tmp_path, "3", None, "--processes", "2")
    served.append(run)
    ports = run.platforms(["p01", "p02", "p03"])
    shards = _shards(run, 2)
    assert {n: s for n, (s, _) in shards.items()} == {"p01": 0, "p02": 1, "p03": 0}  # round-robin
    for name in ports:
        with Client(ports[name][0]) as c:
            assert c.status().operation_state == OP_NOT_INIT, name  # as booted
    os.kill(shards["p02"][1], signal.SIGKILL)
    run.wait_for(rf"shard 1 \(pid {shards['p02'][1]}\) lost \(exit status -9\): platforms p02 stopped serving")
    assert not _answers(ports["p02"][0])
    for name in ("p01", "p03"):  # the others keep serving
        assert _answers(ports[name][0]), f"{name} does not answer"
    assert run.proc.poll() is None, run.text()
    assert run.stop() == 0


@pytest.mark.parametrize(
    ("extra", "said"),
    [
        (["--processes", "0"], "--processes must be at least 1"),
        (["--processes", "2", "--ray", "auto"], "--ray and --processes: choose one"),
        (["--processes", "2", "--shared-map"], "--shared-map hands a map on in one process"),
        (["--processes", "2", "--ray-lag", "0"], "--ray-lag must be at least 1 (period)"),
        (["--processes", "1"], None),  # one process: the fleet as without the option
    ],
)
def test_what_a_split_refuses_is_one_line(tmp_path: Path, extra: list[str], said: str | None) -> None:
    fleet = HEAD_ON.replace("node: 1", "node: 0")
    (tmp_path / "fleet.yaml").write_text(fleet, encoding="utf-8")
    cmd = [sys.executable, "-m", "pltf.reference_server", "--fleet", str(tmp_path / "fleet.yaml"), "--ports", "0,0"]
    cmd += ["--data-dir", str(tmp_path / "d"), *extra]
    if said is None:
        run = Served(tmp_path, fleet, None, *extra)
        try:
            run.platforms(["alpha", "bravo"])
            assert not any("serves platforms" in line for line in run.lines), run.text()
        finally:
            assert run.stop() == 0
        return
    done = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines()[-1].split(": error: ", 1)[1].startswith(said), done.stderr
    assert "Traceback" not in done.stderr


def test_a_node_past_the_processes_is_one_line(tmp_path: Path) -> None:
    (tmp_path / "fleet.yaml").write_text(HEAD_ON.replace("node: 1", "node: 2"), encoding="utf-8")
    cmd = [sys.executable, "-m", "pltf.reference_server", "--fleet", str(tmp_path / "fleet.yaml"), "--ports", "0,0"]
    cmd += ["--data-dir", str(tmp_path / "d"), "--processes", "2"]
    done = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2, done.stderr
    last = done.stderr.strip().splitlines()[-1]
    assert re.fullmatch(r".*: error: platform 'bravo': node 2, but --processes gives 2 \(0\.\.1\)", last), last
    assert "Traceback" not in done.stderr
