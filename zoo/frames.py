"""Cut a byte stream into frames (guide 6.2) without judging it: what the zoo's relays need.

Rules:
- A frame is the header FF 01 FE 02, a big-endian uint32 N and N data bytes; ``FrameCutter.feed`` returns the
  complete frames in order, each whole (header included), and keeps a partial one for the next call.
- A stream that is not in step (no header where one belongs, a length over the codec's maximum) is not ours to
  judge: from there on everything is returned as raw chunks (``Piece.frame`` False), in order, so a relay
  passes the peer's bytes on unchanged and the target behind decides what they mean.
- Nothing here touches a socket or a clock.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from pltf.spec import errors
from pltf.spec.codec import DEFAULT_MAX_LENGTH, HEADER, decode_frame

_LEN = struct.Struct(">I")
OVERHEAD = 8


@dataclass(frozen=True)
class Piece:
    data: bytes
    frame: bool  # a whole frame (header, length, data); False: raw bytes of a stream out of step

    @property
    def ident(self) -> int | None:
        """The telegram identifier (first data byte) of a frame with data."""
        return self.data[OVERHEAD] if self.frame and len(self.data) > OVERHEAD else None


class FrameCutter:
    def __init__(self, max_length: int = DEFAULT_MAX_LENGTH) -> None:
        self.max_length = max_length
        self.in_step = True
        self._buf = bytearray()

    @property
    def pending(self) -> int:
        return len(self._buf)

    def feed(self, data: bytes) -> list[Piece]:
        if not self.in_step:
            return [Piece(bytes(data), False)] if data else []
        self._buf += data
        out: list[Piece] = []
        buf = self._buf
        while len(buf) >= OVERHEAD:
            if buf[:4] != HEADER:
                break
            (n,) = _LEN.unpack_from(buf, 4)
            if n > self.max_length:
                break
            if len(buf) < OVERHEAD + n:
                return out
            out.append(Piece(bytes(buf[: OVERHEAD + n]), True))
            del buf[: OVERHEAD + n]
        if buf and (len(buf) >= OVERHEAD or not HEADER.startswith(bytes(buf[:4]))):
            self.in_step = False
            out.append(Piece(bytes(buf), False))
            buf.clear()
        return out

    def flush(self) -> list[Piece]:
        """What is left at the end of the stream (a partial frame), as raw bytes."""
        if not self._buf:
            return []
        rest = Piece(bytes(self._buf), False)
        self._buf.clear()
        return [rest]


def well_formed(piece: Piece) -> bool:
    """Whether a piece is a whole request frame the codec decodes (a known command with its fields): what a strict
    member (matrix row 8) demands; raw bytes out of step, an unknown identifier or a bad field are not."""
    if not piece.frame:
        return False
    try:
        decode_frame(piece.data, "request")
    except errors.ProtocolError:
        return False
    return True
