"""Scenario harness over the socket API: a real server whose motion model is the world, and a client that drives it.

Two kinds of server, both the real network shell (reference_server.network.Server) around a ``Platform`` built
like ``pltf serve --motion world`` (one seeded ``WorldModel``):
- ``WorldServer``: free running at an accelerated time scale (the conftest's ``ServerThread``); for scenarios
  whose outcome does not depend on when exactly a command lands (a target reached, a wall never crossed).
- ``SteppedServer``: the simulated clock stands still until the test advances it by whole control periods
  (``advance``); a command sent before an ``advance`` lands at a known simulated time. For what must hold to
  the control period (BREAK, emergency stop, watchdog) and for bit-identical runs of two servers.
Everything the tests observe comes over TCP (GET_STATUS, GET_POSITION); only the emergency stop button, which
has no telegram, is pressed on the platform (as tests/reference_server/test_network.py does).
"""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pltf.reference_server import hardware_link
from pltf.reference_server.network import CONTROL_PERIOD, Server, SimClock
from pltf.reference_server.platform import Platform
from pltf.reference_server.world import MapGeometry
from pltf.reference_server.world.geometry import F64, circles, clearance, segments, segments_clear
from pltf.reference_server.world.model import WorldModel, factory
from pltf.spec.codec import REQUESTS
from pltf.spec.documents import DocumentKind, validate_document
from pltf.spec.model import enum_classes
from tests.reference_server.conftest import Client, ServerThread

R: Any = REQUESTS
MotionMode: Any = enum_classes()["MotionMode"]
PlannerState: Any = enum_classes()["PlannerState"]
OperationState: Any = enum_classes()["OperationState"]
TIME_SCALE = 25.0
HALF_WIDTH = 270.0  # mm: the default footprint's half width (DistWheels 430 + 110, E-MOT-002)
OFFICE_MAP = Path(__file__).resolve().parents[3] / "fixtures" / "maps" / "office.map"
START = (2000.0, 10000.0, 0.0)  # fixtures/start_pose.dat: the west end of the office corridor, facing east


def world_platform(server: ServerThread, seed: int, hardware: bool = False) -> Platform:
    """The platform of ``pltf serve --motion world --seed <seed> [--no-hardware]`` on the server's data dir."""
    return Platform(
        server.platform.storage, seed=seed, motion=factory(seed), hardware=hardware_link.factory() if hardware else None
    )


class WorldServer(ServerThread):
    """The free-running server (accelerated time scale) with the world as its motion model."""

    def __init__(self, data_dir: Path, time_scale: float = TIME_SCALE, seed: int = 1, hardware: bool = False) -> None:
        super().__init__(data_dir, time_scale)
        self.platform = world_platform(self, seed, hardware)

    @property
    def world(self) -> WorldModel:
        assert isinstance(self.platform.motion, WorldModel)
        return self.platform.motion

    def press_emergency(self, pressed: bool) -> float:
        """The emergency stop button (no telegram); returns the simulated time it was pressed at."""

        def press() -> float:
            assert self.server is not None
            now = self.server.clock.now()
            self.platform.set_emergency(pressed, now)
            return now

        return float(self.call(press))


class _StepClock(SimClock):
    """Simulated time that moves only when the test says."""

    def __init__(self) -> None:  # no loop: nothing reads the wall clock
        self.ticks = 0

    def begin(self) -> float:
        return self.now()

    def now(self) -> float:
        return self.ticks * CONTROL_PERIOD

    def wall_at(self, sim: float) -> float:
        return math.inf


class _Stepped(Server):
    async def start(self) -> list[int]:
        ports = await super().start()
        self._clock = _StepClock()
        return ports

    async def _simulate(self) -> None:
        await asyncio.Event().wait()  # no control loop of its own: ``periods`` ticks the platform

    async def periods(self, n: int) -> None:
        clock = self.clock
        assert isinstance(clock, _StepClock)
        clock.ticks += n
        self.control.advance(clock.now())  # the control loop's ticks (reference_server/control_loop.py)


class SteppedServer(WorldServer):
    """The real network shell with a clock the test advances (``advance``) in control periods."""

    def _main(self) -> None:
        async def main() -> int:
            server = _Stepped(self.platform, "127.0.0.1", [0, 0])
            await server.start()
            self.server, self.loop = server, asyncio.get_running_loop()
            self._ready.set()
            return await server.run()

        self.exit_code = asyncio.run(main())
        self._ready.set()

    def advance(self, seconds: float) -> None:
        assert isinstance(self.server, _Stepped) and self.loop is not None
        n = round(seconds / CONTROL_PERIOD)
        asyncio.run_coroutine_threadsafe(self.server.periods(n), self.loop).result(120)

    @property
    def now(self) -> float:
        assert self.server is not None
        return float(self.call(self.server.clock.now))


# ---------------------------------------------------------------------------------------------- the client side


def running(c: Client, mode: int, *setup: Any) -> None:
    """Connect, init, ``setup`` telegrams (in Ready), the motion mode, start: the platform is Running."""
    c.send(R.CMD_CONNECT_TO_PLTF(), R.CMD_INIT_PLTF(), *setup, R.CMD_SET_MODE(mode=mode), R.CMD_START())
    s = c.status()
    assert (s.operation_state, s.motion_mode) == (OperationState.ST_OP_RUNNING, mode), s


def running_stepped(srv: SteppedServer, c: Client, mode: int) -> None:
    """``running`` on a stepped server with the CAN boards: the self test of CMD_INIT_PLTF takes a few periods."""
    command(c, R.CMD_CONNECT_TO_PLTF(), R.CMD_INIT_PLTF())
    srv.advance(0.6)
    c.send(R.CMD_SET_MODE(mode=mode), R.CMD_START())
    s = c.status()
    assert (s.operation_state, s.motion_mode) == (OperationState.ST_OP_RUNNING, mode), s


def command(c: Client, *telegrams: Any) -> None:
    """Send ``telegrams`` and wait until the server has handled them (a GET_POSITION behind them is answered):
    with a ``SteppedServer`` they then land before the next ``advance``."""
    c.send(*telegrams, R.CMD_GET_POSITION())
    assert c.receive().NAME == "CMD_GET_POSITION"


def param(name: str, value: object) -> Any:
    text = str(value).lower() if isinstance(value, bool) else str(value)
    return R.CMD_SET_PLTF_PARAM(key=name, value=text)


@dataclass
class Sample:
    t: float  # simulated s (status timestamp)
    x: float
    y: float
    angle: float  # rad
    vel_trans: int
    target_reached: int
    planner_state: int
    collision: int


def sample(c: Client) -> Sample:
    s = c.status()
    return Sample(
        s.timestamp / 1000.0,
        s.est_x,
        s.est_y,
        math.radians(s.est_angle / 1000.0),
        s.vel_trans,
        s.target_reached,
        s.planner_state,
        s.collision,
    )


def poll(c: Client, until: Callable[[Sample], bool], timeout: float, every: float = 0.004) -> list[Sample]:
    """GET_STATUS every ``every`` wall seconds until ``until`` holds (the trace, its last sample satisfying it)."""
    trace = [sample(c)]
    deadline = time.monotonic() + timeout
    while not until(trace[-1]):
        if time.monotonic() > deadline:
            last = trace[-1]
            raise AssertionError(f"not reached within {timeout} s: last {last}")
        time.sleep(every)
        trace.append(sample(c))
    return trace


def stepped_poll(
    srv: SteppedServer, c: Client, seconds: float, every: float = 0.1, until: Callable[[Sample], bool] | None = None
) -> list[Sample]:
    """Advance ``seconds`` of simulated time, sampling GET_STATUS every ``every`` s (stops early on ``until``)."""
    trace = [sample(c)]
    for _ in range(round(seconds / every)):
        srv.advance(every)
        trace.append(sample(c))
        if until is not None and until(trace[-1]):
            break
    return trace


def settled_at(goal: tuple[float, float, float], pos: float = 60.0, angle_deg: float = 3.0) -> Callable[[Sample], bool]:
    """The platform reports target reached within ``pos`` mm and ``angle_deg`` of ``goal`` (x, y mm, angle rad)."""

    def check(s: Sample) -> bool:
        return bool(s.target_reached) and near(s, goal, pos, angle_deg)

    return check


def near(s: Sample, goal: tuple[float, float, float], pos: float, angle_deg: float) -> bool:
    err = (s.angle - goal[2] + math.pi) % (2 * math.pi) - math.pi
    return math.hypot(s.x - goal[0], s.y - goal[1]) <= pos and abs(math.degrees(err)) <= angle_deg


def assert_clear(trace: list[Sample], walls: F64, circs: F64 | None = None, keep: float = HALF_WIDTH - 40.0) -> None:
    """The sampled (estimated) trajectory never crossed a wall and kept ``keep`` mm from every wall at each sample
    (the estimate may be a few cm off the truth: the default keeps half the body's width less 40 mm)."""
    pts = np.array([(s.x, s.y) for s in trace], dtype=np.float64)
    steps = np.column_stack([pts[:-1], pts[1:]])
    crossed = ~segments_clear(steps, walls, circles([]), 0.0)
    assert not crossed.any(), f"trajectory crosses a wall between {pts[:-1][crossed][:3]} and {pts[1:][crossed][:3]}"
    free = clearance(pts[:, 0], pts[:, 1], walls, circles([]) if circs is None else circs)
    assert free.min() >= keep, f"came within {free.min():.0f} mm of a wall at {pts[free.argmin()]}"


def travelled(trace: list[Sample]) -> float:
    pts = np.array([(s.x, s.y) for s in trace], dtype=np.float64)
    return float(np.hypot(*np.diff(pts, axis=0).T).sum()) if len(pts) > 1 else 0.0


# ---------------------------------------------------------------------------------------------- maps built in a test


def map_xml(walls: list[tuple[float, float, float, float]], prohibit: list[tuple[float, float]] | None = None) -> str:
    """A map document (guide 6.5) of ``walls``; ``prohibit``: one prohibited polygon."""

    def pt(x: float, y: float) -> str:
        return f'<point x="{x:.0f}" y="{y:.0f}"/>'

    body = [f"<line>{pt(x0, y0)}{pt(x1, y1)}</line>" for x0, y0, x1, y1 in walls]
    if prohibit:
        body.append("<prohibit>" + "".join(pt(x, y) for x, y in prohibit) + "</prohibit>")
    head = '<?xml version="1.0" encoding="UTF-8"?>\n<map Version="1.0"><layer index="0">'
    return head + "".join(body) + "</layer></map>"


def wall_array(walls: list[tuple[float, float, float, float]]) -> F64:
    return segments(walls)


def office() -> MapGeometry:
    """The fixture office floor the server boots with."""
    return MapGeometry.from_tree(validate_document(DocumentKind.MAP, OFFICE_MAP.read_bytes()))
