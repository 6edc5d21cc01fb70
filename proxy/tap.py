"""Live decoding of one direction of one proxied connection (sans-IO: bytes and ``now`` in, records out).

Rules:
- The proxy forwards bytes before it shows them to the tap; nothing the tap finds changes what is forwarded.
- Framing follows the codec (guide 6.2, spec/codec.py): header FF 01 FE 02, a uint32 length over the maximum
  (erratum E-WIRE-004) refused before anything is buffered for it. Each frame's data is then decoded on its own,
  so a frame that is framed correctly but does not decode (unknown identifier, value out of range, bytes left
  over) is recorded with its error and the next frame decodes again.
- A framing error (a bad header, a length over the maximum) loses the frame boundaries: the bytes from there on
  are recorded raw and marked, chunk by chunk, and nothing is guessed (no search for the next header: it could
  sit inside a string). The end of the stream inside a frame marks the partial frame Truncated.
- Decoding is a function of the direction and the frame's bytes: the result for a short frame is kept
  (``MEMO_FRAMES`` of them, at most ``MEMO_BYTES`` each), so a poller's identical requests and unchanged
  replies are decoded once.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from pltf.spec import errors
from pltf.spec.codec import DEFAULT_MAX_LENGTH, FRAME_OVERHEAD, HEADER, telegram_set
from pltf.spec.model import Direction
from pltf.spec.telegram import Telegram

_LENGTH = struct.Struct(">I")
MEMO_FRAMES = 4096  # decoded frames kept per direction (the memo is emptied when it is full)
MEMO_BYTES = 512  # longer frames are decoded every time
_MEMO: dict[Direction, dict[bytes, tuple[Telegram | None, str | None]]] = {"request": {}, "reply": {}}

# Record kinds
FRAME = "frame"  # one frame: a telegram, or a frame marked with its error
RAW = "raw"  # bytes that are no frame (after a framing error), marked
OPEN, CLOSE = "open", "close"  # connection events


@dataclass(frozen=True)
class Record:
    """One line of the session: a frame, marked raw bytes, or a connection event."""

    time: float
    conn: int  # connection number, from 1, in the order the proxy accepted them
    port: int  # the target's port
    kind: str
    direction: Direction | None = None  # request: client -> target; reply: target -> client
    raw: bytes = b""
    telegram: Telegram | None = None
    error: str | None = None  # "<error class>: <reason>" when the bytes are malformed
    detail: str = ""  # events: the peer's address, who closed and why

    @property
    def name(self) -> str:
        """The telegram's name, or what stands in for it in a view."""
        if self.telegram is not None:
            return self.telegram.NAME
        if self.kind in (OPEN, CLOSE):
            return self.kind
        return "malformed"


def _describe(exc: errors.RemoteProtocolError) -> str:
    return f"{type(exc).__name__}: {exc}"


class Tap:
    """Decodes one direction of a connection; ``feed`` and ``end`` return the records the bytes made."""

    def __init__(self, direction: Direction, conn: int, port: int, max_length: int = DEFAULT_MAX_LENGTH) -> None:
        self.direction = direction
        self.conn, self.port = conn, port
        self.max_length = max_length
        self._set = telegram_set(direction)
        self._buf = bytearray()
        self._pos = 0  # start of the first frame not yet decoded (during ``feed``)
        self.out_of_sync: str | None = None  # the framing error that lost the boundaries
        self.frames = 0

    def _record(
        self, now: float, raw: bytes, telegram: Telegram | None = None, error: str | None = None, kind: str = FRAME
    ) -> Record:
        return Record(now, self.conn, self.port, kind, self.direction, raw, telegram, error)

    def feed(self, data: bytes, now: float) -> list[Record]:
        if not data:
            return []
        if self.out_of_sync is not None:
            return [self._record(now, bytes(data), error=f"OutOfSync: after {self.out_of_sync}", kind=RAW)]
        self._buf += data
        out: list[Record] = []
        while (rec := self._next(now)) is not None:
            out.append(rec)
        del self._buf[: self._pos]  # once per chunk, not once per frame
        self._pos = 0
        return out

    def end(self, now: float) -> list[Record]:
        """The end of the stream: a partial frame left over is marked Truncated."""
        if self.out_of_sync is not None or not self._buf:
            return []
        rest = bytes(self._buf)
        self._buf.clear()
        if len(rest) < FRAME_OVERHEAD:
            why = f"stream ended inside a frame header ({len(rest)} bytes)"
        else:
            need = FRAME_OVERHEAD + _LENGTH.unpack_from(rest, 4)[0]
            why = f"stream ended inside a frame: {len(rest)} of {need} bytes"
        return [self._record(now, rest, error=f"Truncated: {why}")]

    def _lose_sync(self, now: float, exc: errors.RemoteProtocolError) -> Record:
        self.out_of_sync = type(exc).__name__
        rest = bytes(self._buf[self._pos :])
        self._buf.clear()
        self._pos = 0
        return self._record(now, rest, error=_describe(exc), kind=RAW)

    def _next(self, now: float) -> Record | None:
        buf, pos = self._buf, self._pos
        avail = len(buf) - pos
        if not avail:
            return None
        head = bytes(buf[pos : pos + 4])
        if not HEADER.startswith(head):
            return self._lose_sync(now, errors.BadHeader(f"bad header {head.hex()} (expected ff01fe02)"))
        if avail < FRAME_OVERHEAD:
            return None
        (length,) = _LENGTH.unpack_from(buf, pos + 4)
        if length > self.max_length:
            return self._lose_sync(
                now, errors.FrameTooLarge(f"frame length {length} over the maximum {self.max_length}")
            )
        if avail < FRAME_OVERHEAD + length:
            return None
        end = pos + FRAME_OVERHEAD + length
        raw = bytes(buf[pos:end])
        self._pos = end
        self.frames += 1
        telegram, error = self._decode(raw)
        return self._record(now, raw, telegram, error)

    def _decode(self, raw: bytes) -> tuple[Telegram | None, str | None]:
        memo = _MEMO[self.direction]
        found = memo.get(raw)
        if found is not None:
            return found
        try:
            found = (self._set.decode_data(raw[FRAME_OVERHEAD:]), None)
        except errors.RemoteProtocolError as exc:
            found = (None, _describe(exc))
        if len(raw) <= MEMO_BYTES:
            if len(memo) >= MEMO_FRAMES:
                memo.clear()
            memo[raw] = found
        return found
