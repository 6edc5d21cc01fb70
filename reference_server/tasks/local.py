"""The local facade (guide 4.5 "local mode"): the program runs inside the reference server, on its model.

Rules:
- Every action is the socket command a remote program would send, run by the platform model itself
  (``Platform.act``: the state chart, the handlers and their logging as for a client, with the moves taken as
  in motion mode Automatic, E-TASK-007), so a program does the same locally and remotely. Only the stop of a
  motion has no command (E-TASK-007): it ends the motion model's command directly.
- Every reading comes from the reply builders of the socket API (reference_server.status): the local program
  sees what a GET_STATUS / GET_DEBUG_DATA would show at that instant, nothing of the model's internals.
- ``ProgramHook`` is the platform's program (reference_server.program_api.Program): it compiles the active
  program at CMD_START and ticks an ``Interpreter`` on it.
"""

from __future__ import annotations

import datetime
import logging
from collections.abc import Sequence
from typing import Any, Protocol

from pltf.reference_server import status
from pltf.reference_server.tasks import entities, grab
from pltf.reference_server.tasks.entities import StatusFields, StatusSensors
from pltf.reference_server.tasks.facade import Target, TaskError
from pltf.reference_server.tasks.interpreter import Interpreter
from pltf.reference_server.tasks.program import compile_program
from pltf.spec.codec import build
from pltf.spec.documents import DocumentKind
from pltf.spec.parameters import DataType, ParameterError
from pltf.spec.telegram import Telegram


class Platform(Protocol):
    """What the local facade uses of reference_server.platform.Platform (see reference_server/program_api.py)."""

    seed: int
    storage: Any  # reference_server.storage.Storage
    params: Any  # spec.parameters.ParameterStore
    documents: Any  # reference_server.documents.Documents
    motion: Any  # reference_server.motion_api.MotionModel

    def act(self, telegram: Telegram, now: float) -> Any:
        """Run a command of the program like a socket command, moves as in motion mode Automatic."""

    def log(self, level: int, text: str) -> None: ...


EPOCH = datetime.datetime(2030, 1, 1)  # E-TASK-010: the platform's local time at simulated time 0
_LEVELS = {"error": logging.ERROR, "warning": logging.WARNING, "warn": logging.WARNING}


class LocalMachine(StatusSensors):
    FIELDS = StatusFields(
        x="est_x", y="est_y", angle="est_angle", radar_velocity="radar_velocity", battery="io_battery_voltage"
    )

    def __init__(self, platform: Platform, epoch: datetime.datetime = EPOCH) -> None:
        self.p = platform
        self._model: Any = platform  # the reply builders take the concrete Platform
        self.epoch = epoch
        self.now = 0.0
        self.events: set[str] = set()
        self._status: Any = None
        self._debug: Any = None

    def _act(self, command: str, /, **fields: Any) -> Any:
        self._status = self._debug = None
        return self.p.act(build("request", command, **fields), self.now)

    # ---- actuators
    def set_digital_outputs(self, states: Sequence[int]) -> None:
        for n, state in enumerate(states):  # E-TASK-004: Dn is IO board channel n-1
            if state != -1:
                self._act("CMD_SET_DIGOUT", board=0, channel=n, value=state)

    def move_to_pose(self, x: float, y: float, angle: float) -> None:
        self._act("CMD_MOVE_ABS", x=round(x), y=round(y), angle=round(angle * 1000.0))

    def move_to_station(self, name: str) -> None:
        self._act("CMD_MOVE_TO_STATION", station=name)

    def stop_motion(self) -> None:
        self._status = None
        self.p.motion.stop()
        self.p.log(logging.INFO, "program: motion stopped")

    def set_parameter(self, key: str, value: str) -> None:
        self._act("CMD_SET_PLTF_PARAM", key=key, value=value)

    def load(self, map_name: str | None, roadmap_name: str | None) -> None:
        for kind, name in ((DocumentKind.MAP, map_name), (DocumentKind.ROADMAP, roadmap_name)):
            if name is None:
                continue
            data = entities.read_document(self.p.storage.root, kind, name)
            command = "CMD_SET_MAP" if kind is DocumentKind.MAP else "CMD_SET_ROADMAP"
            self._act(command, name=name, xml=data.decode("latin-1"))  # E-WIRE-003: bytes as Latin-1 text

    def log(self, type: str, message: str) -> None:
        self.p.log(_LEVELS.get(type.lower(), logging.INFO), f"task log [{type}] {message}")

    def grab(self, filename: str, scan: bool, image: bool, auto_observation: bool) -> list[str]:
        points = [(float(x), float(y)) for x, y in self.status().scan]
        pose = self.pose()
        if auto_observation:  # E-TASK-013
            self._act("CMD_SET_PLTF_PARAM", key="SurveillanceModeEnabled", value="true")
        try:
            written = grab.write_grab(self.p.storage.root, filename, scan, image, points, pose, self.now)
        except OSError as exc:
            raise TaskError(f"grab {filename}: {exc}") from None
        self.p.log(logging.INFO, f"grab {filename}: {', '.join(written) or 'nothing'}")
        return written

    def move_camera(self, position: str) -> None:
        self._act("CMD_SET_POS_PAN_TILT_CAMERA", position=position)

    def speak(self, text: str) -> None:
        self._act("CMD_SPEAK_TEXT", text=text)

    def play(self, filename: str) -> None:
        self._act("CMD_PLAY_SOUND", filename=filename)

    def turn_head(self, angle: float) -> None:
        self._act("CMD_SET_POS_HEAD_DRIVE", angle=round(angle))

    # ---- sensors: what GET_STATUS / GET_DEBUG_DATA would report now
    def begin_tick(self, now: float) -> None:
        self.now = now
        self._status = self._debug = None

    def status(self) -> Any:
        if self._status is None:
            self._status = status.status_reply(self._model, self.now)
        return self._status

    def debug_data(self) -> Any:
        if self._debug is None:
            self._debug = status.debug_reply(self._model)
        return self._debug

    def parameter(self, key: str) -> tuple[DataType, str]:
        try:
            return DataType(int(self.p.params.parameter(key).type)), self.p.params.get_text(key)
        except ParameterError:
            raise TaskError(f"unknown parameter {key!r}") from None

    def charging_station(self) -> Target | None:
        doc = self.p.documents.get(DocumentKind.ROADMAP)
        return None if doc is None else entities.charging_station(doc.tree)

    def take_user_events(self) -> frozenset[str]:
        out, self.events = frozenset(self.events), set()
        return out


class ProgramHook:
    """The platform's program (reference_server.program_api.Program): the task interpreter on LocalMachine."""

    def __init__(self, platform: Platform) -> None:
        self.p = platform
        self.machine = LocalMachine(platform)
        self.interpreter: Interpreter | None = None
        self._starting = False
        self._held = False  # CMD_BREAK came between CMD_START and the program's first tick

    def start(self, now: float) -> None:
        doc = self.p.documents.get(DocumentKind.PROGRAM)
        if doc is None:
            self.p.log(logging.WARNING, "no active program: MODE_MOTION_PROGRAM runs nothing")
            return
        program = compile_program(doc.tree)  # checked when it was set or loaded already (E-TASK-016)
        self.machine.events.clear()
        self.interpreter = Interpreter(program, self.machine, self.p.seed)
        self._starting, self._held = True, False  # CMD_START is handled before the state is Running: next tick

    def pause(self, now: float) -> None:
        if self._starting:
            self._held = True  # the program starts at CMD_CONTINUE
        elif self.interpreter is not None:
            self.interpreter.pause(now)
            self._log(self.interpreter.tick(now))

    def resume(self, now: float) -> None:
        if self._starting:
            self._held = False
        elif self.interpreter is not None:
            self.interpreter.resume(now)
            self._log(self.interpreter.tick(now))

    def stop(self, now: float) -> None:
        self._starting = False
        if self.interpreter is not None:
            self._log(self.interpreter.stop(now))
            self.interpreter = None

    def tick(self, now: float) -> None:
        if self.interpreter is None:
            return
        if self._starting and not self._held:
            self._starting = False
            self.machine.begin_tick(now)
            self._log(self.interpreter.start(now))
        elif self.interpreter.running:
            self._log(self.interpreter.tick(now))

    def raise_event(self, event_id: str) -> int:
        """E-TASK-012: deliver a user event at the next tick; returns how many tasks wait for it now."""
        if self.interpreter is None or not self.interpreter.running:
            return 0
        self.machine.events.add(event_id)
        return self.interpreter.waiting_for(event_id)

    def _log(self, records: Any) -> None:
        for r in records:  # task starts, ends and failures come through LocalMachine.log; commands log themselves
            if r.kind == "program":
                self.p.log(logging.INFO, r.text)


def factory(platform: Platform) -> ProgramHook:
    """pltf.reference_server.program_api.ProgramFactory of the task interpreter."""
    return ProgramHook(platform)
