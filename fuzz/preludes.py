"""State preludes: the valid traffic that brings the target into a state of the chart ahead of a unit's cases,
so that what lies behind a state (Running, a motion mode) is fuzzed too. No sockets.

Rules:
- The plan (guide 4.2 figure 2, 6.3 CMD_SET_MODE) visits every operation state, and every motion mode where a
  mode applies, ``WINDOWS_PER_STATE`` windows each (mode-major, so every state comes early in a run).
- ``full(target)`` gets there from anywhere (STOP, SHUTDOWN, CONNECT, INIT, SET_MODE, START, BREAK): what a
  fresh target needs, and where the minimiser starts (it keeps the frames a fresh target needs).
- ``path(state, mode, target)`` is the shortest way from the state the target reported last, over ``CHART`` (the
  guide's transitions, as the conformance suite's oracle and the reference server read them; a command absent
  from a state changes nothing there). ST_OP_NOT_INITIALIZED stands for Not connected and Connected alike: read
  as Not connected (a CONNECT where connected changes nothing).
  An unknown state takes the full prelude. Forbidden commands (no ``--allow-motion``) are never on a path.
- A unit with a prelude carries a GET_STATUS after it (the *check*); its reply says whether the target got
  there (``reached``). Units get one when they are the first batch of a window, or a single about an
  operation or motion command (``STATEFUL``): in a batch the chart commands go last, so that a STOP drawn
  among the cases does not leave the rest of the batch outside the state.
- ``DOCUMENT_RESET`` makes tiny documents active and saved at each state switch and after a huge case, so that a
  huge saved document does not make every later LOAD_* dear; ``HARVEST`` asks the GET_* replies that feed later
  cases (``pltf.fuzz.knowledge``) every ``HARVEST_EVERY`` of those.
"""

from __future__ import annotations

import collections
import functools
from typing import Any

from pltf.fuzz.case import Case
from pltf.spec.codec import REQUESTS, encode
from pltf.spec.model import enum_classes, load_telegrams

MODES = sorted(int(v) for v in enum_classes()["MotionMode"])
OP: Any = enum_classes()["OperationState"]  # built from the spec at import: untyped for mypy
WINDOWS_PER_STATE = 4  # windows fuzzed in one (state, mode) before the plan moves on
HARVEST_EVERY = 4
Target = tuple[str, int | None]


def _enc(telegram: str, **fields: Any) -> bytes:
    return encode(REQUESTS[telegram](**fields))


_RESET = [_enc("CMD_STOP"), _enc("CMD_SHUTDOWN_PLTF")]
_UP = [*_RESET, _enc("CMD_CONNECT_TO_PLTF")]
_READY = [*_UP, _enc("CMD_INIT_PLTF")]
STATES: dict[str, tuple[int, list[bytes], bool]] = {
    # name: (reported ST_OP_*, prelude from anywhere, needs motion)
    "not_connected": (OP.ST_OP_NOT_INITIALIZED, _RESET, False),
    "connected": (OP.ST_OP_NOT_INITIALIZED, _UP, False),
    "ready": (OP.ST_OP_READY, _READY, False),
    "running": (OP.ST_OP_RUNNING, _READY, True),
    "breaked": (OP.ST_OP_BREAKED, _READY, True),
}
REPORTED = {
    OP.ST_OP_READY: "ready",
    OP.ST_OP_RUNNING: "running",
    OP.ST_OP_BREAKED: "breaked",
    OP.ST_OP_NOT_INITIALIZED: "not_connected",
}
CHART: dict[tuple[str, str], str] = {
    # guide 4.2: "The initialization process starts with the command CMD_CONNECT_CAN" (= CMD_CONNECT_TO_PLTF, E-CMD-002)
    ("not_connected", "CMD_CONNECT_TO_PLTF"): "connected",
    # guide 4.2: "The command CMD_INIT_CAN initializes all hardware components" (= CMD_INIT_PLTF)
    ("connected", "CMD_INIT_PLTF"): "ready",
    # guide 6.3 CMD_START: "The operation state changes into the state 'Moving'" (E-CMD-003: Running)
    ("ready", "CMD_START"): "running",
    # guide 6.3 CMD_BREAK: "... into the state 'Break'"; CMD_CONTINUE: "... into the state 'Moving'"
    ("running", "CMD_BREAK"): "breaked",
    ("breaked", "CMD_CONTINUE"): "running",
    # guide 6.3 CMD_STOP: "The operation state changes into the state 'Ready'"
    ("running", "CMD_STOP"): "ready",
    ("breaked", "CMD_STOP"): "ready",
    # guide 6.3 CMD_SHUTDOWN_PLTF: "Used to shutdown the CAN communication"
    **{(s, "CMD_SHUTDOWN_PLTF"): "not_connected" for s in ("connected", "ready", "running", "breaked")},
}
STATEFUL = frozenset(t.name for t in load_telegrams() if t.category in ("operation", "motion"))
CHART_IDS = frozenset(REQUESTS[cmd].ID for _, cmd in CHART) | {REQUESTS.CMD_SET_MODE.ID}
# Tiny valid documents made active and saved at every state switch: a huge (or merely real) document saved
# by an earlier case would otherwise make every later LOAD_* cost the target milliseconds for the rest of the run.
TINY = {
    "map": '<?xml version="1.0"?><map Version="1.0"><layer index="0"/></map>',
    "roadmap": '<?xml version="1.0"?><roadmap Version="1.0"><stations><station id="a" name="A"><point x="0" y="0"/>'
    '</station><station id="b" name="B"><point x="1000" y="0"/></station></stations>'
    '<edges><edge startstation="a" endstation="b"/></edges></roadmap>',
    "program": '<?xml version="1.0"?><program version="1.0"><task name="t"><log type="info" message="m"/></task>'
    "</program>",
}
DOCUMENT_RESET = [
    _enc("CMD_SET_MAP", name="fuzz.map", xml=TINY["map"]),
    _enc("CMD_SAVE_MAP"),
    _enc("CMD_SET_ROADMAP", name="fuzz.rm", xml=TINY["roadmap"]),
    _enc("CMD_SAVE_ROADMAP"),
    _enc("CMD_SET_PROGRAM", xml=TINY["program"]),
    _enc("CMD_SAVE_PROGRAM"),
]
HARVEST = [
    _enc(n)
    for n in (
        "CMD_GET_PLTF_PARAM_VEC",
        "CMD_GET_ROADMAP",
        "CMD_GET_MAP",
        "CMD_GET_PROGRAM",
        "CMD_GET_POSITION",
        "CMD_GET_CAMERA",
        "CMD_GET_DEBUG_DATA",
    )
]


def full(target: Target) -> list[bytes]:
    """The prelude that drives a target into ``target`` from any state."""
    name, mode = target
    frames = list(STATES[name][1])
    if mode is not None:
        frames.append(_enc("CMD_SET_MODE", mode=mode))
    if name in ("running", "breaked"):
        frames.append(_enc("CMD_START"))
    if name == "breaked":
        frames.append(_enc("CMD_BREAK"))
    return frames


@functools.cache
def _steps(start: str, goal: str, forbidden: frozenset[int]) -> tuple[str, ...] | None:
    """The chart commands of a shortest way from ``start`` to ``goal`` (breadth first), or None."""
    seen: dict[str, tuple[str, ...]] = {start: ()}
    todo = collections.deque([start])
    while todo:
        state = todo.popleft()
        if state == goal:
            return seen[state]
        for (s, cmd), t in CHART.items():
            if s == state and t not in seen and REQUESTS[cmd].ID not in forbidden:
                seen[t] = (*seen[state], cmd)
                todo.append(t)
    return None


def path(state: int | None, mode: int | None, target: Target, forbidden: frozenset[int]) -> list[bytes]:
    """The prelude from the reported ``state`` (ST_OP_*) and ``mode`` to ``target``; ``full`` when unknown."""
    return list(_path(state, mode, target, forbidden))


@functools.cache
def _path(state: int | None, mode: int | None, target: Target, forbidden: frozenset[int]) -> tuple[bytes, ...]:
    return tuple(_find_path(state, mode, target, forbidden))


def _find_path(state: int | None, mode: int | None, target: Target, forbidden: frozenset[int]) -> list[bytes]:
    name, want = target
    here = REPORTED.get(state) if state is not None else None
    if here is None:
        return full(target)
    if want is None or (mode == want and here in ("ready", "running", "breaked")):
        steps = _steps(here, name, forbidden)
        if steps is None:
            return full(target)
        return [_enc(c) for c in steps]
    to_ready, onwards = _steps(here, "ready", forbidden), _steps("ready", name, forbidden)
    if to_ready is None or onwards is None:
        return full(target)
    return [*(_enc(c) for c in to_ready), _enc("CMD_SET_MODE", mode=want), *(_enc(c) for c in onwards)]


def matches(target: Target, operation_state: int | None, motion_mode: int | None) -> bool:
    name, mode = target
    return operation_state == STATES[name][0] and (mode is None or motion_mode == mode)


def chart_last(cases: list[Case]) -> list[Case]:
    """The cases of a batch in their order, those that change the chart state (CONNECT ... STOP) last."""
    return sorted(cases, key=lambda c: bool(c.frames) and len(c.frames[0]) > 8 and c.frames[0][8] in CHART_IDS)


class StatePlan:
    """Targets (state, mode) visited in turn; mode None where no mode applies."""

    def __init__(self, allow_motion: bool) -> None:
        self.targets: list[Target] = [("not_connected", None), ("connected", None)]
        for mode in MODES:  # mode-major, so that every state is visited early in a run
            for name, (_, _, motion) in STATES.items():
                if name not in ("not_connected", "connected") and (allow_motion or not motion):
                    self.targets.append((name, mode))
        self.index = 0
        self.windows = 0  # windows fuzzed in the current target
        self.reached: set[Target] = set()
        self.documents_due = True  # the next prelude installs the tiny documents
        self.resets = 0

    @property
    def current(self) -> Target:
        return self.targets[self.index % len(self.targets)]

    def advance(self) -> None:
        self.index += 1
        self.windows = 0
        self.documents_due = True

    def window_done(self, huge: bool) -> None:
        """A window ran; ``huge``: it had a case over 1 MiB (its document may now be saved and active)."""
        self.windows += 1
        self.documents_due = self.documents_due or huge
        if self.windows >= WINDOWS_PER_STATE:
            self.advance()

    def prelude(self, state: int | None, mode: int | None, forbidden: frozenset[int]) -> list[bytes]:
        """The frames ahead of the next window's first batch: documents when due, then the way to the target."""
        frames: list[bytes] = []
        if self.documents_due:
            self.documents_due = False
            self.resets += 1
            frames = DOCUMENT_RESET + (HARVEST if self.resets % HARVEST_EVERY == 1 else [])
        return frames + path(state, mode, self.current, forbidden)

    @staticmethod
    def full(target: Target) -> list[bytes]:
        return full(target)

    def check(self, target: Target, operation_state: int | None, motion_mode: int | None) -> bool:
        """Whether a status after a prelude to ``target`` shows it reached; recorded in ``reached``."""
        if matches(target, operation_state, motion_mode):
            self.reached.add(target)
            return True
        return False
