"""``pltf serve --fleet FILE --ray ADDRESS|auto``: the fleet's shards as Ray actors, one per node (issue 30).

Rules (the shards' rules, the lag and the snapshots: reference_server/fleet/shards.py, erratum E-FLEET-004):
- The driver (this process) connects to the cluster, plans one shard per node (``shards.plan``), starts each as
  a ``ShardActor`` pinned to its node (``NodeAffinitySchedulingStrategy``, not soft), and hands every shard the
  others' handles. Each actor builds its platforms as ``pltf serve --fleet`` does (data dirs on its node, the path
  the driver resolved), boots them at simulated time 0, and on ``go(epoch)`` serves their ports on its node with
  the fleet's asyncio shell in a thread of its own: the one clock is simulated time 0 at the wall-clock ``epoch``
  (``time.time()`` of the driver: the nodes' clocks are assumed in step, as NTP keeps them; a skew only makes
  the faster shard wait within the lag).
- Every ``lag`` control periods each shard sends its snapshots to every other shard directly (``receive``, fire
  and forget: an actor method run on one of the actor's threads), and the control loop's tick waits for the
  peers' (``shards.Exchange``).
- The driver logs "server started at port N" for every port and "platform NAME at HOST:PORT,PORT on node K
  (NODE_ID)" for every platform, then watches the shards: a shard whose platforms all exited ends normally; a
  shard whose actor or node dies (its ``wait`` fails and it does not answer a probe within ``ANSWER_TIMEOUT``:
  Ray reports a killed node's actors as unavailable first) is LOST: the driver logs "shard K on node K lost
  (...): platforms A, B stopped serving" and tells the others to drop its bodies; the others keep serving. The
  driver exits when no shard is left (status 0; 1 when one was lost) or on SIGINT/SIGTERM (it stops every
  shard, status 0).
- Ray is imported here only, and this module only under ``--ray``: without the extra the user gets one line.
  Loopback stays loopback: ``RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0`` is set (unless set) before Ray is imported,
  or Ray would resolve 127.0.0.1 to this machine's outward address.
"""

from __future__ import annotations

import argparse
import logging
import os
import socket
import sys
import threading
import time
from typing import Any

from pltf.harness.ray_actors import kill_actors
from pltf.reference_server.fleet.config import FleetError, FleetSpec
from pltf.reference_server.fleet.shard import (
    START_TIMEOUT,
    Shard,
    first_line,
    options,
    placed,
    settled,
    stopped_by_signals,
)
from pltf.reference_server.fleet.shards import LAG, ShardPlan, plan

log = logging.getLogger("pltf.server")

INSTALL = "pip install 'pltf-toolkit[ray]'"
CPUS = 1.0  # a shard is a busy simulation loop: a whole CPU of its node
THREADS = 8  # the actor's threads: wait, receive (one per peer at a time), stats, stop
STOP_GRACE = 10.0  # s the shards have to stop at SIGINT/SIGTERM before they are killed
WATCH = 0.5  # s between two looks at the shards
ANSWER_TIMEOUT = 5.0  # s a shard whose wait failed has to answer before it is called lost
PROBE_TIMEOUT = 5.0  # s for the cluster's GCS port to accept a connection


class RayMissing(RuntimeError):
    """Ray is not installed (one line naming the extra), or its cluster cannot be reached (one line: why)."""


def import_ray() -> Any:
    os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
    try:
        import ray
    except ImportError:
        raise RayMissing(f"--ray needs Ray, an optional extra: {INSTALL}") from None
    return ray


# ------------------------------------------------------------------------------------------ a shard (the actor)
class ShardActor(Shard):
    """One shard on its node (``ray.remote`` is applied in ``Driver``, so that this module imports without Ray)."""

    def prepare(self, shard: ShardPlan, options: dict[str, Any], lag: int) -> tuple[str, int]:  # type: ignore[override]
        """Build and boot this shard's platforms (simulated time 0); this node's id and this process's."""
        import ray

        return ray.get_runtime_context().get_node_id(), super().prepare(shard, options, lag)

    def connect(self, peers: dict[int, Any]) -> None:
        """The other shards' actor handles: a batch goes to each with ``receive.remote`` (fire and forget)."""
        super().connect({k: handle.receive.remote for k, handle in peers.items()})


# ------------------------------------------------------------------------------------------ the driver
def _nodes(ray: Any) -> list[dict[str, Any]]:
    """The cluster's alive nodes in the order of the fleet file's ``node: K``: the head first, then by address,
    the nodes of one machine in the order they started (their raylet sockets: raylet, raylet.1, raylet.2, ...)."""
    return sorted((n for n in ray.nodes() if n.get("Alive")), key=_node_order)


def _node_order(node: dict[str, Any]) -> tuple[bool, tuple[int, ...], int]:
    head = "node:__internal_head__" in node.get("Resources", {})
    address = tuple(int(x) if x.isdigit() else 0 for x in str(node.get("NodeManagerAddress", "")).split("."))
    suffix = str(node.get("RayletSocketName", "")).rsplit(".", 1)[-1]
    return not head, address, int(suffix) if suffix.isdigit() else 0


class Driver:
    def __init__(self, spec: FleetSpec, args: argparse.Namespace) -> None:
        self.ray = import_ray()
        self.spec, self.args = spec, args
        self.actors: dict[int, Any] = {}
        self.plans: dict[int, ShardPlan] = {}
        self.node_ids: dict[int, str] = {}
        self.ports: dict[str, list[int]] = {}
        self.connected_here = False
        self._stopping = threading.Event()

    # ---- start
    def connect(self) -> None:
        ray = self.ray
        if ray.is_initialized():
            return
        _probe(self.args.ray)
        try:
            ray.init(address=self.args.ray, log_to_driver=False, logging_level="ERROR")
        except Exception as exc:  # ConnectionError, or Ray's own: no cluster at that address
            raise RayMissing(f"cannot connect to the Ray cluster at {self.args.ray}: {first_line(exc)}") from None
        self.connected_here = True

    def start(self) -> None:
        ray = self.ray
        from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

        nodes = _nodes(ray)
        plans = plan(self.spec, len(nodes), self.args.seed)
        options_ = options(self.args)
        actor_class = ray.remote(num_cpus=CPUS, max_concurrency=THREADS, max_restarts=0)(ShardActor)
        for p in plans:
            node_id = nodes[p.node]["NodeID"]
            strategy = NodeAffinitySchedulingStrategy(node_id=node_id, soft=False)
            self.actors[p.shard] = actor_class.options(scheduling_strategy=strategy).remote()
            self.plans[p.shard] = p
            self.node_ids[p.shard] = node_id
        refs = [self.actors[p.shard].prepare.remote(p, options_, self.args.ray_lag) for p in plans]
        for p, (node_id, _pid) in zip(plans, ray.get(refs, timeout=START_TIMEOUT), strict=True):
            assert node_id == self.node_ids[p.shard], "Ray placed a shard on another node than asked"
        handles = dict(self.actors)
        ray.get([a.connect.remote(handles) for a in self.actors.values()], timeout=START_TIMEOUT)
        epoch = time.time()
        served = ray.get(
            [a.go.remote(epoch, self.args.host, self.args.time_scale) for a in self.actors.values()],
            timeout=START_TIMEOUT,
        )
        for shard, ports in zip(self.actors, served, strict=True):
            for name, pair in ports.items():
                self.ports[name] = pair
                for port in pair:
                    log.info("server started at port %d", port)
                where = ",".join(f"{self.args.host}:{port}" for port in pair)
                log.info("platform %s at %s on node %d (%s)", name, where, shard, self.node_ids[shard][:12])

    # ---- run
    def watch(self) -> int:
        """Until every shard has ended: report the lost ones, tell the others."""
        ray = self.ray
        waits = {self.actors[s].wait.remote(): s for s in self.actors}
        lost = 0
        while waits:
            if self._stopping.is_set():
                return self._stop(waits)
            done, _ = ray.wait(list(waits), num_returns=1, timeout=WATCH)
            for ref in done:
                shard = waits.pop(ref)
                try:
                    ray.get(ref)
                    log.info("shard %d on node %d ended: its platforms exited", shard, self.plans[shard].node)
                except Exception as exc:  # ActorDiedError, ActorUnavailableError, ...: the actor or its node
                    if self._answers(shard):  # unreachable for a moment (a loaded node), not gone: watch on
                        log.warning("shard %d did not answer for a moment (%s); it answers again", shard, exc)
                        waits[self.actors[shard].wait.remote()] = shard
                        continue
                    lost += 1
                    self._lost(shard, exc)
        log.info("fleet stopped")
        return 1 if lost else 0

    def _answers(self, shard: int) -> bool:
        """Whether the shard's actor still answers within ``ANSWER_TIMEOUT``."""
        try:
            self.ray.get(self.actors[shard].stats.remote(), timeout=ANSWER_TIMEOUT)
        except Exception:  # Ray's: dead, unreachable or too slow
            return False
        return True

    def _lost(self, shard: int, exc: Exception) -> None:
        names = ", ".join(p.name for p in self.plans[shard].platforms)
        why = type(exc).__name__
        log.error("shard %d on node %d lost (%s): platforms %s stopped serving", shard, shard, why, names)
        self.actors.pop(shard)
        for actor in self.actors.values():
            actor.drop.remote(shard)

    def stop(self) -> None:
        self._stopping.set()

    def _stop(self, waits: dict[Any, int]) -> int:
        ray = self.ray
        for actor in self.actors.values():
            actor.stop.remote()
        ray.wait(list(waits), num_returns=len(waits), timeout=STOP_GRACE)
        log.info("fleet stopped")
        return 0

    def close(self) -> None:
        kill_actors(self.ray, self.actors.values())
        if self.connected_here:
            self.ray.shutdown()


def _probe(address: str) -> None:
    """A HOST:PORT where nothing listens is one line at once (Ray itself retries for minutes)."""
    host, _, port = address.rpartition(":")
    if not host or not port.isdigit():
        return  # 'auto', ray://...: Ray's own lookup
    try:
        socket.create_connection((host, int(port)), timeout=PROBE_TIMEOUT).close()
    except OSError as exc:
        raise RayMissing(f"cannot connect to the Ray cluster at {address}: {exc.strerror or exc}") from None


def run(spec: FleetSpec, args: argparse.Namespace, prog: str) -> int:
    """``pltf serve --fleet FILE|N --ray ADDRESS``: user errors are one line and status 2, as ``pltf serve``'s."""
    try:
        spec = placed(spec, args)
    except FleetError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    try:
        driver = Driver(settled(spec), args)
        driver.connect()
    except RayMissing as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    try:
        with stopped_by_signals(driver.stop):
            driver.start()
            return driver.watch()
    except FleetError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except Exception as exc:  # a shard that could not start (a port taken, a data dir refused): Ray's error
        print(f"{prog}: error: a shard did not start: {first_line(exc)}", file=sys.stderr)
        return 2
    finally:
        driver.close()


__all__ = ["LAG", "Driver", "RayMissing", "ShardActor", "run"]
