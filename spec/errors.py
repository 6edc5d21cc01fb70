"""The codec's one exception family.

Rules (after h11): an error is Local when *we* tried to produce something the protocol forbids (encoding an
out-of-range field), Remote when the *peer* sent bytes the protocol forbids. Every decode failure raises a
subclass of RemoteProtocolError and nothing else: a fuzzer's invariant is "any byte string decodes or raises
RemoteProtocolError".
"""

from __future__ import annotations


class ProtocolError(Exception):
    """Base of every codec error."""


class LocalProtocolError(ProtocolError):
    """We tried to encode a telegram the protocol does not allow."""


class FieldValueError(LocalProtocolError):
    """A field value is of the wrong type or outside its range (encode side)."""


class RemoteProtocolError(ProtocolError):
    """The peer sent bytes the protocol does not allow."""


class BadHeader(RemoteProtocolError):
    """The frame does not start with FF 01 FE 02 (guide 6.2 figure 11)."""


class FrameTooLarge(RemoteProtocolError):
    """The frame's length field is over the configured maximum (checked before any allocation)."""


class Truncated(RemoteProtocolError):
    """The stream ended inside a frame, or a telegram is shorter than its layout."""


class TrailingBytes(RemoteProtocolError):
    """A telegram has bytes left over after its last field, or a frame is followed by extra bytes."""


class UnknownTelegram(RemoteProtocolError):
    """The telegram identifier is not in the spec (or the frame carries no identifier)."""


class FieldOutOfRange(RemoteProtocolError):
    """A decoded field is outside its enum, its declared range or its constant."""


class LengthMismatch(RemoteProtocolError):
    """A STRING/XML length or a repeat count disagrees with the bytes that follow (negative or too large)."""
