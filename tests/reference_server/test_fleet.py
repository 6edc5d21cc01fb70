"""``pltf serve --fleet``: platforms that share one world (issue 30), over real TCP with the fake CAN boards.

``FleetThread`` runs the fleet's real asyncio shell (reference_server/fleet/network.py) in a thread of its own, each
platform on two ephemeral ports. What the tests look at is what a client sees: GET_STATUS (scan points, ultrasonic
distances, the collision flag, the state) and GET_POSITION.
"""

from __future__ import annotations

import asyncio
import math
import socket
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from pltf.reference_server import hardware_link
from pltf.reference_server.fleet import config
from pltf.reference_server.fleet.fleet import Fleet, FleetPlatform
from pltf.reference_server.fleet.network import FleetServer
from pltf.reference_server.fleet.network import serve as serve_fleet
from pltf.reference_server.platform import Platform
from pltf.reference_server.storage import Storage
from pltf.reference_server.tasks.local import factory as program_factory
from pltf.reference_server.world.model import factory as world_factory
from pltf.spec.codec import REQUESTS as R
from tests.reference_server.conftest import Client
from tests.reference_server.helpers import wait_for

FRONT, REAR, HALF_WIDTH = 225.0, -425.0, 270.0  # the default footprint (PltfLength 650, axis 100 mm behind)
US_FRONT = range(4)
US_RANGE = 3000  # USSensor01..04 face forward (angle 0)
OP_READY, OP_RUNNING, OP_NOT_INIT = 0, 1, 3
MODE_VEL = 3
HEAD_ON = """
platforms:
  - name: alpha
    pose: {x: 4000, y: 10000, angle: 0}
    ports: [0, 0]
  - name: bravo
    pose: {x: 8000, y: 10000, angle: 180}
    ports: [0, 0]
"""


class FleetThread:
    """The fleet's network shell with its own event loop in a daemon thread."""

    def __init__(
        self, data_dir: Path, spec: config.FleetSpec, time_scale: float = 5.0, *, hardware: bool = True, **fleet: Any
    ) -> None:
        platforms: list[Platform] = []
        for k, p in enumerate(spec.platforms):
            storage = Storage(data_dir / p.name)
            storage.seed_from_fixtures()
            platforms.append(
                FleetPlatform(
                    storage,
                    seed=k + 1,
                    motion=world_factory(k + 1),
                    program=program_factory,
                    hardware=hardware_link.factory() if hardware else None,
                )
            )
        self.fleet = Fleet(spec, platforms, **fleet)
        self.time_scale = time_scale
        self.server: FleetServer | None = None
        self.loop: asyncio.AbstractEventLoop | None = None
        self._ready = threading.Event()
        self._thread = threading.Thread(target=self._main, name="fleet", daemon=True)
        self.exit_code: int | None = None

    def _main(self) -> None:
        def ready(server: FleetServer) -> None:
            self.server, self.loop = server, asyncio.get_running_loop()
            self._ready.set()

        self.exit_code = asyncio.run(
            serve_fleet(self.fleet, "127.0.0.1", self.time_scale, ready=ready, handle_signals=False)
        )
        self._ready.set()

    def start(self) -> FleetThread:
        self._thread.start()
        assert self._ready.wait(20), "fleet did not start"
        return self

    def ports(self, name: str) -> list[int]:
        assert self.server is not None
        return self.server.servers[name].ports

    def call(self, func: Callable[..., Any], *args: Any) -> Any:
        assert self.loop is not None

        async def run() -> Any:
            return func(*args)

        return asyncio.run_coroutine_threadsafe(run(), self.loop).result(10)

    def stop(self) -> None:
        if self.loop is not None and self._thread.is_alive():
            self.loop.call_soon_threadsafe(self.server.stop)  # type: ignore[union-attr]
        self._thread.join(20)
        assert not self._thread.is_alive(), "fleet thread did not stop"
        self.fleet.close()


@pytest.fixture
def head_on(tmp_path: Path) -> Iterator[FleetThread]:
    srv = FleetThread(tmp_path / "data", config.parse(__import__("yaml").safe_load(HEAD_ON))).start()
    try:
        yield srv
    finally:
        srv.stop()


def wait(c: Client, pred: Callable[[Any], bool], what: str, timeout: float = 30.0, keep: Any = None) -> Any:
    deadline = time.monotonic() + timeout
    while True:
        if keep is not None:
            c.send(keep)
        st = c.status()
        if pred(st):
            return st
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.01)


def bring_up(c: Client) -> None:
    """Connect, init (the CAN boards' self test), ultrasonic on, velocity mode, Running."""
    c.send(R.CMD_CONNECT_TO_PLTF(), R.CMD_INIT_PLTF())
    wait(c, lambda s: s.operation_state == OP_READY, "Ready")
    c.send(R.CMD_START_ULTRASONIC(active_channels=0xFFFF), R.CMD_SET_MODE(mode=MODE_VEL), R.CMD_START())
    wait(c, lambda s: s.operation_state == OP_RUNNING and any(s.us_distance), "Running, ultrasonic measuring")


def ahead(st: Any, lo: float, hi: float) -> list[tuple[int, int]]:
    """The scan points (platform frame) straight ahead, within the body's width, between lo and hi mm."""
    return [(x, y) for x, y in st.scan if lo <= x <= hi and abs(y) <= HALF_WIDTH]


def front_echo(st: Any) -> int:
    """The nearest echo of the forward ultrasonic sensors (mm; 0: none within their 3 m, which they report as 3000)."""
    echoes = [st.us_distance[i] for i in US_FRONT if 0 < st.us_distance[i] < US_RANGE]
    return min(echoes) if echoes else 0


def test_two_platforms_head_on_see_and_block_each_other(head_on: FleetThread) -> None:
    with Client(head_on.ports("alpha")[0]) as a, Client(head_on.ports("bravo")[1]) as b:
        bring_up(a)
        bring_up(b)
        # at the start each sees the other 3,550 mm ahead (the corridor is empty to its far end without it)
        for c in (a, b):
            st = c.status()
            face = ahead(st, 3700.0, 3850.0)
            assert len(face) >= 10, f"no scan points on the other platform 3.55 m ahead: {ahead(st, 0, 40000)[:5]}"
            assert not ahead(st, 0.0, 3700.0)
            assert front_echo(st) == 0  # 3.3 m: beyond the ultrasonic range (3 m)
        go = R.CMD_MOVE_VEL(vel_trans=400, vel_rot=0)
        blocked = []
        for c in (a, b):  # both drive at each other until the collision check holds each back
            blocked.append(wait(c, lambda s: s.collision == 1, "collision (held back)", keep=go))
            other = b if c is a else a
            other.send(go)
        sa = wait(a, lambda s: s.collision == 1 and abs(s.vel_trans) < 5, "alpha stopped", keep=go)
        sb = wait(b, lambda s: s.collision == 1 and abs(s.vel_trans) < 5, "bravo stopped", keep=go)
        for st in (sa, sb):
            assert st.operation_state == OP_RUNNING  # a held-back platform stays Running; only the motion stops
            assert ahead(st, FRONT, FRONT + 700.0), "the other is not in the scan just ahead"
            assert 0 < front_echo(st) < 900, st.us_distance
        pa, pb = a.request(R.CMD_GET_POSITION()), b.request(R.CMD_GET_POSITION())
        gap = (pb.x - FRONT) - (pa.x + FRONT)  # bravo faces west: its front edge is at x - 225
        assert 150.0 < gap < 900.0, (pa.x, pb.x)
        assert abs(pa.y - 10000) < 50 and abs(pb.y - 10000) < 50


def test_without_the_collision_check_the_bodies_still_cannot_pass(head_on: FleetThread) -> None:
    with Client(head_on.ports("alpha")[0]) as a, Client(head_on.ports("bravo")[0]) as b:
        for c in (a, b):
            c.send(R.CMD_SET_PLTF_PARAM(key="CollCheckEnabled", value="false"))
            bring_up(c)
        go = R.CMD_MOVE_VEL(vel_trans=300, vel_rot=0)
        deadline = time.monotonic() + 40
        xs: list[tuple[int, int]] = []
        while time.monotonic() < deadline:
            a.send(go)
            b.send(go)
            pa, pb = a.request(R.CMD_GET_POSITION()), b.request(R.CMD_GET_POSITION())
            xs.append((pa.x, pb.x))
            assert pa.x + FRONT <= pb.x - FRONT + 40, f"alpha's front passed bravo's: {xs[-5:]}"
            if len(xs) > 20 and a.status().collision and b.status().collision and pb.x - pa.x < 2 * FRONT + 40:
                break
            time.sleep(0.01)
        else:
            pytest.fail(f"the bodies never met: {xs[-5:]}")
        assert math.isclose(pb.x - pa.x, 2 * FRONT, abs_tol=40), xs[-3:]  # front to front, touching


def test_each_platform_serves_its_own_ports(head_on: FleetThread) -> None:
    with Client(head_on.ports("alpha")[1]) as a, Client(head_on.ports("bravo")[0]) as b:
        pa, pb = a.request(R.CMD_GET_POSITION()), b.request(R.CMD_GET_POSITION())
        assert (pa.x, pa.y) == (4000, 10000) and (pb.x, pb.y) == (8000, 10000)
        assert math.isclose(pb.angle, math.pi, abs_tol=1e-6) or math.isclose(pb.angle, -math.pi, abs_tol=1e-6)
        a.send(R.CMD_CONNECT_TO_PLTF(), R.CMD_INIT_PLTF())
        wait(a, lambda s: s.operation_state == OP_READY, "alpha Ready")
        assert b.status().operation_state == OP_NOT_INIT  # bravo's state chart is its own


PILLAR = '<circle><center x="6000" y="10000"/><radius r="200"/></circle>'  # between alpha and bravo


@pytest.mark.parametrize("shared", [True, False], ids=["--shared-map", "maps of their own"])
def test_shared_map_reaches_every_platform(tmp_path: Path, shared: bool) -> None:
    spec = config.parse(__import__("yaml").safe_load(HEAD_ON))
    srv = FleetThread(tmp_path / "data", spec, hardware=False, shared_map=shared).start()
    try:
        with Client(srv.ports("alpha")[0]) as a, Client(srv.ports("bravo")[0]) as b:
            office = a.request(R.CMD_GET_MAP())
            xml = office.xml.replace('<layer index="1">', f'<layer index="1">{PILLAR}', 1)
            a.send(R.CMD_SET_MAP(name="hall.map", xml=xml))
            assert a.request(R.CMD_GET_MAP()).name == "hall.map"
            got = b.request(R.CMD_GET_MAP())
            assert (got.name == "hall.map") is shared and (PILLAR in got.xml) is shared
    finally:
        srv.stop()


def refused(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=5).close()
    except ConnectionRefusedError:
        return True
    return False


def test_cmd_exit_ends_one_platform_and_the_others_serve_on(tmp_path: Path) -> None:
    """Erratum E-FLEET-001: CMD_EXIT on one platform's port closes its ports only; the last one ends the fleet."""
    spec = config.parse(__import__("yaml").safe_load(HEAD_ON))
    srv = FleetThread(tmp_path / "data", spec, hardware=False).start()
    try:
        (a0, a1), (b0, _) = srv.ports("alpha"), srv.ports("bravo")
        with Client(a0) as a:
            a.send(R.CMD_EXIT())
            assert a.closed_by_server()
        wait_for(lambda: refused(a1), timeout=10)  # the fleet closes alpha's listeners right after
        with Client(b0) as b:
            assert b.status().operation_state == OP_NOT_INIT  # bravo still serves
            b.send(R.CMD_EXIT())
            assert b.closed_by_server()
        srv._thread.join(20)
        assert srv.exit_code == 0  # the last platform gone: the fleet's shell returned
    finally:
        srv.stop()
