"""The suite's own oracle of the operation state chart (guide 4.2 figure 2, 6.3, and the project's decisions).

Rules:
- This table is the suite's, written from the guide, not imported from the reference server: a conformance
  suite that took its oracle from the implementation it checks would check nothing.
- ``TRANSITIONS[(state, command)]`` is the state an allowed command leads to; a pair that is absent means the
  command is not allowed in that state and must change nothing. SET_MODE is a self-loop of Ready that changes
  the motion mode.
- Not connected and Connected (CAN up, not initialized) both report ST_OP_NOT_INITIALIZED with initialized 0;
  the suite tells them apart by what CMD_INIT_PLTF does next.
- ``GUIDE`` marks the cells the guide itself states (graded MUST); every other cell is a project decision on
  what figure 2 leaves to the reader, recorded in the errata register: ``DECIDED_BY`` names its erratum, whose
  level grades the cell. Each cell is in exactly one of the two (a test checks it).
"""

from __future__ import annotations

import enum
from typing import Any

from pltf.spec.model import enum_classes

# The spec's enums are built at import; mypy sees them as plain IntEnum classes without members.
OperationState: Any = enum_classes()["OperationState"]
MotionMode: Any = enum_classes()["MotionMode"]


class St(enum.Enum):
    NOT_CONNECTED = "not-connected"
    CONNECTED = "connected"
    READY = "ready"
    RUNNING = "running"
    BREAKED = "breaked"


REPORTED: dict[St, int] = {
    St.NOT_CONNECTED: OperationState.ST_OP_NOT_INITIALIZED,
    St.CONNECTED: OperationState.ST_OP_NOT_INITIALIZED,
    St.READY: OperationState.ST_OP_READY,
    St.RUNNING: OperationState.ST_OP_RUNNING,
    St.BREAKED: OperationState.ST_OP_BREAKED,
}
INITIALIZED: dict[St, int] = {s: int(s in (St.READY, St.RUNNING, St.BREAKED)) for s in St}

CHART_COMMANDS = (
    "CMD_CONNECT_TO_PLTF",
    "CMD_INIT_PLTF",
    "CMD_SHUTDOWN_PLTF",
    "CMD_START",
    "CMD_BREAK",
    "CMD_CONTINUE",
    "CMD_STOP",
    "CMD_SET_MODE",
)

_NC, _CO, _RD, _RU, _BR = St.NOT_CONNECTED, St.CONNECTED, St.READY, St.RUNNING, St.BREAKED

TRANSITIONS: dict[tuple[St, str], St] = {
    # guide 4.2: "The initialization process starts with the command CMD_CONNECT_CAN" (= CMD_CONNECT_TO_PLTF)
    (_NC, "CMD_CONNECT_TO_PLTF"): _CO,
    # guide 4.2: "The command CMD_INIT_CAN initializes all hardware components" (= CMD_INIT_PLTF)
    (_CO, "CMD_INIT_PLTF"): _RD,
    # guide 6.3 CMD_SHUTDOWN_PLTF: "Used to shutdown the CAN communication" - from every state with CAN up
    **{(s, "CMD_SHUTDOWN_PLTF"): _NC for s in (_CO, _RD, _RU, _BR)},
    # guide 6.3 CMD_START: "The operation state changes into the state 'Moving'" (4.2: from 'Initialized')
    (_RD, "CMD_START"): _RU,
    # guide 6.3 CMD_BREAK: "The operation state changes into the state 'Break'"
    (_RU, "CMD_BREAK"): _BR,
    # guide 6.3 CMD_CONTINUE: "Continue the execution ... The operation state changes into the state 'Moving'"
    (_BR, "CMD_CONTINUE"): _RU,
    # guide 6.3 CMD_STOP: "The operation state changes into the state 'Ready'"
    (_RU, "CMD_STOP"): _RD,
    (_BR, "CMD_STOP"): _RD,
    # guide 6.3 CMD_SET_MODE: "The operation state has to be in 'Ready' before changing to another motion mode"
    (_RD, "CMD_SET_MODE"): _RD,
}

# Cells the guide states in words (the rest are project decisions on figure 2, which the text version lacks).
GUIDE: set[tuple[St, str]] = {
    (_NC, "CMD_CONNECT_TO_PLTF"),
    (_CO, "CMD_INIT_PLTF"),
    (_RD, "CMD_START"),
    (_RU, "CMD_BREAK"),
    (_BR, "CMD_CONTINUE"),
    (_RU, "CMD_STOP"),
    (_BR, "CMD_STOP"),
    (_RD, "CMD_SET_MODE"),
    # SET_MODE outside Ready: "has to be in 'Ready'"
    (_NC, "CMD_SET_MODE"),
    (_CO, "CMD_SET_MODE"),
    (_RU, "CMD_SET_MODE"),
    (_BR, "CMD_SET_MODE"),
    # CMD_START before initialization: 4.2 "In the state 'Initialized' the platform can be started"
    (_NC, "CMD_START"),
    (_CO, "CMD_START"),
}


# The erratum (spec/errata/server.yaml) that decides each cell the guide does not state.
DECIDED_BY: dict[tuple[St, str], str] = {
    **{(s, "CMD_CONNECT_TO_PLTF"): "E-SRV-002" for s in (_CO, _RD, _RU, _BR)},
    **{(s, "CMD_INIT_PLTF"): "E-SRV-002" for s in (_NC, _RD, _RU, _BR)},
    **{(s, "CMD_SHUTDOWN_PLTF"): "E-SRV-003" for s in St},
    (_RD, "CMD_STOP"): "E-SRV-004",
    **{(s, "CMD_START"): "E-SRV-018" for s in (_RU, _BR)},
    **{(s, "CMD_BREAK"): "E-SRV-018" for s in (_NC, _CO, _RD, _BR)},
    **{(s, "CMD_CONTINUE"): "E-SRV-018" for s in (_NC, _CO, _RD, _RU)},
    **{(s, "CMD_STOP"): "E-SRV-018" for s in (_NC, _CO)},
}


def allowed(state: St, command: str) -> bool:
    return (state, command) in TRANSITIONS


def target(state: St, command: str) -> St:
    """Where ``command`` leads from ``state`` (the state itself when it is not allowed)."""
    return TRANSITIONS.get((state, command), state)


def every_transition() -> list[tuple[St, str, St]]:
    """(from, command, to) for every cell of the chart, allowed or not: what the coverage report counts."""
    return [(s, c, target(s, c)) for s in St for c in CHART_COMMANDS]


# A path of commands from Ready to every state (the suite's "known state" routine uses it).
PATH_FROM_READY: dict[St, tuple[str, ...]] = {
    _RD: (),
    _RU: ("CMD_START",),
    _BR: ("CMD_START", "CMD_BREAK"),
    _NC: ("CMD_SHUTDOWN_PLTF",),
    _CO: ("CMD_SHUTDOWN_PLTF", "CMD_CONNECT_TO_PLTF"),
}
