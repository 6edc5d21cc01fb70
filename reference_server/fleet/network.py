"""The asyncio shell of a fleet: one event loop, one simulated clock, every member on its own ports.

Rules:
- One ``ControlLoop`` (reference_server/control_loop.py) ticks the whole ``Fleet`` at 50 Hz simulated time; every
  member's ``network.Server`` shares it (``Server(..., control=...)``), so a telegram on any port first runs the
  ticks due for the whole world, exactly as a single platform's server does for its one platform.
- Each member's ports are served by a ``network.Server`` of its own: the protocol on each port is that of a single
  platform (guide 6.1), and each logs "server started at port N" for its ports as ``pltf serve`` does, then
  "platform NAME at HOST:PORT[,PORT]" once (the line a user looks for).
- CMD_EXIT on a member's port ends that member only (erratum E-FLEET-001: it leaves the world, its ports close);
  the fleet exits with status 0 when the last member has gone, on SIGINT or SIGTERM.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable

from pltf.reference_server.control_loop import BURST, ControlLoop, Ticked
from pltf.reference_server.fleet.fleet import Fleet, Member
from pltf.reference_server.network import Server, serve_until_stopped

log = logging.getLogger("pltf.server")


class FleetServer:
    def __init__(self, fleet: Fleet, host: str, time_scale: float = 1.0, *, ticked: Ticked | None = None) -> None:
        self.fleet = fleet
        self.ticked: Ticked = fleet if ticked is None else ticked  # what the control loop ticks (a shard: more)
        self.host = host
        self.time_scale = time_scale
        self.servers: dict[str, Server] = {}
        self._stopped = asyncio.Event()
        self.control: ControlLoop | None = None

    async def start(self) -> None:
        loop = asyncio.get_running_loop()
        # a burst of ticks is the whole fleet's: as many platform periods between two looks at the sockets as a
        # single platform's server runs (control_loop.BURST), so a client of any platform waits no longer
        burst = max(1, BURST // max(1, len(self.fleet.members)))
        self.control = self.control_loop(loop.time(), burst)
        try:
            for m in self.fleet.members:
                srv = Server(m.platform, self.host, m.ports, self.time_scale, control=self.control)
                await srv.start()
                self.servers[m.name] = srv
                log.info("platform %s at %s", m.name, ",".join(f"{self.host}:{p}" for p in srv.ports))
        except OSError:
            for srv in self.servers.values():
                srv.close()
            raise

    def control_loop(self, wall: float, burst: int) -> ControlLoop:
        """The fleet's one clock: simulated time 0 at ``wall`` (a shard's: at the fleet's common origin)."""
        return ControlLoop(self.ticked, self.time_scale, wall, burst=burst)

    def boot(self, control: ControlLoop, wall: float) -> None:
        """Boot the fleet at the simulated time of ``wall`` (a shard's fleet booted at 0 before its ports opened)."""
        self.fleet.boot(control.begin(wall))
        control.begin(asyncio.get_running_loop().time())  # the boot took its time: the first tick one period on

    def stop(self) -> None:
        self._stopped.set()

    async def run(self) -> int:
        """Boot the fleet, tick it until every member exited or ``stop``, then close everything."""
        control, loop = self.control, asyncio.get_running_loop()
        assert control is not None, "FleetServer.start first"
        self.boot(control, loop.time())
        tasks = [asyncio.create_task(self._simulate(control))]
        tasks += [asyncio.create_task(self._watch(m)) for m in self.fleet.members]
        try:
            await self._stopped.wait()
        finally:
            for task in tasks:
                task.cancel()
            for srv in self.servers.values():
                srv.close()
            for task in tasks:
                with contextlib.suppress(asyncio.CancelledError):
                    await task
            log.info("fleet stopped")
        return 0

    async def _simulate(self, control: ControlLoop) -> None:
        loop = asyncio.get_running_loop()
        while True:
            control.now(loop.time())
            await asyncio.sleep(max(0.0, control.wall_at(control.next_tick) - loop.time()))

    async def _watch(self, member: Member) -> None:
        """A member's server stopped (CMD_EXIT): it leaves; the last one to leave ends the fleet."""
        srv = self.servers[member.name]
        await srv.wait_stopped()
        srv.close()
        self.fleet.retire(member)
        if not self.fleet.live:
            self.stop()


async def serve(
    fleet: Fleet,
    host: str,
    time_scale: float = 1.0,
    *,
    ready: Callable[[FleetServer], None] | None = None,
    handle_signals: bool = True,
) -> int:
    return await serve_until_stopped(FleetServer(fleet, host, time_scale), ready, handle_signals, "fleet")


def run(fleet: Fleet, host: str, time_scale: float = 1.0) -> int:
    """Blocking entry point for the command line."""
    return asyncio.run(serve(fleet, host, time_scale))
