"""What the interpreter needs from a platform: ``Actuators`` and ``Sensors`` (together a ``Machine``).

Rules:
- The interpreter sees the platform only through this facade. Two implementations: ``local.LocalMachine``
  inside the reference server (the platform model, directly) and ``remote.RemoteMachine`` on another computer
  (socket commands through clients.pltf_client only, so it drives the original PlatformCtrl as well).
- Units at this seam: mm, degrees, milliseconds, percent; the facade converts to its wire or model.
- Actions are commands, not requests: like the socket API (guide 6.1) they report nothing back, except the
  failures the facade itself can see, raised as ``TaskError`` (a missing file, an unknown parameter).
- Queries describe the platform as its status telegram would (guide 6.4), refreshed by ``begin_tick``:
  a facade may answer from one snapshot per tick, but never from one taken before its own last command.
"""

from __future__ import annotations

import datetime
from collections.abc import Sequence
from typing import NamedTuple, Protocol

from pltf.reference_server.tasks.model import Detection, Direction, Entity
from pltf.spec.parameters import DataType


class TaskError(Exception):
    """A command of a task failed in a way the task can see (one line, logged by the interpreter)."""


class Pose(NamedTuple):
    x: float  # mm
    y: float  # mm
    angle: float  # degrees


class Target(NamedTuple):
    """Where <moveto> finds an entity: a point (tracked objects) or a frame (the charging station)."""

    x: float  # mm
    y: float  # mm
    angle: float | None  # degrees; None: face the entity from where the platform stands


class Actuators(Protocol):
    def set_digital_outputs(self, states: Sequence[int]) -> None:
        """D1..D12 (index 0..11): -1 unchanged, 0 off, 1 on (guide 6.5 <digitalout>)."""

    def move_to_pose(self, x: float, y: float, angle: float) -> None:
        """A motion to a frame in map coordinates (CMD_MOVE_ABS)."""

    def move_to_station(self, name: str) -> None:
        """A motion over the roadmap (CMD_MOVE_TO_STATION)."""

    def stop_motion(self) -> None: ...

    def set_parameter(self, key: str, value: str) -> None:
        """CMD_SET_PLTF_PARAM; TaskError when the facade knows it was refused."""

    def load(self, map_name: str | None, roadmap_name: str | None) -> None:
        """Activate the named map and roadmap files of the data dir; TaskError when one is missing or invalid."""

    def log(self, type: str, message: str) -> None: ...

    def grab(self, filename: str, scan: bool, image: bool, auto_observation: bool) -> list[str]:
        """Write ``filename``.dat (the scan) and/or ``filename``.jpg (an image); the paths written."""

    def move_camera(self, position: str) -> None: ...

    def speak(self, text: str) -> None: ...

    def play(self, filename: str) -> None: ...

    def turn_head(self, angle: float) -> None: ...


class Sensors(Protocol):
    def begin_tick(self, now: float) -> None:
        """A new tick at simulated time ``now``: snapshots taken before may be dropped."""

    def pose(self) -> Pose: ...

    def target_reached(self) -> bool: ...

    def collision(self) -> bool: ...

    def detected(self, what: Detection) -> bool: ...

    def localization_lost(self) -> bool: ...

    def infrared(self, direction: Direction | None) -> bool:
        """Whether the IR sensor in ``direction`` (None: any) is active."""

    def radar(self, direction: Direction | None) -> bool:
        """Whether the radar sensor in ``direction`` (None: any) sees motion (E-TASK-011)."""

    def battery_percent(self) -> float: ...

    def digital_input(self, n: int) -> int:
        """DIn, n = 1..16 (E-XML-013)."""

    def digital_output(self, n: int) -> int:
        """DOn, n = 1..12 (E-XML-013)."""

    def parameter(self, key: str) -> tuple[DataType, str]:
        """The parameter's type and value text; TaskError for an unknown key (E-XML-013)."""

    def entity(self, what: Entity) -> Target | None:
        """Where <moveto> would go, or None when there is no such entity (E-TASK-008)."""

    def take_user_events(self) -> frozenset[str]:
        """The user events raised since the last call (E-TASK-012)."""

    def local_time(self, now: float) -> datetime.datetime:
        """The platform's local wall time at simulated time ``now`` (E-TASK-010)."""


class Machine(Actuators, Sensors, Protocol):
    """Both halves: what an interpreter runs against."""
