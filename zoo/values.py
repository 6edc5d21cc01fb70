"""Absurd values a member writes into the replies it passes on: the pose as little-endian doubles, NaN or
infinity in every double of CMD_GET_POSITION and CMD_GET_STATUS (sans-IO).

Rules:
- ``rewrite(piece, style)`` returns the bytes of one reply frame with each DOUBLE field of those two replies
  replaced by the style's value; every other frame, and a frame that does not decode, comes back unchanged.
- ``little-endian``: the target sends the IEEE 754 double in the wrong byte order (guide 6.2: the data are big
  endian), so a client that decodes by the guide reads an absurd value (an angle of 1.2 rad reads as ~5e-62, one of
  3.14 as ~8e-157; a velocity of 300 mm/s as ~6e-317; the issue saw ~1e85 rad): what a port from a little-endian
  controller shows when its author forgot one conversion.
- ``nan`` and ``inf``: every such double is NaN, or +infinity (a sensor that failed, a division by zero).
- The frame keeps its length: only the 8 bytes of each double change.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable

from pltf.spec import errors
from pltf.spec.codec import REPLIES, decode_frame, encode
from pltf.zoo.frames import Piece

_BE, _LE = struct.Struct(">d"), struct.Struct("<d")


def _swapped(value: float) -> float:
    """The double whose big-endian bytes are ``value``'s little-endian ones."""
    return float(_BE.unpack(_LE.pack(value))[0])


STYLES: dict[str, Callable[[float], float]] = {
    "little-endian": _swapped,
    "nan": lambda value: math.nan,
    "inf": lambda value: math.inf,
}
# the replies whose doubles are rewritten (guide 6.4): the pose and velocities, the GPS position
DOUBLES: dict[int, tuple[str, ...]] = {
    t.ID: tuple(f.name for f in t.DEF.reply or () if f.type == "DOUBLE" and f.repeat is None)
    for t in (REPLIES.CMD_GET_POSITION, REPLIES.CMD_GET_STATUS)
}


def rewrite(piece: Piece, style: str) -> bytes:
    """The frame with its doubles rewritten in ``style`` (unchanged when it carries none or does not decode)."""
    names = DOUBLES.get(-1 if piece.ident is None else piece.ident)
    if not names:
        return piece.data
    try:
        reply = decode_frame(piece.data, "reply")
    except errors.ProtocolError:
        return piece.data  # not ours to judge: the client sees what the target sent
    change = STYLES[style]
    return encode(reply.replace(**{name: change(getattr(reply, name)) for name in names}))
