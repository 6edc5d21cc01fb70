"""examples/teleop.py driven through a pseudo-terminal, as from a keyboard: a held key (its repeats) drives the
platform without the velocity watchdog ever stopping it; on release the teleop stops the platform itself, within
one watchdog period; q leaves the platform standing in state Ready.

The key repeats are written into the pty every 30 ms (a fast keyboard's autorepeat); the teleop takes 200 ms
without a repeat as the release. A keyboard is a wall-clock device and so is the teleop's refresh, while the
watchdog counts simulated time: at any time scale above 1 a machine that stalls the teleop for a fraction of the
watchdog period lets the watchdog stop the platform, as a real platform would. This module's server therefore runs
in real time (the other examples' at 5 times); the whole module takes about ten seconds. Times on the platform's
side are read from the status time stamp (simulated ms).
"""

from __future__ import annotations

import math
import os
import subprocess
import time
from collections.abc import Iterator

import pytest

from pltf.client import OperationState, PlatformClient
from pltf.client.waits import stamp_after
from tests.clients.client_fakes import LiveServer
from tests.examples.runner import Example, python_example, target

TIME_SCALE = 1.0
SPEED = 300  # mm/s
RELEASE_MS = 200  # wall
REPEAT_S = 0.03  # wall seconds between two key repeats
HOLD_S = 1.5  # wall: three watchdog periods
EXPIRED = "velocity watchdog expired"


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveServer]:
    root = tmp_path_factory.mktemp("server")
    live = LiveServer(root / "data", root / "server.log", TIME_SCALE)
    try:
        yield live
    finally:
        live.close()


@pytest.fixture
def pty_teleop(server: LiveServer) -> Iterator[tuple[Example, int]]:
    master, slave = os.openpty()
    cmd = python_example(
        "teleop.py",
        "--target",
        target(server),
        "--speed",
        str(SPEED),
        "--release-ms",
        str(RELEASE_MS),
        "--time-scale",
        f"{TIME_SCALE:g}",
    )
    run = Example(cmd, stdin=slave)
    os.close(slave)
    try:
        yield run, master
    finally:
        run.close()
        os.close(master)


def hold(master: int, key: bytes, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        os.write(master, key)
        time.sleep(REPEAT_S)


def test_a_held_key_drives_and_its_release_stops_the_platform(
    pty_teleop: tuple[Example, int], server: LiveServer
) -> None:
    run, master = pty_teleop
    ready = run.expect("ready")
    watchdog_ms = float(ready.split("watchdog ")[1].split(" ms")[0])
    with PlatformClient("127.0.0.1", server.ports[1], timeout=10) as watch:
        start = watch.get_status()
        expired_before = server.log().count(EXPIRED)
        hold(master, b"w", HOLD_S)
        released_wall = time.monotonic()
        released = watch.get_status()
        assert run.expect("drive v=300 w=0", timeout=1) and released.vel_trans_mm_s > 0.8 * SPEED, released
        assert server.log().count(EXPIRED) == expired_before  # refreshed in time, never left to the watchdog
        run.expect("stop (released)", timeout=5)
        # the teleop said stop within one watchdog period of the release (simulated time; the pipe's delay included)
        assert (time.monotonic() - released_wall) * TIME_SCALE * 1000 <= watchdog_ms
        still = watch.wait_until(
            lambda s: watch.get_position().vel_trans_mm_s == 0.0, timeout=5, poll=0.005, what="standstill"
        )
        # standing within one watchdog period and the braking ramp (MaxTransAcc) after the release
        braking_ms = SPEED / float(watch.get_pltf_param("MaxTransAcc").typed_value) * 1000
        assert stamp_after(still.timestamp_ms, released.timestamp_ms) <= watchdog_ms + braking_ms
        driven = math.hypot(still.pose.x_mm - start.pose.x_mm, still.pose.y_mm - start.pose.y_mm)
        assert driven > 0.8 * SPEED * (HOLD_S * TIME_SCALE - 0.5), driven  # the hold at SPEED, less the ramps
        time.sleep(2 * watchdog_ms / 1000 / TIME_SCALE)
        assert watch.get_position().vel_trans_mm_s == 0.0  # and stays


def test_q_stops_the_platform_and_leaves_it_ready(pty_teleop: tuple[Example, int], server: LiveServer) -> None:
    run, master = pty_teleop
    run.expect("ready")
    hold(master, b"d", 0.3)  # turning on the spot
    os.write(master, b"q")
    assert run.finish() == 0, run.stderr()
    assert run.lines[-1] == "bye" and "stop (quit)" in run.lines
    with PlatformClient("127.0.0.1", server.ports[1], timeout=10) as watch:
        status = watch.get_status()
        assert status.operation_state is OperationState.ST_OP_READY
        # at rest once the braking ramp is over (real time: on a loaded machine the check can come first)
        deadline = time.monotonic() + 5.0
        while (rot := watch.get_position().vel_rot_rad_s) != 0.0 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert rot == 0.0


def test_a_pipe_drives_too_and_its_end_quits(server: LiveServer) -> None:
    cmd = python_example("teleop.py", "--target", target(server), "--time-scale", f"{TIME_SCALE:g}")
    with Example(cmd, stdin=subprocess.PIPE) as run:
        run.expect("ready")
        assert run.proc.stdin is not None
        run.proc.stdin.write("s")
        run.proc.stdin.flush()
        run.expect("drive v=-300 w=0")
        run.proc.stdin.close()  # end of input
        assert run.finish() == 0
    assert run.lines[-1] == "bye" and run.lines[-2].startswith("stop (")
