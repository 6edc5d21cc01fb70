"""The operation state chart of guide 4.2 (figure 2) and the emergency-stop flag, as one table.

Rules:
- Everything that decides whether a command may run, and which operation state it leads to, lives in
  ``RULES`` below: one entry per telegram of the spec (a test checks that none is missing). Nothing else in
  the server branches on the operation state to accept or refuse a command.
- A refused command changes nothing; ``StateChart.check`` returns the reason, the caller logs it.
- The emergency stop is orthogonal to the operation state (guide 6.4 "Active emergency state"): while it is
  ACTIVE the commands marked ``blocked_by_emergency`` are refused. Pressing it brings Running/Breaked back
  to Ready (the platform model halts the motion); releasing it (= the safety system has been reset) reports
  ST_EM_RESET for ``EMERGENCY_RESET_TIME`` simulated seconds, then ST_EM_NOT_ACTIVE.
- A drive fault (the fake hardware's motors lost, absent or over-temperature, the CAN interface bus-off;
  erratum E-HW-025) is a second orthogonal flag with the same effect as the emergency stop: Running/Breaked
  fall back to Ready and the ``blocked_by_emergency`` commands are refused while it lasts; when its cause is
  gone the platform stays in Ready until a new CMD_START.
- Sans-IO: time comes in as ``now`` (simulated seconds).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Any

from pltf.spec.model import enum_classes

# The spec's enums are built at import; mypy sees them as plain IntEnum classes without members.
OperationState: Any = enum_classes()["OperationState"]
EmergencyState: Any = enum_classes()["EmergencyState"]

EMERGENCY_RESET_TIME = 1.0  # simulated s that ST_EM_RESET is reported after a release


class State(enum.Enum):
    """Internal operation states; ``NOT_CONNECTED`` and ``CONNECTED`` both report ST_OP_NOT_INITIALIZED."""

    NOT_CONNECTED = "not connected"  # CAN bus down (start-up, after CMD_SHUTDOWN_PLTF)
    CONNECTED = "connected"  # CAN nodes connected (CMD_CONNECT_TO_PLTF), not initialized
    READY = "ready"
    RUNNING = "running"
    BREAKED = "breaked"


REPORTED: dict[State, int] = {
    State.NOT_CONNECTED: OperationState.ST_OP_NOT_INITIALIZED,
    State.CONNECTED: OperationState.ST_OP_NOT_INITIALIZED,
    State.READY: OperationState.ST_OP_READY,
    State.RUNNING: OperationState.ST_OP_RUNNING,
    State.BREAKED: OperationState.ST_OP_BREAKED,
}


@dataclass(frozen=True)
class Rule:
    """Where a command is allowed and where it leads (``target`` None: the state does not change)."""

    allowed: frozenset[State]
    target: State | None = None
    blocked_by_emergency: bool = False


ANY = frozenset(State)
CAN_UP = frozenset({State.CONNECTED, State.READY, State.RUNNING, State.BREAKED})
_NC, _CO, _RD, _RU, _BR = State

_ANYWHERE = Rule(ANY)
_ON_CAN = Rule(CAN_UP)
# guide 4.2: "A movement of the platform is only possible in the state 'Running'"; 4.3 decides per mode
# whether it has an effect.
_MOVE = Rule(frozenset({_RU}), blocked_by_emergency=True)

# fmt: off
_DATA_COMMANDS = (
    "CMD_SET_MAP", "CMD_GET_MAP", "CMD_LOAD_MAP", "CMD_SAVE_MAP",
    "CMD_MAPPING_START", "CMD_MAPPING_RESET", "CMD_MAPPING_STOP",
    "CMD_SET_ROADMAP", "CMD_GET_ROADMAP", "CMD_LOAD_ROADMAP", "CMD_SAVE_ROADMAP",
    "CMD_SET_FRM_PLTF", "CMD_SET_PLTF_PARAM", "CMD_GET_PLTF_PARAM", "CMD_GET_PLTF_PARAM_VEC",
    "CMD_SET_PROGRAM", "CMD_GET_PROGRAM", "CMD_LOAD_PROGRAM", "CMD_SAVE_PROGRAM",
)
_DEBUG_COMMANDS = (
    "CMD_GET_DEBUG_DATA", "CMD_DEBUG1", "CMD_DEBUG2", "CMD_DEBUG3", "CMD_DEBUG4", "CMD_MOUSE_MOVE",
    "CMD_SET_LOG_ENABLED", "CMD_SET_POST_PROCESS_FILENAME", "CMD_SET_EVENT", "CMD_GET_CAMERA",
    # identifiers known only from field code (field-evidence.md), layouts unknown
    "CMD_GET_MAPIMAGE", "CMD_ENABLE_EXT_MAPPING", "CMD_DISABLE_EXT_MAPPING", "CMD_EXT_WRITE_MAPPING",
    "CMD_EXT_READ_MAPPING", "CMD_WRITE_LCD", "CMD_STOP_MOTIONTHREAD", "CMD_RESTART_MOTIONTHREAD",
    "CMD_SHUTDOWN_HOST",
)
# fmt: on

RULES: dict[str, Rule] = {
    # ---- CAN communication (6.3)
    # guide 4.2: "The initialization process starts with the command CMD_CONNECT_CAN" (= CMD_CONNECT_TO_PLTF)
    "CMD_CONNECT_TO_PLTF": Rule(frozenset({_NC}), _CO),
    # guide 6.3: "Used to shutdown the CAN communication"; the platform model stops the motion first.
    "CMD_SHUTDOWN_PLTF": Rule(CAN_UP, _NC),
    # guide 4.2: "CMD_INIT_CAN initializes all hardware components" (= CMD_INIT_PLTF): needs the CAN bus.
    "CMD_INIT_PLTF": Rule(frozenset({_CO}), _RD),
    # The board commands talk to CAN nodes: they need CMD_CONNECT_TO_PLTF, not the self test.
    "CMD_SET_BRAKE": _ON_CAN,
    "CMD_SET_DIGOUT": _ON_CAN,
    "CMD_START_ULTRASONIC": _ON_CAN,
    "CMD_STOP_ULTRASONIC": _ON_CAN,
    "CMD_ADD_CAN_LISTENING_ID": _ON_CAN,
    "CMD_REMOVE_CAN_LISTENING_ID": _ON_CAN,
    "CMD_SEND_CAN_MESSAGE": _ON_CAN,
    "CMD_GET_CAN_MESSAGES": _ANYWHERE,  # a GET_* is always answered (guide 6.1); empty when the bus is down
    # ---- platform operation (6.3, 4.2 figure 2)
    # guide 4.2: "In the state 'Initialized' the platform can be started, stopped, paused or made to continue"
    "CMD_START": Rule(frozenset({_RD}), _RU, blocked_by_emergency=True),
    "CMD_BREAK": Rule(frozenset({_RU}), _BR),
    "CMD_CONTINUE": Rule(frozenset({_BR}), _RU, blocked_by_emergency=True),
    # guide 6.3 CMD_STOP: "The operation state changes into the state 'Ready'"
    "CMD_STOP": Rule(frozenset({_RU, _BR}), _RD),
    # guide 6.3 CMD_SET_MODE: "The operation state has to be in 'Ready' before changing to another motion mode"
    "CMD_SET_MODE": Rule(frozenset({_RD})),
    "CMD_EXIT": _ANYWHERE,
    "CMD_CLOSE_SOCKET": _ANYWHERE,
    # ---- request status (6.3)
    "CMD_GET_STATUS": _ANYWHERE,
    "CMD_GET_POSITION": _ANYWHERE,
    # ---- motion (6.3, 4.3)
    "CMD_MOVE_PATH": _MOVE,
    "CMD_MOVE_TO_STATION": _MOVE,
    "CMD_MOVE_ABS": _MOVE,
    "CMD_MOVE_REL": _MOVE,
    # guide 6.3 CMD_MOVE_VEL_WHEEL: "The operation state has to be in 'Moving'"
    "CMD_MOVE_VEL_WHEEL": _MOVE,
    "CMD_MOVE_VEL": _MOVE,
    # ---- platform data (6.3): documents, pose and parameters are data, not motion: any state.
    # guide 5.3: "The platform can be shifted by drag and drop" (CMD_SET_FRM_PLTF) - no state is named.
    **dict.fromkeys(_DATA_COMMANDS, _ANYWHERE),
    # ---- special functions (6.3): speech, sound and camera are host devices, not CAN nodes.
    "CMD_SPEAK_TEXT": _ANYWHERE,
    "CMD_PLAY_SOUND": _ANYWHERE,
    "CMD_GRAB_IMAGE": _ANYWHERE,
    # The head drive is a motor on the CAN bus (like the wheel drives of CMD_SET_BRAKE).
    "CMD_SET_POS_HEAD_DRIVE": _ON_CAN,
    "CMD_SET_VEL_HEAD_DRIVE": _ON_CAN,
    "CMD_SET_POS_PAN_TILT_CAMERA": _ANYWHERE,
    # ---- debug (6.3) and the identifiers known only from field code: accepted anywhere; the platform
    # model logs those it does not implement.
    **dict.fromkeys(_DEBUG_COMMANDS, _ANYWHERE),
}


class StateChart:
    """The current operation state and emergency state; ``check`` then ``fire`` for each command."""

    def __init__(self) -> None:
        self.state = State.NOT_CONNECTED
        self.emergency: int = EmergencyState.ST_EM_NOT_ACTIVE
        self._reset_until: float | None = None
        self.drive_fault = False

    @property
    def operation_state(self) -> int:
        return REPORTED[self.state]

    @property
    def initialized(self) -> bool:
        return self.state in (State.READY, State.RUNNING, State.BREAKED)

    def check(self, name: str) -> str | None:
        """Why ``name`` is refused now, or None when it may run."""
        rule = RULES.get(name)
        if rule is None:
            return f"command {name} unknown to the state chart"
        if self.state not in rule.allowed:
            return f"command {name} not allowed in state {self.state.value}"
        if rule.blocked_by_emergency and self.emergency == EmergencyState.ST_EM_ACTIVE:
            return f"command {name} not allowed while the emergency stop is active"
        if rule.blocked_by_emergency and self.drive_fault:
            return f"command {name} not allowed during a drive fault"
        return None

    def fire(self, name: str) -> tuple[State, State]:
        """Apply an allowed command's transition; returns (old, new) state."""
        old = self.state
        target = RULES[name].target
        if target is not None:
            self.state = target
        return old, self.state

    def shutdown(self) -> None:
        """CMD_EXIT: the program ends; the CAN bus goes down with it."""
        self.state = State.NOT_CONNECTED

    # ---- emergency stop (guide 4.2: "If a hardware emergency stop occurs, the platform switches into a
    # secure state. After the safety system has been reset, the platform will enter the state 'Ready' again.")
    def press_emergency(self) -> tuple[State, State]:
        old = self.state
        self.emergency = EmergencyState.ST_EM_ACTIVE
        self._reset_until = None
        if self.state in (State.RUNNING, State.BREAKED):
            self.state = State.READY
        return old, self.state

    def enter_drive_fault(self) -> tuple[State, State]:
        """A drive fault (erratum E-HW-025): the secure state, as for the emergency stop."""
        old = self.state
        self.drive_fault = True
        if self.state in (State.RUNNING, State.BREAKED):
            self.state = State.READY
        return old, self.state

    def clear_drive_fault(self) -> None:
        self.drive_fault = False

    def release_emergency(self, now: float) -> bool:
        """The safety system has been reset; False when the emergency stop was not active."""
        if self.emergency != EmergencyState.ST_EM_ACTIVE:
            return False
        self.emergency = EmergencyState.ST_EM_RESET
        self._reset_until = now + EMERGENCY_RESET_TIME
        return True

    def tick(self, now: float) -> bool:
        """Advance the timed part (RESET -> NOT_ACTIVE); True when the emergency state changed."""
        if self._reset_until is not None and now >= self._reset_until:
            self._reset_until = None
            self.emergency = EmergencyState.ST_EM_NOT_ACTIVE
            return True
        return False
