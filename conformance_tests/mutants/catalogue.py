"""The mutant catalogue: each mutant, what it breaks, and the case that must kill it.

Wire mutants are ``WireMutant`` subclasses (hooks of the frame proxy); model mutants name a patch function of
``patches.py`` that ``serve.py`` applies before the reference server starts.
"""

from __future__ import annotations

import socket
import struct
from dataclasses import dataclass
from typing import Any

from pltf.conformance_tests.mutants.proxy import Conn, FrameProxy
from pltf.spec.codec import REPLIES, REQUESTS, frame

_ID = {cls.NAME: cls.ID for cls in REQUESTS}


class WireMutant:
    """A faithful proxy; subclasses override the hooks they need."""

    wants_client_frames = False

    def on_accept(self, proxy: FrameProxy, index: int, client: socket.socket) -> bool:
        return False

    def client_bytes(self, proxy: FrameProxy, conn: Conn, data: bytes) -> bytes:
        return data

    def client_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        conn.to_server(data)

    def malformed(self, proxy: FrameProxy, conn: Conn, data: bytes) -> bool:
        return False

    def server_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        conn.to_client(data)

    def on_client_eof(self, proxy: FrameProxy, conn: Conn, pending: bytes) -> bool:
        return False


def _ident(data: bytes) -> int:
    return data[8] if len(data) > 8 else -1


class ReplyRewrite(WireMutant):
    """Rewrite the data of the replies to one request."""

    def __init__(self, name: str, rewrite: Any) -> None:
        self.id, self.rewrite = _ID[name], rewrite

    def server_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        conn.to_client(frame(self.rewrite(data[8:])) if _ident(data) == self.id else data)


class DropRequest(WireMutant):
    """The server never sees request ``name`` (a command ignored, or a GET never answered: a hang)."""

    wants_client_frames = True

    def __init__(self, name: str) -> None:
        self.id = _ID[name]

    def client_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        if _ident(data) != self.id:
            conn.to_server(data)


class CloseOn(WireMutant):
    """The connection drops when the client sends request ``name``."""

    wants_client_frames = True

    def __init__(self, name: str) -> None:
        self.id = _ID[name]

    def client_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        if _ident(data) == self.id:
            conn.close()
        else:
            conn.to_server(data)


class RewriteRequest(WireMutant):
    wants_client_frames = True

    def __init__(self, name: str, rewrite: Any) -> None:
        self.id, self.rewrite = _ID[name], rewrite

    def client_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        conn.to_server(frame(self.rewrite(data[8:])) if _ident(data) == self.id else data)


class AckCommands(WireMutant):
    """Every command that has no reply table is acknowledged with an echo of its identifier."""

    wants_client_frames = True

    def client_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        conn.to_server(data)
        cls = REQUESTS.by_id.get(_ident(data))
        if cls is not None and not cls.DEF.answered:
            conn.to_client(frame(bytes([_ident(data)])))


class SkipMalformed(WireMutant):
    """Bytes that are not a frame are skipped instead of closing the connection (E-WIRE-006 alternative)."""

    wants_client_frames = True

    def malformed(self, proxy: FrameProxy, conn: Conn, data: bytes) -> bool:
        return data[:4] != b"\xff\x01\xfe\x02"


class WaitOnHugeLength(WireMutant):
    """A frame over the maximum length is swallowed and the connection kept open (E-WIRE-004 alternative)."""

    wants_client_frames = True

    def malformed(self, proxy: FrameProxy, conn: Conn, data: bytes) -> bool:
        return data[:4] == b"\xff\x01\xfe\x02"


class DropSplitFrames(WireMutant):
    """A frame that arrived in more than one piece is lost."""

    wants_client_frames = True

    def client_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        if conn.state.get("chunks", 1) <= 1:
            conn.to_server(data)


class FirstFrameOnly(WireMutant):
    """Of the frames that arrive in one piece only the first is executed."""

    wants_client_frames = True

    def client_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        if conn.state.get("done") == conn.state.get("recv"):
            return
        conn.state["done"] = conn.state.get("recv")
        conn.to_server(data)


class KeepSecondClient(WireMutant):
    """A second client on a busy port is accepted and left open, never served (E-WIRE-007 alternative)."""

    def on_accept(self, proxy: FrameProxy, index: int, client: socket.socket) -> bool:
        if proxy.open_on(index) == 0:
            return False
        proxy.held.append(client)
        return True


class StaleMap(WireMutant):
    """CMD_GET_MAP always returns the first map it ever returned."""

    def server_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        if _ident(data) == _ID["CMD_GET_MAP"]:
            data = proxy.shared.setdefault("first_map", data)
        conn.to_client(data)


def _status_field(data: bytes, name: str, new_type: str) -> bytes:
    """Re-encode a GET_STATUS reply with one field in another wire type (an alternative reading's layout)."""
    import dataclasses

    from pltf.spec.compiler import compile_telegram

    t = REPLIES.decode_data(data)
    tdef = t.DEF
    layout = tuple(dataclasses.replace(f, type=new_type, enum=None) if f.name == name else f for f in tdef.reply or ())
    cls, _dec, enc = compile_telegram(dataclasses.replace(tdef, reply=layout), "reply")
    return enc(cls._make(tuple(t)))  # type: ignore[attr-defined]


def _swap_position_ints(data: bytes) -> bytes:
    x, y = struct.unpack_from(">ii", data, 1)
    return data[:1] + struct.pack("<ii", x, y) + data[9:]


def _position_degrees(data: bytes) -> bytes:
    import math

    (a,) = struct.unpack_from(">d", data, 9)
    return data[:9] + struct.pack(">d", math.degrees(a)) + data[17:]


def _vec_count_plus_one(data: bytes) -> bytes:
    (n,) = struct.unpack_from(">i", data, 1)
    return data[:1] + struct.pack(">i", n + 1) + data[5:]


def _mode_zero(data: bytes) -> bytes:
    t = REPLIES.decode_data(data)
    return REPLIES.encode_data(t.replace(motion_mode=0))


def _move_abs_off(data: bytes) -> bytes:
    x, y, a = struct.unpack_from(">iii", data, 1)
    return data[:1] + struct.pack(">iii", x, y + 300, a)


class AnswerCommand(WireMutant):
    """Command ``name`` (one without a reply table) is answered with an echo frame."""

    wants_client_frames = True

    def __init__(self, name: str) -> None:
        self.id = _ID[name]

    def client_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        conn.to_server(data)
        if _ident(data) == self.id:
            conn.to_client(frame(bytes([self.id])))


class IgnoreUndecodable(WireMutant):
    """A frame that does not decode as a request is dropped and the connection kept (E-WIRE-006 alternative)."""

    wants_client_frames = True

    def client_frame(self, proxy: FrameProxy, conn: Conn, data: bytes) -> None:
        from pltf.spec.errors import RemoteProtocolError

        try:
            REQUESTS.decode_data(data[8:])
        except RemoteProtocolError:
            return
        conn.to_server(data)


class IgnoreHalfClose(WireMutant):
    """The client's half-close is not passed on: the connection stays open with its partial frame."""

    def on_client_eof(self, proxy: FrameProxy, conn: Conn, pending: bytes) -> bool:
        return True


class CloseOnHalfClose(WireMutant):
    """The client's half-close drops the connection at once, pending replies included."""

    def on_client_eof(self, proxy: FrameProxy, conn: Conn, pending: bytes) -> bool:
        conn.close()
        return True


class ClosePort(WireMutant):
    """Every client of port ``index`` is closed at once."""

    def __init__(self, index: int) -> None:
        self.index = index

    def on_accept(self, proxy: FrameProxy, index: int, client: socket.socket) -> bool:
        if index != self.index:
            return False
        client.close()
        return True


class RefuseReconnect(WireMutant):
    """A port takes one client in its life; later ones are closed at once."""

    def on_accept(self, proxy: FrameProxy, index: int, client: socket.socket) -> bool:
        seen = proxy.shared.setdefault("accepted", set())
        if index in seen:
            client.close()
            return True
        seen.add(index)
        return False


class CloseAllOnMalformed(SkipMalformed):
    """Malformed input on one connection drops every connection (the other port's included)."""

    def malformed(self, proxy: FrameProxy, conn: Conn, data: bytes) -> bool:
        proxy.close_all()
        return True


def _truncate(data: bytes) -> bytes:
    return data[:-1]


def corrupt_reply(name: str) -> ReplyRewrite:
    """The reply to ``name`` loses its last byte (shorter than its layout)."""
    return ReplyRewrite(name, _truncate)


@dataclass(frozen=True)
class Mutant:
    id: str
    breaks: str  # what is broken, in words
    killer: str  # the case that must fail (FAIL, or NON-STRICT for a SHOULD requirement)
    wire: Any = None  # a WireMutant factory, or
    patch: str | None = None  # a patch of patches.py (model mutant)

    def make(self) -> WireMutant | None:
        return self.wire() if self.wire is not None else None


MUTANTS: tuple[Mutant, ...] = (
    # ---- wire mutants (proxy)
    Mutant(
        "reply-byte-order",
        "GET_POSITION sends x and y little-endian",
        "6.3/CMD_SET_FRM_PLTF/sets-estimate",
        wire=lambda: ReplyRewrite("CMD_GET_POSITION", _swap_position_ints),
    ),
    Mutant(
        "reply-wrong-count",
        "GET_PLTF_PARAM_VEC's count is one more than the entries",
        "6.4/CMD_GET_PLTF_PARAM_VEC/strict-decode",
        wire=lambda: ReplyRewrite("CMD_GET_PLTF_PARAM_VEC", _vec_count_plus_one),
    ),
    Mutant(
        "status-trailing-byte",
        "GET_STATUS carries one byte after the head drive position",
        "6.4/CMD_GET_STATUS/strict-decode",
        wire=lambda: ReplyRewrite("CMD_GET_STATUS", lambda d: d + b"\x00"),
    ),
    Mutant(
        "status-emergency-byte",
        "GET_STATUS sends the emergency state as a BYTE (E-REP-009 alternative)",
        "6.4/CMD_GET_STATUS/strict-decode",
        wire=lambda: ReplyRewrite("CMD_GET_STATUS", lambda d: _status_field(d, "emergency_state", "BYTE")),
    ),
    Mutant(
        "position-in-degrees",
        "GET_POSITION's angle is in degrees (E-REP-012 alternative)",
        "6.4/CMD_GET_POSITION/agrees-with-status",
        wire=lambda: ReplyRewrite("CMD_GET_POSITION", _position_degrees),
    ),
    Mutant(
        "mode-not-reported",
        "GET_STATUS always reports MODE_MOTION_NO",
        "6.3/CMD_SET_MODE/every-mode",
        wire=lambda: ReplyRewrite("CMD_GET_STATUS", _mode_zero),
    ),
    Mutant(
        "hang-on-debug-data",
        "GET_DEBUG_DATA is never answered (a hang)",
        "6.4/CMD_GET_DEBUG_DATA/strict-decode",
        wire=lambda: DropRequest("CMD_GET_DEBUG_DATA"),
    ),
    Mutant(
        "drop-connection-on-camera",
        "the connection drops on GET_CAMERA",
        "6.4/CMD_GET_CAMERA/strict-decode",
        wire=lambda: CloseOn("CMD_GET_CAMERA"),
    ),
    Mutant(
        "parameter-not-stored",
        "CMD_SET_PLTF_PARAM is ignored",
        "6.3/CMD_SET_PLTF_PARAM/round-trip",
        wire=lambda: DropRequest("CMD_SET_PLTF_PARAM"),
    ),
    Mutant(
        "close-socket-ignored",
        "CMD_CLOSE_SOCKET does not close",
        "6.3/CMD_CLOSE_SOCKET/closes",
        wire=lambda: DropRequest("CMD_CLOSE_SOCKET"),
    ),
    Mutant(
        "commands-acknowledged",
        "every command is answered with an echo frame",
        "6.1/replies/only-on-request",
        wire=AckCommands,
    ),
    Mutant(
        "bad-header-skipped",
        "bytes without the header are skipped, the connection stays open",
        "6.2/framing/bad-header",
        wire=SkipMalformed,
    ),
    Mutant(
        "huge-length-waits",
        "a frame of length 2^32-1 is waited for, the connection stays open",
        "6.2/framing/huge-length",
        wire=WaitOnHugeLength,
    ),
    Mutant(
        "split-frames-lost",
        "a frame that arrives in two pieces is lost",
        "6.2/framing/split-every-offset",
        wire=DropSplitFrames,
    ),
    Mutant(
        "coalesced-frames-lost",
        "of frames that arrive together only the first is executed",
        "6.2/framing/coalesced",
        wire=FirstFrameOnly,
    ),
    Mutant(
        "second-client-kept",
        "a second client on a busy port is accepted and left hanging",
        "6.1/ports/second-client-turned-away",
        wire=KeepSecondClient,
    ),
    Mutant("stale-map", "GET_MAP keeps returning the first map", "6.3/CMD_SET_MAP/round-trip", wire=StaleMap),
    Mutant(
        "move-abs-off-target",
        "CMD_MOVE_ABS drives 300 mm off in y",
        "4.3/MODE_MOTION_AUTOMATIC/move-abs",
        wire=lambda: RewriteRequest("CMD_MOVE_ABS", _move_abs_off),
    ),
    Mutant(
        "set-frame-ignored",
        "CMD_SET_FRM_PLTF is ignored",
        "6.3/CMD_SET_FRM_PLTF/sets-estimate",
        wire=lambda: DropRequest("CMD_SET_FRM_PLTF"),
    ),
    # ---- model mutants (patched reference server)
    Mutant(
        "set-mode-in-running",
        "CMD_SET_MODE is accepted in Running",
        "6.3/CMD_SET_MODE/in-running",
        patch="set_mode_anywhere",
    ),
    Mutant(
        "start-before-init",
        "CMD_START is accepted in Connected (before CMD_INIT_PLTF)",
        "6.3/CMD_START/in-connected",
        patch="start_when_connected",
    ),
    Mutant(
        "break-ignored",
        "CMD_BREAK leaves the platform Running",
        "6.3/CMD_BREAK/in-running",
        patch="break_no_transition",
    ),
    Mutant(
        "shutdown-ignored",
        "CMD_SHUTDOWN_PLTF changes no state",
        "6.3/CMD_SHUTDOWN_PLTF/in-ready",
        patch="shutdown_no_transition",
    ),
    Mutant(
        "range-unchecked",
        "a parameter value out of range is stored",
        "6.3/CMD_SET_PLTF_PARAM/out-of-range-refused",
        patch="parameter_range_unchecked",
    ),
    Mutant(
        "invalid-document-accepted",
        "documents are not validated against the schema",
        "6.3/CMD_SET_MAP/invalid-refused",
        patch="documents_unvalidated",
    ),
    Mutant(
        "invalid-document-clears-active",
        "a refused document also clears the active one",
        "6.3/CMD_SET_ROADMAP/invalid-refused",
        patch="refusal_clears_active",
    ),
    Mutant(
        "save-not-written",
        "CMD_SAVE_* writes nothing",
        "6.3/CMD_SAVE_PROGRAM/load-round-trip",
        patch="save_does_nothing",
    ),
    Mutant(
        "stop-keeps-moving",
        "CMD_STOP leaves the drive's command running",
        "6.3/CMD_STOP/halts-motion",
        patch="stop_keeps_command",
    ),
    Mutant(
        "no-velocity-watchdog",
        "MODE_MOTION_VEL keeps the velocity forever",
        "4.3/MODE_MOTION_VEL/watchdog",
        patch="no_watchdog",
    ),
    Mutant(
        "moves-in-mode-no",
        "move commands act in every motion mode",
        "4.3/MODE_MOTION_NO/moves-ignored",
        patch="moves_in_every_mode",
    ),
    Mutant(
        "dies-on-bad-input",
        "the server process exits on malformed input",
        "6.2/framing/no-header",
        patch="die_on_malformed",
    ),
)

BY_ID = {m.id: m for m in MUTANTS}
