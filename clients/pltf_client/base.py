"""What the blocking and the asyncio client share: the connection settings around one sans-IO ``ClientCore``.

Rules:
- No I/O here: each transport (``sync``, ``aio``) overrides ``_setup``, its one hook, to prepare its own state
  (the blocking client connects there; the asyncio one connects later, in ``open``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypedDict

from pltf.client.core import ClientCore, PendingReply
from pltf.client.errors import InvalidArgument
from pltf.spec.codec import DEFAULT_MAX_LENGTH
from pltf.spec.telegram import Telegram

DEFAULT_PORT = 10002  # guide 4.2: PlatformCtrl listens on 10000 and 10002; the field client's default
DEFAULT_TIMEOUT = 5.0

WireLog = Callable[[str, bytes], None]
"""``wire_log(direction, data)``: ``"send"`` with each whole frame, ``"recv"`` with each chunk read."""


class ClientOptions(TypedDict, total=False):
    """The keyword arguments of ``ClientBase`` (for a factory that passes them on, typed)."""

    timeout: float
    connect_timeout: float
    wire_log: WireLog | None
    max_length: int


class ClientBase:
    """The settings of one connection to PlatformCtrl and its protocol core.

    Args:
        host: the platform PC's address.
        port: its PlatformCtrl port (guide 4.2: 10000 or 10002; one client per port).
        timeout: default seconds to wait for a reply (each GET_* method takes its own ``timeout`` too).
        connect_timeout: seconds to wait for the TCP connection.
        wire_log: optional callback ``(direction, data)`` seeing every frame sent and every chunk received.
        max_length: largest reply frame accepted, in data bytes (erratum E-WIRE-004).
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = DEFAULT_PORT,
        *,
        timeout: float = DEFAULT_TIMEOUT,
        connect_timeout: float = DEFAULT_TIMEOUT,
        wire_log: WireLog | None = None,
        max_length: int = DEFAULT_MAX_LENGTH,
    ) -> None:
        self.host = host
        self.port = port
        self.timeout = timeout
        self.connect_timeout = connect_timeout
        self.wire_log = wire_log
        self.core = ClientCore(max_length)
        self._setup()

    def _setup(self) -> None:
        """The transport's hook, run at the end of the constructor."""

    def _frame(self, telegram: Telegram) -> tuple[bytes, PendingReply | None]:
        """The core numbers and frames a request (InvalidArgument, ConnectionClosed); the wire log sees it."""
        frame, pending = self.core.send(telegram)
        if self.wire_log is not None:
            self.wire_log("send", frame)
        return frame, pending

    def _received(self, data: bytes) -> None:
        """A chunk read from the socket (``b""``: the peer closed) goes to the wire log, then the core.

        Raises:
            ProtocolError: the bytes break the protocol (the core is closed then).
        """
        if self.wire_log is not None and data:
            self.wire_log("recv", data)
        self.core.receive_data(data)

    def _check_answered(self, telegram: Telegram) -> None:
        if not telegram.DEF.answered:
            raise InvalidArgument(f"{telegram.NAME} is not answered (guide 6.1): use send()")

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.host}:{self.port}{' closed' if self.closed else ''}>"

    @property
    def closed(self) -> bool:
        """True once the connection is closed (by ``close``, by the peer or after a protocol error)."""
        return self.core.closed
