"""A fleet in one world: N full platforms, one clock, one index of bodies (issue 30).

Rules:
- Every member is a complete ``Platform`` (state chart, parameters, documents in its own data dir, the fake
  CAN boards on a channel of its own, the task interpreter) with the world as its motion model; the fleet only
  adds that the worlds share their bodies (reference_server/fleet/bodies.py) and that one control loop ticks
  them all, one after the other in the fleet's order, at the same simulated times (``tick``).
- ``boot`` boots every platform as ``pltf serve`` does (start pose, map, roadmap), then puts each at its pose
  from the fleet (the file's, or a free place of the first platform's map for ``--fleet N``) and only then joins
  the bodies: no platform meets another at the data dir's one start pose.
- ``--shared-map`` (``shared_map``): a CMD_SET_MAP a platform accepts is handed to every other live platform as
  if a fleet manager had sent it to each (their state charts still decide).
- A member whose server exits (CMD_EXIT) is ``retire``d: no longer ticked, no longer a body; the rest go on.
- A shard of a fleet spread over Ray nodes (reference_server/fleet/shards.py) is a ``Fleet`` of its own platforms
  whose ``bodies`` hold the whole fleet's (``indices``: its members' places among them); the other shards'
  platforms are bodies it places from their snapshots.
- Sans-IO: ``now`` comes from the caller (reference_server/fleet/network.py).
"""

from __future__ import annotations

import logging
from collections.abc import MutableMapping, Sequence
from dataclasses import dataclass
from typing import Any

from pltf.reference_server.commands import Outcome
from pltf.reference_server.fleet.bodies import Bodies
from pltf.reference_server.fleet.config import FleetSpec, Pose
from pltf.reference_server.fleet.places import free_places
from pltf.reference_server.kinematics import Frame
from pltf.reference_server.platform import Platform
from pltf.reference_server.world.world import World
from pltf.spec.telegram import Telegram

log = logging.getLogger("pltf.server")


class _Named(logging.LoggerAdapter[logging.Logger]):
    """A member's log lines start with its name."""

    def process(self, msg: Any, kwargs: MutableMapping[str, Any]) -> tuple[Any, MutableMapping[str, Any]]:
        return f"[{self.extra['name'] if self.extra else ''}] {msg}", kwargs


class FleetPlatform(Platform):
    """A platform of a fleet: itself in every respect, its log lines named, its accepted maps shared on request."""

    fleet: Fleet | None = None

    def handle(self, telegram: Telegram, now: float) -> Outcome:
        outcome = super().handle(telegram, now)
        fleet = self.fleet
        if fleet is not None and fleet.shared_map and telegram.NAME == "CMD_SET_MAP" and outcome.refused is None:
            fleet.share(self, telegram, now)
        return outcome


@dataclass
class Member:
    name: str
    index: int
    platform: Platform
    ports: tuple[int, ...]
    pose: Pose | None

    @property
    def world(self) -> World:
        motion = self.platform.motion
        assert isinstance(motion, World), "a fleet's platforms have the world as motion model"
        return motion


class Fleet:
    def __init__(
        self,
        spec: FleetSpec,
        platforms: list[Platform],
        *,
        shared_map: bool = False,
        bodies: Bodies | None = None,
        indices: Sequence[int] | None = None,
    ) -> None:
        self.spec = spec
        self.bodies = bodies if bodies is not None else Bodies(len(platforms))
        where = range(len(platforms)) if indices is None else indices
        self.members = [
            Member(p.name, k, platform, p.ports, p.pose)
            for k, p, platform in zip(where, spec.platforms, platforms, strict=True)
        ]
        self.live = list(self.members)
        self.shared_map = shared_map
        self._sharing = False  # a shared SET_MAP is being handed on (its copies are not shared again)
        for m in self.members:
            m.platform.logger = _Named(log, {"name": m.name})
            if isinstance(m.platform, FleetPlatform):
                m.platform.fleet = self

    # ---- start and end
    def boot(self, now: float) -> None:
        for m in self.members:
            m.platform.boot(now)
        poses = [m.pose for m in self.members]
        if not self.spec.placed:
            poses = list(self._free_places())
        for m, pose in zip(self.members, poses, strict=True):
            if pose is not None:
                m.platform.motion.place(Frame(*pose))
                m.platform.log(logging.INFO, "pose in the fleet: x:%g y:%g a:%g", *pose)
        for m in self.members:
            m.world.attach(self.bodies.member(m.index))

    def _free_places(self, count: int | None = None) -> list[Pose]:
        """``count`` (default: one per member) free places of the first member's map, stations first."""
        first = self.members[0]
        world, roadmap = first.world, first.platform.roadmap
        stations = [] if roadmap is None else [tuple(st.frame) for st in roadmap.stations.values()]
        geometry = world.geometry
        assert geometry is not None, "a fleet needs a map"
        wanted = len(self.members) if count is None else count
        return free_places(geometry, stations, world.footprint.radius, wanted)  # type: ignore[arg-type]

    def retire(self, member: Member) -> None:
        if member in self.live:
            self.live.remove(member)
            self.bodies.retire(member.index)
            log.info("platform %s left the fleet (%d live)", member.name, len(self.live))

    def close(self) -> None:
        for m in self.members:
            m.platform.close()

    # ---- the control period (reference_server.control_loop.Ticked)
    def tick(self, now: float) -> None:
        for m in self.live:
            m.platform.tick(now)

    # ---- --shared-map
    def share(self, source: Platform, telegram: Telegram, now: float) -> None:
        if self._sharing:
            return
        self._sharing = True
        try:
            for m in self.live:
                if m.platform is not source:
                    m.platform.handle(telegram, now)
        finally:
            self._sharing = False
