"""The client's one exception family: every failure a caller can see is a ``PlatformError``.

Rules:
- The codec's own errors never escape raw: a peer's bad bytes become ``ProtocolError`` (the codec's
  ``RemoteProtocolError`` is its ``__cause__``), a bad argument becomes ``InvalidArgument``.
- ``Timeout`` is also a builtin ``TimeoutError``, ``InvalidArgument`` also a ``ValueError``, so generic
  handlers keep working.
- PlatformCtrl does not acknowledge commands (guide 6.1: it "returns data only on request"), so a refused
  command is only visible through the status telegram. ``CommandRejected`` is raised where the client can
  tell: a wait that sees the state the command needs missing, or a state that never came.
"""

from __future__ import annotations


class PlatformError(Exception):
    """Base of every error raised by the client library."""


class ConnectionClosed(PlatformError):
    """The connection is closed (by us, by the peer, or after a protocol error); nothing more can be sent."""


class ProtocolError(PlatformError):
    """The platform sent bytes the protocol does not allow; the connection has been closed.

    The codec's ``pltf.spec.errors.RemoteProtocolError`` that was detected is the ``__cause__``.
    """


class InvalidArgument(PlatformError, ValueError):
    """A command argument cannot be encoded (wrong type, outside its field's range or enum, not Latin-1)."""


class Timeout(PlatformError, TimeoutError):
    """A reply or an awaited condition did not come in time."""


class CommandRejected(PlatformError):
    """A command did not take effect, and the status telegram shows why (or that it never did).

    Attributes:
        command: the telegram name of the command, e.g. ``"CMD_START"``.
        reason: a sentence explaining what the status showed, with the guide's rule.
    """

    def __init__(self, command: str, reason: str) -> None:
        super().__init__(f"{command} was not carried out: {reason}")
        self.command = command
        self.reason = reason
