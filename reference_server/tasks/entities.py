"""What both facades read alike: the sensors, where <moveto> finds its entity, the files <load> sends.

Rules:
- The tracked person, ball and moving object are the clusters of CMD_GET_DEBUG_DATA (map coordinates,
  E-TASK-008), the nearest one to the platform wins; the charging station is the roadmap station whose name or
  id starts with "charg" (case-insensitive; the fixtures' "Charging"), docked at its own frame.
- ``StatusSensors`` answers the queries of ``facade.Sensors`` from one GET_STATUS / GET_DEBUG_DATA snapshot
  per tick; each facade fetches its snapshots and names their fields (``StatusFields``: the codec telegram's
  locally, pltf_client's remotely). So the local and the remote facade, given the same platform, answer alike
  and drive to the same frame.
- <load> reads its files on the computer the program runs on (E-TASK-006, E-TASK-014): ``read_document``
  looks in ``<data dir>/Map/`` (``Roadmap/``), then in the data dir itself, and validates what it reads.
"""

from __future__ import annotations

import abc
import datetime
import math
from collections.abc import Iterable
from pathlib import Path
from typing import Any, ClassVar, NamedTuple

from pltf.reference_server.tasks.facade import Pose, Target, TaskError
from pltf.reference_server.tasks.model import Detection, Direction, Entity
from pltf.spec.documents import DocumentError, DocumentKind, validate_document

CHARGING_PREFIX = "charg"


def nearest_cluster(clusters: Iterable[tuple[int, int, int]], pose: Pose) -> Target | None:
    """The (x, y, index) cluster nearest the platform, as a point target; None when there is none."""
    best = min(clusters, key=lambda c: math.hypot(c[0] - pose.x, c[1] - pose.y), default=None)
    return None if best is None else Target(float(best[0]), float(best[1]), None)


def charging_station(roadmap_root: Any) -> Target | None:
    """The charging station of a validated roadmap (lxml element or tree), or None."""
    if roadmap_root is None:
        return None
    root = roadmap_root.getroot() if hasattr(roadmap_root, "getroot") else roadmap_root
    for st in root.iterfind("stations/station"):
        names = (st.get("name") or "", st.get("id") or "")
        if any(n.lower().startswith(CHARGING_PREFIX) for n in names):
            pt = st.find("point")
            return Target(float(pt.get("x")), float(pt.get("y")), float(st.get("angle") or 0))
    return None


# ------------------------------------------------------------------------------------------------ <load>

_FOLDERS = {DocumentKind.MAP: "Map", DocumentKind.ROADMAP: "Roadmap"}


def read_document(data_dir: Path, kind: DocumentKind, name: str) -> bytes:
    """<load>'s map or roadmap NAME, schema-valid; a TaskError when it is missing or invalid.

    E-TASK-006: ``<data dir>/Map/NAME`` (``Roadmap/NAME``), else ``<data dir>/NAME``.
    """
    path = next((p for p in (data_dir / _FOLDERS[kind] / name, data_dir / name) if p.is_file()), None)
    if path is None:
        raise TaskError(f"no {kind.value} file {name!r} in {data_dir / _FOLDERS[kind]} or {data_dir}")
    data = path.read_bytes()
    try:
        validate_document(kind, data)
    except DocumentError as exc:
        raise TaskError(f"{name}: {exc}") from None
    return data


# ---------------------------------------------------------------------------------------------- sensors

NOMINAL_MV, EMPTY_MV = 25_600.0, 23_000.0  # E-TASK-015: 100 % and 0 % of the battery charge
RADAR_MIN_SPEED = 50.0  # mm/s: a radar reading above this is "something detected" (E-TASK-011)
RADAR_ABSENT = -1  # radar_status of a board that is not on the CAN bus (E-SRV-008)
# GET_DEBUG_DATA's cluster group of each detection; a "tracked..." entity is the same group (E-TASK-008)
CLUSTERS = {"movingobject": "moving_clusters", "person": "person_clusters", "ball": "ball_clusters"}


def battery_percent(millivolts: float) -> float:
    """E-TASK-015: linear between 23000 mV (0 %, the IO board's low-battery level) and 25600 mV (100 %)."""
    return max(0.0, min(100.0, (millivolts - EMPTY_MV) / (NOMINAL_MV - EMPTY_MV) * 100.0))


class StatusFields(NamedTuple):
    """The names a status snapshot gives what the sensors read (the codec telegram's, or pltf_client's)."""

    x: str  # mm
    y: str  # mm
    angle: str  # millidegrees
    radar_velocity: str  # mm/s, one per direction
    battery: str  # mV


class StatusSensors(abc.ABC):
    """The queries of ``facade.Sensors`` that both facades answer alike, from this tick's snapshots.

    A facade sets ``FIELDS`` and ``epoch`` and implements the abstract hooks ``status`` and ``debug_data`` (the
    tick's GET_STATUS and GET_DEBUG_DATA replies) and ``charging_station`` (from its roadmap, E-TASK-008); a
    facade that leaves one out fails at construction.
    """

    FIELDS: ClassVar[StatusFields]
    epoch: datetime.datetime

    @abc.abstractmethod
    def status(self) -> Any:
        """This tick's GET_STATUS reply."""

    @abc.abstractmethod
    def debug_data(self) -> Any:
        """This tick's GET_DEBUG_DATA reply."""

    @abc.abstractmethod
    def charging_station(self) -> Target | None:
        """The charging station of the active roadmap, or None (E-TASK-008)."""

    def _field(self, name: str) -> Any:
        return getattr(self.status(), getattr(self.FIELDS, name))

    def _clusters(self, what: Detection | Entity) -> list[tuple[int, int, int]]:
        group = getattr(self.debug_data(), CLUSTERS[what.value.removeprefix("tracked")])
        return [(int(x), int(y), int(i)) for x, y, i in group]

    def pose(self) -> Pose:
        return Pose(float(self._field("x")), float(self._field("y")), self._field("angle") / 1000.0)

    def target_reached(self) -> bool:
        return bool(self.status().target_reached)

    def collision(self) -> bool:
        return bool(self.status().collision)

    def detected(self, what: Detection) -> bool:
        return bool(self._clusters(what))

    def localization_lost(self) -> bool:
        return bool(self.status().localization_lost)

    def infrared(self, direction: Direction | None) -> bool:
        ir = self.status().ir_active
        return any(ir) if direction is None else bool(ir[direction])

    def radar(self, direction: Direction | None) -> bool:
        if self.status().radar_status == RADAR_ABSENT:
            return False
        moving = [abs(v) >= RADAR_MIN_SPEED for v in self._field("radar_velocity")]
        return any(moving) if direction is None else moving[direction]

    def battery_percent(self) -> float:
        return battery_percent(self._field("battery"))

    def digital_input(self, n: int) -> int:
        return int(self.status().io_digital_in >> (n - 1)) & 1

    def digital_output(self, n: int) -> int:
        return int(self.status().io_digital_out >> (n - 1)) & 1

    def entity(self, what: Entity) -> Target | None:
        if what is Entity.CHARGING_STATION:
            return self.charging_station()
        return nearest_cluster(self._clusters(what), self.pose())

    def local_time(self, now: float) -> datetime.datetime:
        return self.epoch + datetime.timedelta(seconds=now)
