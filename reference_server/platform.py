"""The sans-IO platform model: one telegram in, one ``Outcome`` out (guide 4 and 6).

Rules:
- ``handle(telegram, now)`` first asks the state chart (reference_server.state_chart, the only place that
  decides where a command is allowed), then runs the command's handler from the ``_HANDLERS`` table, then
  fires the state chart's transition. A refused command changes nothing and is logged.
- Only answered telegrams (the GET_* requests, guide 6.1 "returns data only on request") produce a reply;
  every other command is silent, whatever happens to it.
- ``tick(now)`` advances time-based behaviour (drive, watchdogs, emergency reset); ``now`` is simulated
  seconds and comes from the caller, like every source of time and randomness here.
- Hardware that does not exist yet (boards, camera, head drive) is reported absent, never invented: the
  commands for it are accepted where the state chart allows them and logged as without effect.
- Log lines go to the "pltf.server" logger and to the protocol queue of CMD_GET_DEBUG_DATA.
"""

from __future__ import annotations

import logging
import math
import random
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from reference_server import status
from reference_server.documents import Documents, from_wire, to_wire
from reference_server.kinematics import Drive, Frame, Roadmap, relative_to_world
from reference_server.state_chart import State, StateChart
from reference_server.storage import Storage, StorageError
from spec.documents import DocumentError, DocumentKind
from spec.model import enum_classes
from spec.parameters import ParameterError, ParameterStore
from spec.telegram import Telegram

log = logging.getLogger("pltf.server")

# The spec's telegram classes and enums are built at import: their fields and members are invisible to mypy,
# so handlers take the telegram as Any and the enums are typed Any.
_E: dict[str, Any] = dict(enum_classes())
MotionMode: Any = _E["MotionMode"]
PlannerState: Any = _E["PlannerState"]

PROTOCOL_QUEUE_LENGTH = 32  # log lines kept for CMD_GET_DEBUG_DATA


@dataclass(frozen=True)
class Outcome:
    """What the network shell must do after a telegram (``refused``/``ignored`` explain a no-op)."""

    reply: Telegram | None = None
    close_connection: bool = False
    exit_server: bool = False
    refused: str | None = None  # not allowed now, or invalid: nothing changed
    ignored: str | None = None  # allowed, but without effect (motion mode, absent hardware, unused command)


ACCEPTED = Outcome()
Handler = Callable[["Platform", Any, float], Outcome]
_HANDLERS: dict[str, Handler] = {}


def handles(*names: str) -> Callable[[Handler], Handler]:
    def register(func: Handler) -> Handler:
        for name in names:
            _HANDLERS[name] = func
        return func

    return register


def handler_names() -> frozenset[str]:
    return frozenset(_HANDLERS)


def _rad(milli_deg: int) -> float:
    """[1000*deg] of the motion telegrams -> rad."""
    return math.radians(milli_deg / 1000.0)


_DOCUMENT_OF = {
    "MAP": DocumentKind.MAP,
    "ROADMAP": DocumentKind.ROADMAP,
    "PROGRAM": DocumentKind.PROGRAM,
}


class Platform:
    def __init__(self, data_dir: Storage, seed: int = 0, parameters: ParameterStore | None = None) -> None:
        self.storage = data_dir
        self.random = random.Random(seed)  # for the simulated sensors of later issues
        self.params = parameters if parameters is not None else ParameterStore()
        self.chart = StateChart()
        self.documents = Documents(data_dir)
        self.drive = Drive(self.params.get)
        self.roadmap: Roadmap | None = None
        self.motion_mode: int = MotionMode.MODE_MOTION_NO
        self.planner_state: int = PlannerState.PLANNER_STANDBY
        self.mapping = False
        self.can_listening: set[int] = set()
        self.brakes: dict[int, int] = {}
        self.mouse_obstacle: tuple[int, int] | None = None
        self.protocol_queue: deque[str] = deque(maxlen=PROTOCOL_QUEUE_LENGTH)
        self.now = 0.0
        self._last_tick: float | None = None

    # ---- start-up (the original's log: init pose, load map, load roadmap, system state)
    def boot(self, now: float = 0.0) -> None:
        self.now = now
        try:
            pose = self.storage.read_start_pose()
            self.drive.set_pose(Frame(pose.x, pose.y, pose.angle))
            self._log(logging.INFO, "init pose read from %s, x:%g y:%g a:%g", self.storage.root / "StartupPosition.dat",
                      pose.x, pose.y, pose.angle)  # fmt: skip
        except StorageError as exc:
            self._log(logging.WARNING, "init pose not read: %s; starting at x:0 y:0 a:0", exc)
        for kind in _DOCUMENT_OF.values():
            self._load(kind, startup=True)
        self._log(logging.INFO, "system state: %s", self.chart.state.value)

    # ---- the two entry points
    def handle(self, telegram: Telegram, now: float) -> Outcome:
        self.now = now
        name = telegram.NAME
        reason = self.chart.check(name)
        if reason is not None:
            self._log(logging.WARNING, "%s", reason)
            return Outcome(refused=reason)
        handler = _HANDLERS.get(name)
        if handler is None:  # pragma: no cover - a test checks every telegram has a handler
            return self._ignore(f"command {name} not implemented")
        outcome = handler(self, telegram, now)
        if outcome.refused is None:
            old, new = self.chart.fire(name)
            if old is not new:
                self._log(logging.INFO, "system state: %s", new.value)
        return outcome

    def tick(self, now: float) -> None:
        dt = 0.0 if self._last_tick is None else now - self._last_tick
        self._last_tick = now
        self.now = now
        if self.chart.tick(now):
            self._log(logging.INFO, "emergency stop reset complete")
        if dt > 0.0:
            for event in self.drive.step(now, dt):
                self._log(logging.INFO, "%s", event)

    # ---- the emergency stop (no telegram: pressed on the platform; the board issues drive it)
    def set_emergency(self, pressed: bool, now: float) -> None:
        self.now = now
        if pressed:
            self.drive.halt()
            _, new = self.chart.press_emergency()
            self._log(logging.WARNING, "emergency stop active: motion halted, system state: %s", new.value)
        elif self.chart.release_emergency(now):
            self._log(logging.INFO, "emergency stop released: safety system reset")

    # ---- helpers
    def _log(self, level: int, msg: str, *args: object) -> None:
        text = msg % args if args else msg
        self.protocol_queue.append(f"{self.now:.3f} {text}".encode("latin-1", "replace").decode("latin-1"))
        log.log(level, "%s", text)

    def _refuse(self, reason: str) -> Outcome:
        self._log(logging.WARNING, "%s", reason)
        return Outcome(refused=reason)

    def _ignore(self, reason: str) -> Outcome:
        self._log(logging.INFO, "%s", reason)
        return Outcome(ignored=reason)

    def _mode_name(self) -> str:
        return str(MotionMode(self.motion_mode).name)

    # ---- CAN communication (guide 6.3)
    @handles("CMD_CONNECT_TO_PLTF")
    def _connect(self, t: Any, now: float) -> Outcome:
        self._log(logging.INFO, "CAN bus connected (simulated platform: no CAN nodes answer)")
        return ACCEPTED

    @handles("CMD_SHUTDOWN_PLTF")
    def _shutdown(self, t: Any, now: float) -> Outcome:
        self.drive.halt()
        self._log(logging.INFO, "CAN bus shut down, motion stopped")
        return ACCEPTED

    @handles("CMD_INIT_PLTF")
    def _init(self, t: Any, now: float) -> Outcome:
        self._log(logging.INFO, "platform initialized, self test passed")
        return ACCEPTED

    @handles("CMD_SET_BRAKE")
    def _set_brake(self, t: Any, now: float) -> Outcome:
        self.brakes[t.motor] = t.state
        return self._ignore(f"brake {t.state} set for motor {t.motor}: no motor board on the CAN bus")

    @handles("CMD_SET_DIGOUT", "CMD_START_ULTRASONIC", "CMD_STOP_ULTRASONIC", "CMD_SEND_CAN_MESSAGE")
    def _absent_board(self, t: Any, now: float) -> Outcome:
        return self._ignore(f"{t.NAME}: the board is not present on the CAN bus")

    @handles("CMD_ADD_CAN_LISTENING_ID", "CMD_REMOVE_CAN_LISTENING_ID")
    def _can_listen(self, t: Any, now: float) -> Outcome:
        if t.NAME == "CMD_ADD_CAN_LISTENING_ID":
            self.can_listening.add(t.can_id)
        else:
            self.can_listening.discard(t.can_id)
        self._log(logging.INFO, "CAN listening ids: %s", sorted(self.can_listening))
        return ACCEPTED

    @handles("CMD_GET_CAN_MESSAGES")
    def _get_can_messages(self, t: Any, now: float) -> Outcome:
        return Outcome(reply=status.reply("CMD_GET_CAN_MESSAGES", messages=()))  # no CAN node sends anything yet

    # ---- platform operation (guide 6.3, 4.2)
    @handles("CMD_START")
    def _start(self, t: Any, now: float) -> Outcome:
        self.drive.stop()
        self._log(logging.INFO, "start motion mode %s", self._mode_name())
        return ACCEPTED

    @handles("CMD_BREAK")
    def _break(self, t: Any, now: float) -> Outcome:
        self.drive.hold()
        return ACCEPTED

    @handles("CMD_CONTINUE")
    def _continue(self, t: Any, now: float) -> Outcome:
        self.drive.resume()
        return ACCEPTED

    @handles("CMD_STOP")
    def _stop(self, t: Any, now: float) -> Outcome:
        self.drive.stop()
        return ACCEPTED

    @handles("CMD_SET_MODE")
    def _set_mode(self, t: Any, now: float) -> Outcome:
        self.motion_mode = t.mode
        self._log(logging.INFO, "motion mode: %s", self._mode_name())
        return ACCEPTED

    @handles("CMD_EXIT")
    def _exit(self, t: Any, now: float) -> Outcome:
        self.drive.halt()
        self.chart.shutdown()
        self._log(logging.INFO, "exit: platform control shuts down")
        return Outcome(exit_server=True)

    @handles("CMD_CLOSE_SOCKET")
    def _close_socket(self, t: Any, now: float) -> Outcome:
        return Outcome(close_connection=True)

    # ---- request status (guide 6.3, 6.4)
    @handles("CMD_GET_STATUS")
    def _get_status(self, t: Any, now: float) -> Outcome:
        return Outcome(reply=status.status_reply(self, now))

    @handles("CMD_GET_POSITION")
    def _get_position(self, t: Any, now: float) -> Outcome:
        return Outcome(reply=status.position_reply(self))

    # ---- motion (guide 4.3: which move commands have an effect in which motion mode)
    def _unless_mode(self, name: str, *modes: int) -> Outcome | None:
        if self.motion_mode in modes:
            return None
        return self._ignore(f"{name} has no effect in motion mode {self._mode_name()}")

    @handles("CMD_MOVE_VEL_WHEEL")
    def _move_vel_wheel(self, t: Any, now: float) -> Outcome:
        # guide 4.3 Mode Velocity: "set ... using the commands CMD_MOVE_VEL_WHEEL or CMD_MOVE_VEL"
        skip = self._unless_mode(t.NAME, MotionMode.MODE_MOTION_VEL)
        if skip is None:
            self.drive.command_wheels(t.vel_right, t.vel_left, now)
        return skip or ACCEPTED

    @handles("CMD_MOVE_VEL")
    def _move_vel(self, t: Any, now: float) -> Outcome:
        # guide 4.3 Mode Joystick (Software): "set ... using the command CMD MOVE VEL"; [1000*rad/s] = mrad/s
        skip = self._unless_mode(t.NAME, MotionMode.MODE_MOTION_VEL, MotionMode.MODE_MOTION_JOYSOFT)
        if skip is None:
            kind = "joy" if self.motion_mode == MotionMode.MODE_MOTION_JOYSOFT else "vel"
            self.drive.command_velocity(float(t.vel_trans), t.vel_rot / 1000.0, now, kind)
        return skip or ACCEPTED

    def _drive_path(self, name: str, frames: list[Frame]) -> Outcome:
        skip = self._unless_mode(name, MotionMode.MODE_MOTION_AUTOMATIC)
        if skip is not None:
            return skip
        if not frames:
            return self._refuse(f"{name}: empty path")
        self.drive.command_path(frames)  # guide 4.3: a new move command preempts the running one
        end = frames[-1]
        self._log(logging.INFO, "%s: target x:%.0f y:%.0f a:%.3f", name, end.x, end.y, end.angle)
        return ACCEPTED

    @handles("CMD_MOVE_ABS")
    def _move_abs(self, t: Any, now: float) -> Outcome:
        return self._drive_path(t.NAME, [Frame(t.x, t.y, _rad(t.angle))])

    @handles("CMD_MOVE_REL")
    def _move_rel(self, t: Any, now: float) -> Outcome:
        target = relative_to_world(self.drive.pose.frame(), Frame(t.x, t.y, _rad(t.angle)))
        return self._drive_path(t.NAME, [target])

    @handles("CMD_MOVE_PATH")
    def _move_path(self, t: Any, now: float) -> Outcome:
        return self._drive_path(t.NAME, [Frame(f.x, f.y, _rad(f.angle)) for f in t.frames])

    @handles("CMD_MOVE_TO_STATION")
    def _move_to_station(self, t: Any, now: float) -> Outcome:
        # guide 4.3: "The shortest path on the roadmap from the current platform position to the target
        # station is calculated. Following the command CMD_MOVE_PATH is executed."
        skip = self._unless_mode(t.NAME, MotionMode.MODE_MOTION_AUTOMATIC)
        if skip is not None:
            return skip
        if self.roadmap is None:
            return self._refuse(f"{t.NAME}: no active roadmap")
        goal = self.roadmap.find(t.station)
        if goal is None:
            return self._refuse(f"{t.NAME}: no station {t.station!r} in the roadmap")
        pose = self.drive.pose
        start = self.roadmap.nearest(pose.x, pose.y)
        frames = None if start is None else self.roadmap.route(start.id, goal.id)
        if frames is None:
            self.planner_state = PlannerState.PLANNER_NO_PATH
            return self._refuse(f"{t.NAME}: no path on the roadmap to station {t.station!r}")
        self.planner_state = PlannerState.PLANNER_PATH_FOUND
        return self._drive_path(t.NAME, frames)

    # ---- platform data (guide 6.3): documents
    def _kind(self, t: Telegram) -> DocumentKind:
        return _DOCUMENT_OF[t.NAME.split("_", 2)[2]]

    def _activated(self, kind: DocumentKind) -> None:
        if kind is DocumentKind.ROADMAP:
            doc = self.documents.get(kind)
            self.roadmap = None if doc is None else Roadmap(doc.tree)

    @handles("CMD_SET_MAP", "CMD_SET_ROADMAP", "CMD_SET_PROGRAM")
    def _set_document(self, t: Any, now: float) -> Outcome:
        kind = self._kind(t)
        name = getattr(t, "name", "")
        try:
            self.documents.set(kind, name, from_wire(t.xml))
        except DocumentError as exc:
            return self._refuse(f"set {kind.value} {name!r} refused: {exc}")
        self._activated(kind)
        self._log(logging.INFO, "set %s: %s (%d bytes)", kind.value, name, len(t.xml))
        return ACCEPTED

    @handles("CMD_GET_MAP", "CMD_GET_ROADMAP", "CMD_GET_PROGRAM")
    def _get_document(self, t: Any, now: float) -> Outcome:
        doc = self.documents.get(self._kind(t))
        xml, name = ("", "") if doc is None else (to_wire(doc.data), doc.name)
        fields = {"xml": xml} if t.NAME == "CMD_GET_PROGRAM" else {"xml": xml, "name": name}
        return Outcome(reply=status.reply(t.NAME, **fields))

    @handles("CMD_LOAD_MAP", "CMD_LOAD_ROADMAP", "CMD_LOAD_PROGRAM")
    def _load_document(self, t: Any, now: float) -> Outcome:
        return self._load(self._kind(t))

    def _load(self, kind: DocumentKind, startup: bool = False) -> Outcome:
        try:
            self.documents.load(kind)
        except (StorageError, DocumentError) as exc:
            what = "not loaded" if startup else "load refused, the active one stays"
            return self._refuse(f"{kind.value} {what}: {exc}")
        self._activated(kind)
        self._log(logging.INFO, "load %s: %s", kind.value, self.storage.path(kind))
        return ACCEPTED

    @handles("CMD_SAVE_MAP", "CMD_SAVE_ROADMAP", "CMD_SAVE_PROGRAM")
    def _save_document(self, t: Any, now: float) -> Outcome:
        kind = self._kind(t)
        try:
            path = self.documents.save(kind)
        except StorageError as exc:
            return self._refuse(f"save {kind.value} refused: {exc}")
        self._log(logging.INFO, "save %s: %s", kind.value, path)
        return ACCEPTED

    @handles("CMD_MAPPING_START", "CMD_MAPPING_STOP", "CMD_MAPPING_RESET")
    def _mapping(self, t: Any, now: float) -> Outcome:
        if t.NAME != "CMD_MAPPING_RESET":
            self.mapping = t.NAME == "CMD_MAPPING_START"
        self._log(logging.INFO, "mapping mode %s (no laser scanner: nothing is mapped)",
                  "reset" if t.NAME == "CMD_MAPPING_RESET" else ("on" if self.mapping else "off"))  # fmt: skip
        return ACCEPTED

    # ---- platform data: pose and parameters
    @handles("CMD_SET_FRM_PLTF")
    def _set_frame(self, t: Any, now: float) -> Outcome:
        self.drive.set_pose(Frame(t.x, t.y, _rad(t.angle)))
        self._log(logging.INFO, "estimated frame set to x:%d y:%d a:%.3f", t.x, t.y, self.drive.pose.angle)
        return ACCEPTED

    @handles("CMD_SET_PLTF_PARAM")
    def _set_param(self, t: Any, now: float) -> Outcome:
        try:
            self.params.set_text(t.key, t.value)
        except ParameterError as exc:  # erratum E-PAR-007: refused as a whole, the old value stays
            return self._refuse(f"set parameter refused: {exc}")
        self._log(logging.INFO, "parameter %s = %s", t.key, self.params.get_text(t.key))
        return ACCEPTED

    @handles("CMD_GET_PLTF_PARAM")
    def _get_param(self, t: Any, now: float) -> Outcome:
        return Outcome(reply=status.param_reply(self.params, t.key))

    @handles("CMD_GET_PLTF_PARAM_VEC")
    def _get_param_vec(self, t: Any, now: float) -> Outcome:
        return Outcome(reply=status.param_vec_reply(self.params))

    # ---- special functions (guide 6.3): host devices the simulated platform does not have
    @handles("CMD_SPEAK_TEXT", "CMD_PLAY_SOUND")
    def _audio(self, t: Any, now: float) -> Outcome:
        text = t.text if t.NAME == "CMD_SPEAK_TEXT" else t.filename
        return self._ignore(f"{t.NAME} {text!r}: no audio output on the simulated platform")

    @handles("CMD_GRAB_IMAGE", "CMD_SET_POS_PAN_TILT_CAMERA", "CMD_SET_POS_HEAD_DRIVE", "CMD_SET_VEL_HEAD_DRIVE")
    def _absent_device(self, t: Any, now: float) -> Outcome:
        device = "head drive" if "HEAD" in t.NAME else "camera"
        return self._ignore(f"{t.NAME}: no {device} mounted")

    # ---- debug (guide 6.3, 6.4)
    @handles("CMD_GET_DEBUG_DATA")
    def _get_debug_data(self, t: Any, now: float) -> Outcome:
        return Outcome(reply=status.debug_reply(self))

    @handles("CMD_GET_CAMERA")
    def _get_camera(self, t: Any, now: float) -> Outcome:
        return Outcome(reply=status.camera_reply())

    @handles("CMD_MOUSE_MOVE")
    def _mouse_move(self, t: Any, now: float) -> Outcome:
        # guide 6.3: "Set the mouse obstacle": right button down places it, up removes it
        self.mouse_obstacle = (t.x, t.y) if t.button == _E["MouseButton"].EV_MOUSE_RBUTTON_DOWN else None
        return ACCEPTED

    @handles("CMD_SET_LOG_ENABLED", "CMD_SET_POST_PROCESS_FILENAME")
    def _unused(self, t: Any, now: float) -> Outcome:
        return self._ignore(f"{t.NAME}: not used at the moment (guide 6.3)")

    @handles("CMD_SET_EVENT")
    def _set_event(self, t: Any, now: float) -> Outcome:
        return self._ignore(f"{t.NAME} {_E['Event'](t.event).name}: post-process recording is not simulated")

    @handles(
        "CMD_DEBUG1", "CMD_DEBUG2", "CMD_DEBUG3", "CMD_DEBUG4", "CMD_GET_MAPIMAGE", "CMD_ENABLE_EXT_MAPPING",
        "CMD_DISABLE_EXT_MAPPING", "CMD_EXT_WRITE_MAPPING", "CMD_EXT_READ_MAPPING", "CMD_WRITE_LCD",
        "CMD_STOP_MOTIONTHREAD", "CMD_RESTART_MOTIONTHREAD", "CMD_SHUTDOWN_HOST",
    )  # fmt: skip
    def _layout_unknown(self, t: Any, now: float) -> Outcome:
        return self._ignore(f"{t.NAME}: layout unknown, command not supported")


__all__ = ["ACCEPTED", "Outcome", "Platform", "State", "handler_names"]
