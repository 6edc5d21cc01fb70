"""The sans-IO platform model: one telegram in, one ``Outcome`` out (guide 4 and 6).

Rules:
- ``handle(telegram, now)`` first asks the state chart (reference_server.state_chart, the only place that
  decides where a command is allowed), then runs the command's handler from the table of
  reference_server/commands/ (one module per command family), then fires the state chart's transition. A
  refused command changes nothing and is logged.
- Only answered telegrams (the GET_* requests, guide 6.1 "returns data only on request") produce a reply;
  every other command is silent, whatever happens to it.
- ``tick(now)`` advances time-based behaviour once per control period: the emergency reset, the program, the
  motion (reference_server/motion_api.py: control, physics, odometry); ``now`` is simulated seconds and comes
  from the caller, like every source of time and randomness here.
- The platform owns three plug-ins built by factories: ``motion`` (a ``motion_api.MotionModel``, default
  ``kinematics.Drive``), ``program`` (a ``program_api.Program``, default ``NoProgram``) and ``hardware`` (a
  ``hardware_link.HardwareLink``: the CAN boards and the laser scanner of fake_hardware/; default none).
- With hardware, ``tick`` runs the control period through the boards (hardware_link.py) and maps their
  events to the state chart: emergency stop, drive fault, the end of a self test. A command whose hardware
  part is not done on return answers ``pending`` and its transition fires later (``awaiting``).
- Hardware that does not exist (camera, head drive, audio; the CAN boards without a hardware plug-in) is
  reported absent, never invented: the commands for it are accepted where the state chart allows them and
  logged as without effect.
- Log lines go to the "pltf.server" logger and to the protocol queue of CMD_GET_DEBUG_DATA (``log``).
- ``epoch`` counts the changes of state: every tick, every command that is not a pure query (``QUERIES``) and
  that the state chart lets run, every emergency or drive-fault event and every request of the control channel
  (``touch``). Between two changes the status reply is built once (reference_server/status.py): a client
  polling GET_STATUS faster than the control period gets the same picture, only its timestamp moves.
"""

from __future__ import annotations

import logging
import random
from collections import deque
from collections.abc import Callable

from pltf.reference_server.commands import HANDLERS, Outcome, handler_names
from pltf.reference_server.commands.data import DOCUMENT_OF
from pltf.reference_server.commands.registry import ACCEPTED
from pltf.reference_server.documents import Documents
from pltf.reference_server.enums import MotionMode, PlannerState
from pltf.reference_server.hardware_link import HardwareFactory, HardwareLink, react
from pltf.reference_server.kinematics import Drive, Frame, Roadmap
from pltf.reference_server.motion_api import MotionFactory, MotionModel, WorldFeatures, advance_ideal
from pltf.reference_server.program_api import Program, ProgramFactory, no_program
from pltf.reference_server.state_chart import EmergencyState, State, StateChart
from pltf.reference_server.storage import Storage, StorageError
from pltf.spec.documents import DocumentError, DocumentKind
from pltf.spec.parameters import ParameterStore
from pltf.spec.telegram import Telegram

log = logging.getLogger("pltf.server")

PROTOCOL_QUEUE_LENGTH = 32  # log lines kept for CMD_GET_DEBUG_DATA
OPERATING = (State.RUNNING, State.BREAKED)
QUERIES = frozenset(
    {
        "CMD_GET_STATUS",
        "CMD_GET_POSITION",
        "CMD_GET_PLTF_PARAM",
        "CMD_GET_PLTF_PARAM_VEC",
        "CMD_GET_MAP",
        "CMD_GET_ROADMAP",
        "CMD_GET_PROGRAM",
        "CMD_GET_DEBUG_DATA",
        "CMD_GET_CAMERA",
    }
)


class Platform:
    logger: logging.Logger | logging.LoggerAdapter[logging.Logger] = log  # a fleet's platforms name themselves

    def __init__(
        self,
        data_dir: Storage,
        seed: int = 0,
        parameters: ParameterStore | None = None,
        *,
        motion: MotionFactory | None = None,
        program: ProgramFactory | None = None,
        hardware: HardwareFactory | None = None,
    ) -> None:
        self.storage = data_dir
        self.seed = seed
        self.random = random.Random(seed)  # every simulated part draws its own seed from this one
        self.params = parameters if parameters is not None else ParameterStore()
        self.chart = StateChart()
        self.documents = Documents(data_dir)
        self.roadmap: Roadmap | None = None
        self.motion_mode: int = MotionMode.MODE_MOTION_NO
        self.planner_state: int = PlannerState.PLANNER_STANDBY
        self.mapping = False
        self.can_listening: set[int] = set()
        self.mouse_obstacle: tuple[int, int] | None = None
        self.head_position = 0  # degrees, set by CMD_SET_POS_HEAD_DRIVE (erratum E-TASK-017)
        self.protocol_queue: deque[str] = deque(maxlen=PROTOCOL_QUEUE_LENGTH)
        self.now = 0.0
        self._last_tick: float | None = None
        self.motion: MotionModel = (motion or Drive)(self.params.get)
        self.world: WorldFeatures | None = self.motion if isinstance(self.motion, WorldFeatures) else None
        self._world_planner = PlannerState.PLANNER_STANDBY
        self.program: Program = (program or no_program)(self)
        self.awaiting: str | None = None  # the command whose transition waits for the hardware
        self.drive_fault: str | None = None  # erratum E-HW-025
        self.hardware: HardwareLink | None = None if hardware is None else hardware(self)
        self.epoch = 0  # see the module's rules
        # (epoch, the telegram at a time, its frame at timestamp 0): reference_server.status
        self.status_cache: tuple[int, Callable[[float], Telegram], bytes] | None = None

    @property
    def drive(self) -> MotionModel:
        """The motion model under its first name (``motion`` is the seam's name)."""
        return self.motion

    # ---- start-up (the original's log: init pose, load map, load roadmap, system state)
    def boot(self, now: float = 0.0) -> None:
        self.now = now
        try:
            pose = self.storage.read_start_pose()
            self.motion.place(Frame(pose.x, pose.y, pose.angle))
            self.log(
                logging.INFO,
                "init pose read from %s, x:%g y:%g a:%g",
                self.storage.root / "StartupPosition.dat",
                pose.x,
                pose.y,
                pose.angle,
            )
        except StorageError as exc:
            self.log(logging.WARNING, "init pose not read: %s; starting at x:0 y:0 a:0", exc)
        for kind in DOCUMENT_OF.values():
            self.load_document(kind, startup=True)
        self.log(logging.INFO, "system state: %s", self.chart.state.value)

    # ---- the two entry points
    def handle(self, telegram: Telegram, now: float) -> Outcome:
        self.now = now
        name = telegram.NAME
        reason = self.chart.check(name)
        if reason is not None:  # refused by the state chart: nothing changed, the status stays as built
            self.log(logging.WARNING, "%s", reason)
            return Outcome(refused=reason)
        if name not in QUERIES:
            self.touch()
        handler = HANDLERS.get(name)
        if handler is None:  # pragma: no cover - a test checks every telegram has a handler
            return self.ignore(f"command {name} not implemented")
        outcome = handler(self, telegram, now)
        if outcome.refused is None and outcome.pending is None and outcome.failed is None:
            self.fire(name)
        return outcome

    def act(self, telegram: Telegram, now: float) -> Outcome:
        """A command of the local program (reference_server/tasks/local.py): ``handle`` as for a client, with the
        moves taken as in motion mode Automatic while the platform runs MODE_MOTION_PROGRAM (erratum E-TASK-007)."""
        mode = self.motion_mode
        if mode == MotionMode.MODE_MOTION_PROGRAM:
            self.motion_mode = MotionMode.MODE_MOTION_AUTOMATIC
        try:
            return self.handle(telegram, now)
        finally:
            if self.motion_mode == MotionMode.MODE_MOTION_AUTOMATIC:
                self.motion_mode = mode

    def touch(self) -> None:
        """Something changed: the next status reply is built afresh."""
        self.epoch += 1

    def tick(self, now: float) -> None:
        self.touch()
        dt = 0.0 if self._last_tick is None else now - self._last_tick
        self._last_tick = now
        self.now = now
        if self.chart.tick(now):
            self.log(logging.INFO, "emergency stop reset complete")
        self.program.tick(now)
        if self.hardware is not None:
            lines, events = self.hardware.advance(now, dt)
            for line in lines:
                self.log(logging.INFO, "%s", line)
            react(self, self.hardware, events, now)
        elif dt > 0.0:
            for event in advance_ideal(self.motion, now, dt):
                self.log(logging.INFO, "%s", event)
        if self.world is not None and self.world.planner_state != self._world_planner:
            self.planner_state = self._world_planner = self.world.planner_state  # the planner's latest word

    def fire(self, name: str) -> None:
        """The state chart's transition for an accepted command (now, or when its hardware part is done)."""
        old, new = self.chart.fire(name)
        if old is not new:
            self.log(logging.INFO, "system state: %s", new.value)

    # ---- the emergency stop (no telegram: pressed on the platform; the board issues drive it)
    def set_emergency(self, pressed: bool, now: float) -> None:
        self.now = now
        self.touch()
        if pressed:
            self.leave_operation("emergency stop", now)
            _, new = self.chart.press_emergency()
            self.log(logging.WARNING, "emergency stop active: motion halted, system state: %s", new.value)
        elif self.chart.release_emergency(now):
            self.log(logging.INFO, "emergency stop released: safety system reset")

    @property
    def emergency_pressed(self) -> bool:
        return bool(self.chart.emergency == EmergencyState.ST_EM_ACTIVE)

    def set_drive_fault(self, reason: str | None, now: float) -> None:
        """A drive fault starts, changes its reason or ends (erratum E-HW-025: the secure state, no motion until
        the cause is gone and a new CMD_START)."""
        self.touch()
        old, self.drive_fault = self.drive_fault, reason
        if reason == old:
            return
        if reason is None:
            self.chart.clear_drive_fault()
            self.log(logging.INFO, "drive fault cleared (was: %s)", old)
            return
        if old is None:
            self.leave_operation("drive fault", now)
            _, new = self.chart.enter_drive_fault()
            self.log(logging.WARNING, "drive fault: %s: motion halted, system state: %s", reason, new.value)
        else:
            self.log(logging.WARNING, "drive fault: %s", reason)

    def leave_operation(self, why: str, now: float) -> None:
        """Halt the motion at once; a running program ends (the platform leaves Running/Breaked)."""
        self.motion.halt()
        if self.chart.state in OPERATING and self.motion_mode == MotionMode.MODE_MOTION_PROGRAM:
            self.log(logging.INFO, "program stopped: %s", why)
            self.program.stop(now)

    def shutdown_hardware(self, now: float) -> None:
        """CMD_SHUTDOWN_PLTF / CMD_EXIT: the CAN bus goes down."""
        self.awaiting = None
        if self.hardware is not None:
            self.hardware.shutdown(now)

    def close(self) -> None:
        """Release what the platform holds outside Python objects (the CAN buses, the serial link)."""
        if self.hardware is not None:
            self.hardware.close()

    # ---- helpers for the command modules (reference_server/commands/) and the plug-ins
    def log(self, level: int, msg: str, *args: object) -> None:
        text = msg % args if args else msg
        self.protocol_queue.append(f"{self.now:.3f} {text}".encode("latin-1", "replace").decode("latin-1"))
        self.logger.log(level, "%s", text)

    # --- the command handlers' interface (reference_server/commands/): outcomes, the mode check, documents

    def refuse(self, reason: str) -> Outcome:
        """The telegram is refused (logged as a warning): an error reply where the command has one."""
        self.log(logging.WARNING, "%s", reason)
        return Outcome(refused=reason)

    def ignore(self, reason: str) -> Outcome:
        """The telegram has no effect (logged): guide 4.3, a command outside its motion mode."""
        self.log(logging.INFO, "%s", reason)
        return Outcome(ignored=reason)

    def mode_name(self) -> str:
        return str(MotionMode(self.motion_mode).name)

    def unless_mode(self, name: str, *modes: int) -> Outcome | None:
        """None when the motion mode takes the move ``name``; else the ignored outcome (guide 4.3)."""
        if self.motion_mode in modes:
            return None
        return self.ignore(f"{name} has no effect in motion mode {self.mode_name()}")

    def activated(self, kind: DocumentKind) -> None:
        """The active document of ``kind`` changed: the roadmap and the world's walls follow it."""
        doc = self.documents.get(kind)
        if kind is DocumentKind.ROADMAP:
            self.roadmap = None if doc is None else Roadmap(doc.tree)
        elif kind is DocumentKind.MAP and self.world is not None:
            self.world.set_map_tree(None if doc is None else doc.tree)  # the walls the body and sensors meet

    def load_document(self, kind: DocumentKind, startup: bool = False) -> Outcome:
        """Load the stored document of ``kind``; a bad one is refused and the active one stays."""
        try:
            self.documents.load(kind)
        except (StorageError, DocumentError) as exc:
            what = "not loaded" if startup else "load refused, the active one stays"
            return self.refuse(f"{kind.value} {what}: {exc}")
        self.activated(kind)
        self.log(logging.INFO, "load %s: %s", kind.value, self.storage.path(kind))
        return ACCEPTED


__all__ = ["ACCEPTED", "Outcome", "Platform", "State", "handler_names"]
