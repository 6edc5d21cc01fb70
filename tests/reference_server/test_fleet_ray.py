"""``pltf serve --fleet FILE --ray ADDRESS``: the fleet's shards on a local Ray cluster of two (three) nodes.

Each test runs the real command line in a child process against the module's cluster (tests/ray_cluster.py, every
node on 127.0.0.1) and looks at what a user sees: the CLI's lines, and the platforms' replies over TCP
(GET_STATUS, GET_POSITION). The same head-on scenario runs in one process (``pltf serve --fleet FILE``) for the
comparison of what is deterministic over TCP (parameters, what each sees at the start, held back Running with the
other in its scan and echo); the exact mm and noise depend on the tick each telegram lands on, i.e. on wall-clock
timing in both runs. The reply-by-reply comparison at the same ticks is test_fleet_ray_shards.py's (sans-IO).
"""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from pltf.spec.codec import REQUESTS as R
from tests.ray_cluster import NODE_ARGS, ray_cluster, ray_or_skip  # noqa: F401  (the fixture)
from tests.reference_server.conftest import Client
from tests.reference_server.test_fleet import FRONT, OP_NOT_INIT, OP_RUNNING, ahead, bring_up, front_echo, wait

pytestmark = pytest.mark.ray

ROOT = Path(__file__).resolve().parents[2]
LINE = re.compile(r"platform (\S+) at 127\.0\.0\.1:(\d+),127\.0\.0\.1:(\d+)(?: on node (\d+) \((\w+)\))?$")
HEAD_ON = """
platforms:
  - name: alpha
    pose: {x: 4000, y: 10000, angle: 0}
    ports: [0, 0]
    node: 0
  - name: bravo
    pose: {x: 8000, y: 10000, angle: 180}
    ports: [0, 0]
    node: 1
"""
TIME_SCALE = "2"


class Served:
    """``pltf serve --fleet FILE [--ray ADDRESS]`` in a child process; its stderr read in a thread."""

    def __init__(self, tmp: Path, fleet: str, ray: str | None, *extra: str) -> None:
        if not fleet.isdigit():  # a count: --fleet N
            (tmp / "fleet.yaml").write_text(fleet, encoding="utf-8")
        where = fleet if fleet.isdigit() else str(tmp / "fleet.yaml")
        cmd = [sys.executable, "-m", "pltf.reference_server", "--fleet", where, "--ports", "0,0"]
        cmd += ["--data-dir", str(tmp / "data"), "--time-scale", TIME_SCALE, *extra]
        if ray is not None:
            cmd += ["--ray", ray]
        env = {**os.environ, "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}
        self.proc = subprocess.Popen(cmd, cwd=tmp, env=env, stderr=subprocess.PIPE, text=True)
        self.lines: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            self.lines.append(line.rstrip("\n"))

    def wait_for(self, pattern: str, timeout: float = 120.0) -> re.Match[str]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for line in list(self.lines):
                m = re.search(pattern, line)
                if m:
                    return m
            assert self.proc.poll() is None or self._reader.is_alive(), self.text()
            time.sleep(0.1)
        pytest.fail(f"no line {pattern!r} within {timeout:.0f} s:\n{self.text()}")

    def platforms(self, names: list[str]) -> dict[str, tuple[int, int, int, str]]:
        """name -> (port A, port B, node, node id) from the CLI's lines."""
        out = {}
        for name in names:
            m = self.wait_for(rf"platform {name} at ")
            full = LINE.search(m.string)
            assert full is not None, m.string
            _, a, b, node, node_id = full.groups()
            out[name] = (int(a), int(b), -1 if node is None else int(node), node_id or "")
        return out

    def text(self) -> str:
        return "\n".join(self.lines[-60:])

    def stop(self) -> int:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        self._reader.join(10)
        if self.proc.stderr is not None:
            self.proc.stderr.close()
        return self.proc.returncode


@pytest.fixture
def cluster(ray_cluster: Any) -> Any:  # noqa: F811
    """The module's two-node cluster (tests/ray_cluster.py)."""
    return ray_cluster


@pytest.fixture
def served(tmp_path: Path) -> Iterator[list[Served]]:
    runs: list[Served] = []
    try:
        yield runs
    finally:
        for r in runs:
            r.stop()


def head_on(ports: dict[str, tuple[int, int, int, str]]) -> dict[str, Any]:
    """Both brought up and driven at each other until each is held back: what the clients saw."""
    with Client(ports["alpha"][0]) as a, Client(ports["bravo"][1]) as b:
        seen: dict[str, Any] = {}
        for name, c in (("alpha", a), ("bravo", b)):
            seen[f"{name} params"] = [
                c.request(R.CMD_GET_PLTF_PARAM(key=k)).value for k in ("PltfLength", "MaxVelTrans")
            ]
            bring_up(c)
            st = c.status()
            seen[f"{name} other ahead"] = len(ahead(st, 3700.0, 3850.0)) >= 10 and not ahead(st, 0.0, 3700.0)
        go = R.CMD_MOVE_VEL(vel_trans=400, vel_rot=0)
        for c in (a, b):
            c.send(go)
        for name, c in (("alpha", a), ("bravo", b)):
            st = wait(c, lambda s: s.collision == 1 and abs(s.vel_trans) < 5, f"{name} held back", 90, keep=go)
            seen[f"{name} held"] = (st.operation_state, st.collision, bool(ahead(st, FRONT, FRONT + 700.0)))
            seen[f"{name} echo"] = front_echo(st)
        pa, pb = a.request(R.CMD_GET_POSITION()), b.request(R.CMD_GET_POSITION())
        seen["gap"] = (pb.x - FRONT) - (pa.x + FRONT)
        seen["lateral"] = (pa.y - 10000, pb.y - 10000)
        return seen


def as_in_one_process(tmp_path: Path, served: list[Served], across: dict[str, Any]) -> dict[str, Any]:
    """The head-on scenario in one process: the same replies as ``across`` (split) where they are deterministic -
    the parameters, each sees the other 3.55 m ahead at the start, each is held back Running with the other in its
    scan just ahead and in its ultrasonic echo (not compared: the echo's mm and the exact gap depend on the tick at
    which each client's telegrams land, i.e. on wall-clock timing in both runs). What one process saw."""
    (tmp_path / "one").mkdir()
    one = Served(tmp_path / "one", HEAD_ON, None)
    served.append(one)
    alone = head_on(one.platforms(["alpha", "bravo"]))
    for key in ("alpha params", "bravo params", "alpha other ahead", "bravo other ahead", "alpha held", "bravo held"):
        assert across[key] == alone[key], (key, across[key], alone[key])
    return alone


def test_head_on_across_two_nodes_as_in_one_process(cluster: Any, tmp_path: Path, served: list[Served]) -> None:
    (tmp_path / "ray").mkdir()
    ray = Served(tmp_path / "ray", HEAD_ON, cluster.address)
    served.append(ray)
    ports = ray.platforms(["alpha", "bravo"])
    assert ports["alpha"][2] == 0 and ports["bravo"][2] == 1
    assert ports["alpha"][3] != ports["bravo"][3], "both platforms on one node"
    assert len([line for line in ray.lines if "server started at port" in line]) == 4
    across = head_on(ports)
    ray.stop()

    alone = as_in_one_process(tmp_path, served, across)
    assert across["alpha held"] == (OP_RUNNING, 1, True)
    for seen in (across, alone):
        assert 150 < seen["gap"] < 900, seen
        assert all(abs(d) < 50 for d in seen["lateral"]), seen
        assert 0 < seen["alpha echo"] < 900 and 0 < seen["bravo echo"] < 900, seen
    assert abs(across["gap"] - alone["gap"]) < 120, (across["gap"], alone["gap"])


def _answers(port: int) -> bool:
    try:
        with Client(port) as c:
            return c.request(R.CMD_GET_POSITION()) is not None
    except OSError:
        return False


def _listeners() -> list[str]:
    out = subprocess.run(["ss", "-ltnpH"], capture_output=True, text=True, check=False).stdout
    return [line for line in out.splitlines() if re.search(r'"(raylet|gcs_server|ray::|python|pltf|plasma)', line)]


def test_killing_a_node_takes_only_its_platforms(cluster: Any, tmp_path: Path, served: list[Served]) -> None:
    third = cluster.add_node(**NODE_ARGS)
    cluster.wait_for_nodes()
    fleet = HEAD_ON.replace("node: 1", "node: 2") + (
        "  - name: charlie\n    pose: {x: 4000, y: 14000, angle: 0}\n    ports: [0, 0]\n    node: 0\n"
    )
    run = Served(tmp_path, fleet, cluster.address)
    served.append(run)
    ports = run.platforms(["alpha", "bravo", "charlie"])
    assert ports["bravo"][3] == third.node_id[: len(ports["bravo"][3])], (ports, third.node_id)
    for name in ports:
        assert _answers(ports[name][0]), f"{name} does not answer"
    # every listener of the cluster and of the fleet is on loopback
    for line in _listeners():
        local = line.split()[3]
        assert local.startswith(("127.0.0.1:", "[::1]:", "[::ffff:127.0.0.1]:")), line
    cluster.remove_node(third, allow_graceful=False)
    run.wait_for(r"shard 2 on node 2 lost \(\w+\): platforms bravo stopped serving", timeout=120)
    assert not _answers(ports["bravo"][0])
    for name in ("alpha", "charlie"):  # the others keep serving, and keep ticking
        with Client(ports[name][0]) as c:
            p0 = c.request(R.CMD_GET_POSITION())
            assert p0 is not None
    assert run.proc.poll() is None, run.text()
    assert run.stop() == 0


def test_a_count_of_platforms_goes_round_robin(cluster: Any, tmp_path: Path, served: list[Served]) -> None:
    run = Served(tmp_path, "2", cluster.address)
    served.append(run)
    ports = run.platforms(["p01", "p02"])
    assert (ports["p01"][2], ports["p02"][2]) == (0, 1)
    for name in ports:
        with Client(ports[name][0]) as c:
            st = c.status()
            assert st.operation_state == OP_NOT_INIT, f"{name}: {st.operation_state}"  # as booted
    assert run.stop() == 0


def test_without_a_cluster_one_line(tmp_path: Path) -> None:
    ray_or_skip()
    (tmp_path / "fleet.yaml").write_text(HEAD_ON, encoding="utf-8")
    env = {**os.environ, "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # nothing listens there once closed
    cmd = [sys.executable, "-m", "pltf.reference_server", "--fleet", str(tmp_path / "fleet.yaml")]
    cmd += ["--data-dir", str(tmp_path / "d"), "--ray", f"127.0.0.1:{port}"]
    done = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines()[-1].startswith("python -m pltf.reference_server: error: cannot connect")
    assert "Traceback" not in done.stderr
