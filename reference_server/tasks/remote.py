"""The remote facade (guide 4.5 "remote mode"): a program on another computer, socket commands only.

Rules:
- Everything goes through clients.pltf_client (``PlatformClient``), so the same run drives the original
  PlatformCtrl. The platform must be Running in MODE_MOTION_AUTOMATIC (pltf run-program brings it there).
- Reads come from one CMD_GET_STATUS per tick, fetched on the first query of the tick; any command sent
  drops the snapshot, so a query after a command always sees a status the platform produced after it (the
  socket keeps the order). Detections need CMD_GET_DEBUG_DATA, parameters CMD_GET_PLTF_PARAM: fetched only
  when a task asks, at most once per tick.
- What the wire cannot carry stays on this computer (E-TASK-014): <load> reads the named file from the local
  data dir and sends it with CMD_SET_MAP/CMD_SET_ROADMAP; <log> goes to this computer's log; <grab> writes the
  scan of the status telegram (and the rendered image) into the local data dir and asks the platform's camera
  with CMD_GRAB_IMAGE; user events are raised on this computer (``raise_event``, E-TASK-012).
- The time base is this computer's simulated clock (``now`` from the caller); <date> compares ``epoch + now``.
"""

from __future__ import annotations

import datetime
import logging
import threading
from collections.abc import Callable, Sequence
from pathlib import Path

from pltf.client import BoardType, DebugData, OutputLevel, PlatformClient, Status
from pltf.reference_server.tasks import entities, grab
from pltf.reference_server.tasks.entities import StatusFields, StatusSensors
from pltf.reference_server.tasks.facade import Target, TaskError
from pltf.spec.documents import DocumentError, DocumentKind, validate_document
from pltf.spec.parameters import DataType

log = logging.getLogger("pltf.tasks.remote")


class RemoteMachine(StatusSensors):
    FIELDS = StatusFields(
        x="est_x_mm",
        y="est_y_mm",
        angle="est_angle_mdeg",
        radar_velocity="radar_velocity_mm_s",
        battery="io_battery_voltage_mv",
    )

    def __init__(
        self,
        client: PlatformClient,
        data_dir: Path,
        epoch: datetime.datetime,
        on_log: Callable[[str, str], None] | None = None,
    ) -> None:
        self.client = client
        self.data_dir = data_dir
        self.epoch = epoch
        self.on_log = on_log
        self.now = 0.0
        self._status: Status | None = None
        self._debug: DebugData | None = None
        self._params: dict[str, tuple[DataType, str]] = {}
        self._roadmap: Target | bool | None = False  # False: not fetched this tick
        self._events: set[str] = set()
        self._lock = threading.Lock()

    # ---- user events (E-TASK-012): raised on this computer, e.g. from the console
    def raise_event(self, event_id: str) -> None:
        with self._lock:
            self._events.add(event_id)

    def take_user_events(self) -> frozenset[str]:
        with self._lock:
            out, self._events = frozenset(self._events), set()
        return out

    # ---- snapshots
    def begin_tick(self, now: float) -> None:
        self.now = now
        self._forget()

    def _forget(self) -> None:
        self._status, self._debug, self._params, self._roadmap = None, None, {}, False

    def status(self) -> Status:
        if self._status is None:
            self._status = self.client.get_status()
        return self._status

    def _sent(self) -> None:
        self._forget()

    # ---- actuators
    def set_digital_outputs(self, states: Sequence[int]) -> None:
        # E-TASK-004: Dn is channel n-1 of the IO board
        for n, state in enumerate(states):
            if state != -1:
                self.client.set_digout(BoardType.TYPE_IOBOARD, n, OutputLevel(state))
        self._sent()

    def move_to_pose(self, x: float, y: float, angle: float) -> None:
        self.client.move_abs(round(x), round(y), round(angle * 1000.0))  # E-XML-007: degrees -> 1000*deg
        self._sent()

    def move_to_station(self, name: str) -> None:
        self.client.move_to_station(name)
        self._sent()

    def stop_motion(self) -> None:
        # E-TASK-007: Automatic mode has no "stop this move" command; STOP + START ends it and stays Running
        self.client.stop()
        self.client.start()
        self._sent()

    def set_parameter(self, key: str, value: str) -> None:
        self.client.set_pltf_param(key, value)
        self._sent()

    def load(self, map_name: str | None, roadmap_name: str | None) -> None:
        for kind, name in ((DocumentKind.MAP, map_name), (DocumentKind.ROADMAP, roadmap_name)):
            if name is None:
                continue
            data = entities.read_document(self.data_dir, kind, name)
            if kind is DocumentKind.MAP:
                self.client.set_map(name, data)
            else:
                self.client.set_roadmap(name, data)
        self._sent()

    def log(self, type: str, message: str) -> None:
        log.log(logging.ERROR if type.lower() == "error" else logging.INFO, "%s", message)
        if self.on_log is not None:
            self.on_log(type, message)

    def grab(self, filename: str, scan: bool, image: bool, auto_observation: bool) -> list[str]:
        points = [(float(x), float(y)) for x, y in self.status().scan]
        pose = self.pose()
        if image:
            self.client.grab_image(filename)
        if auto_observation:  # E-TASK-013
            self.client.set_pltf_param("SurveillanceModeEnabled", "true")
        self._sent()
        try:
            return grab.write_grab(self.data_dir, filename, scan, image, points, pose, self.now)
        except OSError as exc:
            raise TaskError(f"grab {filename}: {exc}") from None

    def move_camera(self, position: str) -> None:
        self.client.set_pos_pan_tilt_camera(position)
        self._sent()

    def speak(self, text: str) -> None:
        self.client.speak_text(text)
        self._sent()

    def play(self, filename: str) -> None:
        self.client.play_sound(filename)
        self._sent()

    def turn_head(self, angle: float) -> None:
        self.client.set_pos_head_drive(round(angle))  # CMD_SET_POS_HEAD_DRIVE takes whole degrees
        self._sent()

    # ---- sensors (the rest: StatusSensors)
    def parameter(self, key: str) -> tuple[DataType, str]:
        if key not in self._params:
            reply = self.client.get_pltf_param(key)
            if reply.key != key or reply.value == "":  # E-SRV-010: an unknown key has an empty value
                raise TaskError(f"unknown parameter {key!r}")
            self._params[key] = (DataType(int(reply.data_type)), reply.value)
        return self._params[key]

    def debug_data(self) -> DebugData:
        if self._debug is None:
            self._debug = self.client.get_debug_data()
        return self._debug

    def charging_station(self) -> Target | None:
        if self._roadmap is False:
            xml = self.client.get_roadmap().xml
            try:
                self._roadmap = entities.charging_station(validate_document(DocumentKind.ROADMAP, xml))
            except DocumentError:
                self._roadmap = None
        return self._roadmap if isinstance(self._roadmap, Target) else None
