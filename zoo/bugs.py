"""Planted bugs: what a zoo member does to a target on the requests it relays (sans-IO).

Rules:
- A bug sees every whole request frame a client sends, on any port, before the target behind does
  (``on_request(piece, now)``), and answers None (pass it on) or a ``Fault``: ``crash`` (the member dies with
  its target, exit status 134 like an abort) or ``hang`` (the member's one thread stops: no port answers,
  newcomers wait in the backlog).
- A bug's trigger depends only on the requests seen, in order, never on timing: a reproducer that replays the
  same requests to a fresh member triggers it again.
- ``PlatformView`` follows the operation state and the motion mode through the chart of guide 4.2 from the
  commands alone (a command the chart does not allow in the state changes nothing, as the target behind
  refuses it); it is the bug's picture of the platform, not a check of the target.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import Any, Protocol

from pltf.spec import errors
from pltf.spec.codec import REQUESTS, decode_frame
from pltf.spec.model import enum_classes
from pltf.spec.parameters import load_parameters
from pltf.zoo.frames import Piece

MotionMode: Any = enum_classes()["MotionMode"]  # built from the spec at import: untyped for mypy
ID = {t.NAME: t.ID for t in REQUESTS}
NAME = {v: k for k, v in ID.items()}

NC, CO, RD, RU, BR = "not connected", "connected", "ready", "running", "breaked"
# guide 4.2 figure 2 and 6.3: (state, command) -> next state; absent pairs change nothing
CHART: dict[tuple[str, str], str] = {
    (NC, "CMD_CONNECT_TO_PLTF"): CO,  # guide 4.2 "CMD_CONNECT_CAN" (erratum E-CMD-002)
    (CO, "CMD_INIT_PLTF"): RD,  # guide 4.2 "CMD_INIT_CAN initializes all hardware components"
    (RD, "CMD_START"): RU,  # guide 6.3 CMD_START: into the state "Moving"
    (RU, "CMD_BREAK"): BR,
    (BR, "CMD_CONTINUE"): RU,
    (RU, "CMD_STOP"): RD,
    (BR, "CMD_STOP"): RD,
    **{(s, "CMD_SHUTDOWN_PLTF"): NC for s in (CO, RD, RU, BR)},  # guide 6.3: "shutdown the CAN communication"
}
PATH_MOVES = ("CMD_MOVE_ABS", "CMD_MOVE_REL", "CMD_MOVE_PATH", "CMD_MOVE_TO_STATION")


@dataclass(frozen=True)
class Fault:
    kind: str  # "crash" or "hang"
    why: str


class Bug(Protocol):
    def on_request(self, piece: Piece, now: float) -> Fault | None: ...


def _decoded_field(piece: Piece, name: str) -> object:
    try:
        return getattr(decode_frame(piece.data, "request"), name)
    except errors.ProtocolError:
        return None


@dataclass
class PlatformView:
    state: str = NC
    mode: int = MotionMode.MODE_MOTION_NO

    def on_request(self, name: str, piece: Piece) -> None:
        if name == "CMD_SET_MODE":
            mode = _decoded_field(piece, "mode")
            if self.state == RD and isinstance(mode, int):  # guide 6.3 CMD_SET_MODE: only in 'Ready'
                self.mode = mode
            return
        self.state = CHART.get((self.state, name), self.state)


@dataclass
class CrashAfterStart:
    """A path command (MOVE_ABS, MOVE_REL, MOVE_PATH, MOVE_TO_STATION) in Running while the motion mode is not
    Automatic reaches a planner that only mode Automatic creates: a null pointer, the process dies. It needs the
    prelude CONNECT_TO_PLTF, INIT_PLTF, START (in a mode other than Automatic)."""

    view: PlatformView = field(default_factory=PlatformView)

    def on_request(self, piece: Piece, now: float) -> Fault | None:
        name = NAME.get(-1 if piece.ident is None else piece.ident, "")
        if name in PATH_MOVES and self.view.state == RU and self.view.mode != MotionMode.MODE_MOTION_AUTOMATIC:
            mode = MotionMode(self.view.mode).name if self.view.mode in MotionMode._value2member_map_ else "unknown"
            return Fault("crash", f"{name} in running, motion mode {mode}: the planner of mode Automatic is null")
        self.view.on_request(name, piece)
        return None


@dataclass
class CrashInVelocityMode:
    """CMD_MOVE_VEL_WHEEL in Running, motion mode VEL, with a wheel velocity at or below -2^30 mm/s overflows the
    wheel controller's set point (a signed 32-bit product): the process dies. It needs the prelude
    CONNECT_TO_PLTF, INIT_PLTF, SET_MODE VEL, START - the mode set in Ready, before START."""

    view: PlatformView = field(default_factory=PlatformView)

    def on_request(self, piece: Piece, now: float) -> Fault | None:
        name = NAME.get(-1 if piece.ident is None else piece.ident, "")
        if name == "CMD_MOVE_VEL_WHEEL" and self.view.state == RU and self.view.mode == MotionMode.MODE_MOTION_VEL:
            speeds = [_decoded_field(piece, f) for f in ("vel_right", "vel_left")]
            if any(isinstance(v, int) and v <= -(1 << 30) for v in speeds):
                return Fault("crash", f"CMD_MOVE_VEL_WHEEL {speeds} in running, mode VEL: the set point overflows")
        self.view.on_request(name, piece)
        return None


@dataclass
class HangOnUnknownKey:
    """CMD_SET_PLTF_PARAM with a key the parameter table does not have sends the lookup into an endless loop: the
    whole target stops answering (every port; newcomers wait in the backlog)."""

    keys: frozenset[str] = field(default_factory=lambda: frozenset(load_parameters()))

    def on_request(self, piece: Piece, now: float) -> Fault | None:
        if piece.ident != ID["CMD_SET_PLTF_PARAM"]:
            return None
        key = _decoded_field(piece, "key")
        if isinstance(key, str) and key not in self.keys:
            return Fault("hang", f"CMD_SET_PLTF_PARAM with the unknown key {key[:40]!r}: the lookup never ends")
        return None


@dataclass
class Leak:
    """Every request leaks ``kb`` KiB (a buffer nobody frees, really allocated); when the leak reaches ``limit_mb``
    MiB the target runs out of memory and dies. With the defaults: after 2,048 requests."""

    kb: int = 32
    limit_mb: int = 64
    kept: list[bytearray] = field(default_factory=list)
    requests: int = 0

    @property
    def leaked(self) -> int:
        return sum(len(b) for b in self.kept)

    def on_request(self, piece: Piece, now: float) -> Fault | None:
        self.requests += 1
        block = bytearray(self.kb * 1024)
        struct.pack_into(">I", block, 0, self.requests)  # touched: the pages are really taken
        block[-1] = 1
        self.kept.append(block)
        if self.leaked >= self.limit_mb * 1024 * 1024:
            return Fault("crash", f"out of memory: {self.leaked >> 20} MiB leaked after {self.requests} requests")
        return None


# the planted bugs by name: a member's own, or any of them on a member's wire behaviour (``python -m pltf.zoo
# slow-release --bug crash-after-start``: a crash behind a proxy that turns newcomers away)
BUGS: dict[str, type[Bug]] = {
    "crash-after-start": CrashAfterStart,
    "crash-in-velocity-mode": CrashInVelocityMode,
    "hang-unknown-key": HangOnUnknownKey,
    "leak": Leak,
}
