"""A fleet spread over shards (``pltf serve --fleet FILE --ray``): which shard serves which platform, the snapshots
the shards exchange every control period, and one shard's world of its own platforms and the others' bodies.

Rules (decision E-FLEET-004 on guide 4.3 "CollCheckEnabled Enable the collision check with all sensors": how fresh
what a platform senses of a platform on another node is; the Ray shell is reference_server/fleet/ray_shards.py):
- ``plan``: one shard per Ray node that serves a platform. A platform's ``node`` (fleet file) names its node by
  index (0 the head, then the others as Ray lists them); the platforms without one go round-robin over all the
  nodes in the file's order. Every shard knows the whole fleet's count: platform k is body k in every shard.
- Every shard is a ``Fleet`` of its own platforms over ``Bodies`` of the whole fleet; the other shards' platforms
  are bodies it places from their ``Snapshot``s (pose, footprint, alive), which its sensors see and its physics
  meets exactly like its own platforms' bodies.
- One clock, a bounded lag of ``lag`` periods (default 1): at tick k a shard places every other shard's bodies
  where they were after THAT shard's tick k - lag, and ticks k only once it has that snapshot (``Exchange.view``
  waits). So no shard runs more than ``lag`` periods ahead of another, and with the same telegrams at the same
  simulated times a run is deterministic whatever the machines' speed and the network's latency. The platforms of
  one shard see each other as in one process (the previous member's move of this very tick).
- A peer that has not delivered the snapshot within ``stall`` wall seconds is LATE: the shard warns and goes on
  with the peer's newest snapshot (not waiting again until the peer has caught up), so a dead or stuck shard
  costs the others one ``stall``, not one per tick; the lag bound is broken for that while (counted: ``late``).
- A peer that said it is ``done`` (its platforms all exited) or that the driver ``drop``ped (its actor or node
  died) is GONE: its bodies leave the world at the next tick and nobody waits for it any more.
- A shard sends its snapshots in batches of ``lag`` ticks (``publish``): one message per peer every ``lag``
  periods, and still in time - a peer at tick k needs our tick k - lag, sent at our tick k - 1 at the latest.
- A platform that exits (CMD_EXIT) is ``alive=False`` in its shard's next snapshot: its body leaves every world.
- Sans-IO: no clock of its own (``clock`` is passed in, for the latency figures and the stall); it blocks only
  in ``Exchange.view``, on a condition the receiving thread signals.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

from pltf.reference_server.control_loop import CONTROL_PERIOD
from pltf.reference_server.fleet.bodies import Bodies
from pltf.reference_server.fleet.config import FleetError, FleetSpec, PlatformSpec
from pltf.reference_server.fleet.fleet import Fleet
from pltf.reference_server.world.physics import Footprint

log = logging.getLogger("pltf.server")

LAG = 1  # periods: at tick k the other shards' bodies are where they were after their tick k - LAG
STALL = 2.0  # wall s a shard waits for a peer's snapshot before it calls the peer late and goes on
KEEP = 256  # snapshots kept per peer (a peer is at most ``lag`` ticks ahead unless we were late)

Outline = tuple[float, float, float]  # a footprint: front, rear, half width (mm)


@dataclass(frozen=True)
class ShardPlan:
    shard: int  # the shard's number = its node's index
    node: int
    total: int  # platforms in the whole fleet
    indices: tuple[int, ...]  # the global index of each of this shard's platforms
    platforms: tuple[PlatformSpec, ...]  # their specs, each with its seed and pose settled
    owners: dict[int, tuple[int, ...]] = field(default_factory=dict)  # every other shard -> its global indices

    @property
    def peers(self) -> list[int]:
        return sorted(self.owners)


def plan(spec: FleetSpec, nodes: int, seed: int, across: str = "the Ray cluster has") -> list[ShardPlan]:
    """The shards of ``spec`` on a cluster of ``nodes`` nodes (or ``nodes`` local processes: ``across`` names them
    in the error); each platform's seed settled (``seed`` + index)."""
    where: list[int] = []
    turn = 0
    for p in spec.platforms:
        if p.node is None:
            where.append(turn % nodes)
            turn += 1
        elif p.node >= nodes:
            raise FleetError(f"platform {p.name!r}: node {p.node}, but {across} {nodes} (0..{nodes - 1})")
        else:
            where.append(p.node)
    settled = [replace(p, seed=seed + k if p.seed is None else p.seed) for k, p in enumerate(spec.platforms)]
    used = sorted(set(where))
    groups = {n: tuple(k for k, w in enumerate(where) if w == n) for n in used}
    return [
        ShardPlan(
            shard=n,
            node=n,
            total=len(spec.platforms),
            indices=groups[n],
            platforms=tuple(settled[k] for k in groups[n]),
            owners={m: groups[m] for m in used if m != n},
        )
        for n in used
    ]


@dataclass(frozen=True)
class Snapshot:
    """A shard's platforms after its tick ``tick`` (tick 0: as booted)."""

    shard: int
    tick: int
    sent: float  # the sender's clock when it was sent (the exchange's latency)
    indices: tuple[int, ...]
    poses: tuple[tuple[float, float, float], ...]
    outlines: tuple[Outline, ...]
    alive: tuple[bool, ...]
    done: bool = False  # the shard has ended (every platform exited, or it was stopped)


@dataclass
class ExchangeStats:
    received: int = 0
    latency_sum: float = 0.0  # s from a peer's send to our receipt, summed
    latency_max: float = 0.0
    latencies: list[float] = field(default_factory=list)  # the last LATENCIES_KEPT, for percentiles
    waits: int = 0  # ticks that had to wait for a peer
    waited: float = 0.0  # wall s spent waiting
    late: int = 0  # times a peer missed ``stall``

    def as_dict(self) -> dict[str, float]:
        lat = sorted(self.latencies)

        def pick(q: float) -> float:
            return lat[min(len(lat) - 1, int(q * len(lat)))] if lat else 0.0

        return {
            "received": self.received,
            "latency_mean": self.latency_sum / max(1, self.received),
            "latency_p50": pick(0.5),
            "latency_p95": pick(0.95),
            "latency_max": self.latency_max,
            "waits": self.waits,
            "waited": self.waited,
            "late": self.late,
        }


LATENCIES_KEPT = 5000


class Exchange:
    """The snapshots a shard has received from its peers; ``view(k)`` waits for what tick k needs."""

    def __init__(self, peers: Sequence[int], clock: Callable[[], float], lag: int = LAG, stall: float = STALL) -> None:
        if lag < 1:
            raise ValueError(f"the lag must be at least one period, not {lag}")
        self.peers, self.clock, self.lag, self.stall = list(peers), clock, lag, stall
        self._got: dict[int, dict[int, Snapshot]] = {p: {} for p in self.peers}
        self._late: set[int] = set()
        self._gone: set[int] = set()
        self._cond = threading.Condition()
        self.stats = ExchangeStats()

    def put(self, snap: Snapshot) -> None:
        """A peer's snapshot arrived (any thread; snapshots may arrive out of order)."""
        self.put_all([snap])

    def put_all(self, snaps: Sequence[Snapshot]) -> None:
        """A peer's batch of snapshots arrived: one latency sample, from the newest's making to now."""
        if not snaps:
            return
        delay = max(0.0, self.clock() - max(s.sent for s in snaps))
        with self._cond:
            s = self.stats
            s.received += 1
            s.latency_sum += delay
            s.latency_max = max(s.latency_max, delay)
            s.latencies.append(delay)
            if len(s.latencies) > LATENCIES_KEPT:
                del s.latencies[: LATENCIES_KEPT // 2]
            for snap in snaps:
                self._store(snap)
            self._cond.notify_all()

    def _store(self, snap: Snapshot) -> None:
        got = self._got.setdefault(snap.shard, {})
        got[snap.tick] = snap
        if len(got) > KEEP:
            for t in sorted(got)[: len(got) - KEEP]:
                del got[t]
        if snap.done:
            self._gone.add(snap.shard)

    def drop(self, shard: int) -> None:
        """The shard is gone (its actor or node died): its bodies leave, nobody waits for it."""
        with self._cond:
            self._gone.add(shard)
            self._cond.notify_all()

    def _has(self, peer: int, need: int) -> bool:
        got = self._got.get(peer, {})
        return need in got or (bool(got) and min(got) > need)

    def view(self, tick: int) -> tuple[list[Snapshot], set[int]]:
        """Each live peer's snapshot for ``tick`` (after its tick ``tick - lag``), waiting for it up to ``stall``;
        and the peers gone so far."""
        need = tick - self.lag
        with self._cond:
            for peer in self.peers:
                if peer in self._late and self._has(peer, need):
                    self._late.discard(peer)
                    log.info("shard %d caught up at tick %d: back in lockstep", peer, tick)
                if peer in self._late or peer in self._gone or self._has(peer, need):
                    continue
                self._wait(peer, need, tick)
            snaps = [self._pick(p, need) for p in self.peers if p not in self._gone and self._got.get(p)]
            return snaps, set(self._gone)

    def _wait(self, peer: int, need: int, tick: int) -> None:
        start = self.clock()
        deadline = start + self.stall
        while not (self._has(peer, need) or peer in self._gone):
            left = deadline - self.clock()
            if left <= 0:
                self._late.add(peer)
                self.stats.late += 1
                log.warning(
                    "shard %d late: no snapshot of its tick %d within %.1f s; tick %d goes on with its newest",
                    peer,
                    need,
                    self.stall,
                    tick,
                )
                break
            self._cond.wait(left)
        self.stats.waits += 1
        self.stats.waited += self.clock() - start

    def _pick(self, peer: int, need: int) -> Snapshot:
        got = self._got[peer]
        if need in got:
            return got[need]
        before = [t for t in got if t <= need]
        return got[max(before)] if before else got[min(got)]


class ShardWorld:
    """What a shard's control loop ticks: the other shards' bodies placed for tick k, its fleet ticked, its
    snapshot sent (``send``) to every peer."""

    def __init__(
        self,
        fleet: Fleet,
        shard: int,
        exchange: Exchange,
        owners: dict[int, tuple[int, ...]],
        send: Callable[[list[Snapshot]], None],
        clock: Callable[[], float],
        period: float = CONTROL_PERIOD,
    ) -> None:
        self.fleet, self.shard, self.exchange, self.owners = fleet, shard, exchange, owners
        self.send, self.clock, self.period = send, clock, period
        self._outlines: dict[int, Outline] = {}
        self._retired: set[int] = set()
        self._batch: list[Snapshot] = []

    def tick(self, now: float) -> None:
        k = round(now / self.period)
        snaps, gone = self.exchange.view(k)
        self.apply(snaps, gone)
        self.fleet.tick(now)
        self.publish(k)

    def apply(self, snaps: list[Snapshot], gone: set[int]) -> None:
        bodies = self.fleet.bodies
        for shard in gone:
            for i in self.owners.get(shard, ()):
                self._retire(bodies, i)
        for snap in snaps:
            for i, pose, outline, alive in zip(snap.indices, snap.poses, snap.outlines, snap.alive, strict=True):
                if not alive:
                    self._retire(bodies, i)
                elif i not in self._retired:
                    if self._outlines.get(i) != outline:
                        self._outlines[i] = outline
                        bodies.set_footprint(i, Footprint(*outline))
                    bodies.place(i, *pose)

    def _retire(self, bodies: Bodies, i: int) -> None:
        if i not in self._retired:
            self._retired.add(i)
            bodies.retire(i)

    def snapshot(self, tick: int, done: bool = False) -> Snapshot:
        members, bodies, live = self.fleet.members, self.fleet.bodies, self.fleet.live
        return Snapshot(
            shard=self.shard,
            tick=tick,
            sent=self.clock(),
            indices=tuple(m.index for m in members),
            poses=tuple((float(x), float(y), float(a)) for x, y, a in (bodies.poses[m.index] for m in members)),
            outlines=tuple(_outline(m.world.footprint) for m in members),
            alive=tuple(not done and m in live for m in members),
            done=done,
        )

    def publish(self, tick: int, done: bool = False) -> None:
        """This tick's snapshot; sent with the ones before it every ``lag`` ticks (and at the end): a peer at
        tick k needs our k - lag, which the batch sent at our tick k - 1 or earlier holds."""
        self._batch.append(self.snapshot(tick, done))
        if done or tick % self.exchange.lag == 0:
            batch, self._batch = self._batch, []
            self.send(batch)


def _outline(fp: Footprint) -> Outline:
    return (float(fp.front), float(fp.rear), float(fp.half_width))


__all__ = ["LAG", "STALL", "Exchange", "ShardPlan", "ShardWorld", "Snapshot", "plan"]
