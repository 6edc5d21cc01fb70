"""One shard of a fleet spread over processes: its platforms built and booted, its ports served, its snapshots
sent to and received from the other shards. The shells move the snapshots: Ray actor calls
(reference_server/fleet/ray_shards.py, ``--ray``) or pipes between local processes
(reference_server/fleet/local_shards.py, ``--processes``).

Rules (the lag and the snapshots: reference_server/fleet/shards.py, erratum E-FLEET-004):
- ``prepare`` builds and boots the shard's platforms at simulated time 0 as ``pltf serve --fleet`` builds them
  (data dirs, seeds, fake hardware: the options the driver resolved); ``connect`` hands it one sender per peer
  (a callable taking a batch of snapshots, fire and forget: a dead peer's send fails on its own and is ignored).
- ``go(epoch)`` serves the platforms' ports with the fleet's asyncio shell in a thread of its own; the one clock
  is simulated time 0 at the wall-clock ``epoch`` (``time.time()`` of the driver; the clocks of the nodes are
  assumed in step, as NTP keeps them: a skew only makes the faster shard wait within the lag).
- ``receive`` and ``drop`` may come on any thread (the shell's); ``wait`` blocks until the shard has ended (its
  platforms all exited, or ``stop``) and gives its exit status; at its end the shard publishes ``done`` so that
  the others stop waiting for it.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

from pltf.reference_server.control_loop import ControlLoop
from pltf.reference_server.fleet.bodies import Bodies
from pltf.reference_server.fleet.config import FleetSpec
from pltf.reference_server.fleet.fleet import Fleet
from pltf.reference_server.fleet.network import FleetServer
from pltf.reference_server.fleet.shards import STALL, Exchange, ShardPlan, ShardWorld, Snapshot
from pltf.reference_server.network import serve_until_stopped

log = logging.getLogger("pltf.server")

START_TIMEOUT = 120.0  # s for every shard to build, boot and open its ports
Sender = Callable[[list[Snapshot]], Any]


class ShardServer(FleetServer):
    """The fleet's asyncio shell for a shard: its clock starts at the fleet's epoch, its fleet is already booted."""

    def __init__(self, fleet: Fleet, world: ShardWorld, host: str, time_scale: float, epoch: float) -> None:
        super().__init__(fleet, host, time_scale, ticked=world)
        self.epoch = epoch

    def control_loop(self, wall: float, burst: int) -> ControlLoop:
        # simulated time 0 at the epoch: loop.time() and time.time() differ by a constant in this process
        return ControlLoop(self.ticked, self.time_scale, wall - (time.time() - self.epoch), burst=burst)

    def boot(self, control: ControlLoop, wall: float) -> None:
        """Booted at simulated time 0 already (``Shard.prepare``): the ticks from 0 on are due."""


class Shard:
    """One shard in the process that runs it (a Ray actor, or a local child process)."""

    def __init__(self) -> None:
        self.plan: ShardPlan | None = None
        self.fleet: Fleet | None = None
        self.world: ShardWorld | None = None
        self.exchange: Exchange | None = None
        self.senders: dict[int, Sender] = {}
        self.server: FleetServer | None = None
        self.loop: asyncio.AbstractEventLoop | None = None
        self.thread: threading.Thread | None = None
        self.exit_code: int | None = None
        self.error: str | None = None
        self._ready = threading.Event()

    def prepare(self, shard: ShardPlan, options: dict[str, Any], lag: int) -> int:
        """Build and boot this shard's platforms (simulated time 0); this process's id."""
        from pltf.reference_server.cli import LOG_DATE, LOG_FORMAT
        from pltf.reference_server.fleet.cli import build_platforms

        level = options.get("log_level", "INFO")
        logging.basicConfig(level=level, format=LOG_FORMAT, datefmt=LOG_DATE, stream=sys.stderr, force=True)
        self.plan = shard
        spec = FleetSpec(shard.platforms)
        platforms = build_platforms(spec, argparse.Namespace(**options))
        self.fleet = Fleet(spec, platforms, bodies=Bodies(shard.total), indices=shard.indices)
        self.fleet.boot(0.0)
        self.exchange = Exchange(shard.peers, time.time, lag, options.get("stall", STALL))
        self.world = ShardWorld(self.fleet, shard.shard, self.exchange, shard.owners, self._send, time.time)
        return os.getpid()

    def connect(self, senders: dict[int, Sender]) -> None:
        """One sender per peer shard (this shard's own is left out)."""
        self.senders = {k: send for k, send in senders.items() if self.plan is not None and k != self.plan.shard}

    def _send(self, snaps: list[Snapshot]) -> None:
        for send in self.senders.values():
            send(snaps)

    def receive(self, snaps: list[Snapshot]) -> None:
        if self.exchange is not None:
            self.exchange.put_all(snaps)

    def drop(self, shard: int) -> None:
        if self.exchange is not None:
            self.exchange.drop(shard)

    def go(self, epoch: float, host: str, time_scale: float) -> dict[str, list[int]]:
        """Serve the platforms' ports with simulated time 0 at ``epoch``; each platform's ports."""
        assert self.fleet is not None and self.world is not None, "prepare first"
        self.world.publish(0)
        server = ShardServer(self.fleet, self.world, host, time_scale, epoch)
        self.thread = threading.Thread(target=self._serve, args=(server,), name="shard", daemon=True)
        self.thread.start()
        if not self._ready.wait(START_TIMEOUT) or self.error is not None:
            raise RuntimeError(self.error or "the shard's ports did not open")
        return {name: srv.ports for name, srv in server.servers.items()}

    def _serve(self, server: ShardServer) -> None:
        def ready(srv: FleetServer) -> None:
            self.server, self.loop = srv, asyncio.get_running_loop()
            self._ready.set()

        try:
            self.exit_code = asyncio.run(serve_until_stopped(server, ready, False, "shard"))
        except OSError as exc:
            self.error = f"cannot listen: {exc.strerror or exc}"
            self.exit_code = 2
        finally:
            self._ready.set()
            if self.world is not None:
                self.world.publish(1 << 40, done=True)  # the others stop waiting for us
            if self.fleet is not None:
                self.fleet.close()

    def wait(self) -> int:
        """Block until the shard has ended (its platforms all exited, or ``stop``); its exit status."""
        if self.thread is not None:
            self.thread.join()
        return self.exit_code if self.exit_code is not None else 2

    def stop(self) -> None:
        if self.loop is not None and self.server is not None:
            self.loop.call_soon_threadsafe(self.server.stop)

    def stats(self) -> dict[str, Any]:
        """The exchange's figures and the simulated time reached (the benchmarks)."""
        out: dict[str, Any] = self.exchange.stats.as_dict() if self.exchange is not None else {}
        control = self.server.control if self.server is not None else None
        out["ticks"] = control.ticks if control is not None else 0
        out["held"] = control.held if control is not None else 0.0
        return out


# ------------------------------------------------------------------------------------------ what every driver does
def options(args: argparse.Namespace) -> dict[str, Any]:
    """What a shard needs of the command line (plain data): the data dir resolved here, as the user meant it."""
    return {
        "data_dir": str(Path(args.data_dir).resolve()),
        "seed": args.seed,
        "no_hardware": args.no_hardware,
        "can_interface": args.can_interface,
        "log_level": args.log_level,
    }


def settled(spec: FleetSpec) -> FleetSpec:
    """The fleet file's data dirs resolved against this directory (a shard may run elsewhere)."""
    platforms = tuple(
        replace(p, data_dir=None if p.data_dir is None else str(Path(p.data_dir).resolve())) for p in spec.platforms
    )
    return replace(spec, platforms=platforms)


def placed(spec: FleetSpec, args: argparse.Namespace) -> FleetSpec:
    """``--fleet N``: the poses chosen here, at free places of the first platform's map (as one process chooses
    them after its boot), so that every shard knows them before it starts."""
    if spec.placed:
        return spec
    from pltf.reference_server.fleet.cli import build_platforms

    first = FleetSpec(spec.platforms[:1])
    probe = argparse.Namespace(**{**vars(args), "no_hardware": True})
    fleet = Fleet(first, build_platforms(first, probe))
    try:
        fleet.boot(0.0)
        poses = fleet._free_places(len(spec.platforms))
    finally:
        fleet.close()
    return FleetSpec(tuple(replace(p, pose=pose) for p, pose in zip(spec.platforms, poses, strict=True)))


@contextlib.contextmanager
def stopped_by_signals(stop: Callable[[], None]) -> Iterator[None]:
    """SIGINT and SIGTERM call ``stop`` (a driver ends its shards itself) while inside; the handlers before after."""
    previous = {sig: signal.signal(sig, lambda *_: stop()) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def first_line(exc: BaseException) -> str:
    """The line of a shard's error that says what went wrong (a traceback from another process is long)."""
    lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
    mine = [line for line in lines if "cannot listen" in line or "Error:" in line]
    return (mine or lines or [type(exc).__name__])[-1][:300]


__all__ = ["START_TIMEOUT", "Shard", "ShardServer", "first_line", "options", "placed", "settled", "stopped_by_signals"]
