"""The blocking client: one TCP socket with timeouts, around the sans-IO ``ClientCore``.

Rules:
- All protocol decisions live in ``core`` (framing, reply routing) and ``waits`` (wait verdicts); this
  module only moves bytes, keeps time and sleeps.
- A reply is read by the caller that waits for it: there is no reader thread. A lock serialises callers,
  so one client may be shared by threads (their requests simply take turns).
- Any transport or protocol failure closes the socket; every later call raises ConnectionClosed.
"""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from collections.abc import Callable
from types import TracebackType

from pltf.client._commands import Commands
from pltf.client._enums import MotionMode, OperationState
from pltf.client._replies import Status
from pltf.client.base import DEFAULT_PORT, DEFAULT_TIMEOUT, ClientBase, WireLog
from pltf.client.core import PendingReply
from pltf.client.errors import ConnectionClosed, ProtocolError, Timeout
from pltf.client.waits import ConditionWait, Judge, ModeWait, StateWait, TargetWait
from pltf.spec.codec import build
from pltf.spec.telegram import Telegram

__all__ = ["DEFAULT_PORT", "DEFAULT_TIMEOUT", "PlatformClient", "WireLog"]


class PlatformClient(ClientBase, Commands):
    """A blocking connection to PlatformCtrl: one method per command, typed replies, waits.

    Connects in the constructor; use it as a context manager (or call ``close``) to close the socket::

        with PlatformClient("127.0.0.1", 10002) as pltf:
            pltf.connect_to_pltf()
            pltf.init_pltf()
            pltf.wait_state(OperationState.ST_OP_READY, timeout=10)

    Args: those of ``ClientBase`` (host, port, timeout, connect_timeout, wire_log, max_length).

    Raises:
        ConnectionClosed: the TCP connection could not be made (the OSError is the cause).
    """

    def _setup(self) -> None:
        self._lock = threading.RLock()
        host, port = self.host, self.port
        try:
            self._sock: socket.socket = socket.create_connection((host, port), timeout=self.connect_timeout)
        except OSError as exc:
            self.core.connection_lost(f"cannot connect to {host}:{port}: {exc}")
            raise ConnectionClosed(f"cannot connect to {host}:{port}: {exc}") from exc
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    # ------------------------------------------------------------------------------------ lifecycle
    def __enter__(self) -> PlatformClient:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def close(self) -> None:
        """Close the socket (idempotent). Requests still waiting fail with ConnectionClosed."""
        self.core.close()
        if self._sock.fileno() != -1:
            with contextlib.suppress(OSError):  # the peer may be gone already
                self._sock.shutdown(socket.SHUT_RDWR)
            self._sock.close()

    # ------------------------------------------------------------------------------------ telegrams
    def send(self, telegram: Telegram) -> PendingReply | None:
        """Send one request telegram; returns its PendingReply when the platform answers it (GET_*).

        Raises:
            InvalidArgument: a field value cannot be encoded.
            ConnectionClosed: the connection is closed or sending failed.
        """
        with self._lock:
            frame, pending = self._frame(telegram)
            try:
                self._sock.settimeout(self.timeout)
                self._sock.sendall(frame)
            except OSError as exc:
                self._lost(f"sending {telegram.NAME} failed: {exc}")
                raise ConnectionClosed(f"sending {telegram.NAME} failed: {exc}") from exc
            return pending

    def wait_reply(self, pending: PendingReply, timeout: float | None = None) -> Telegram:
        """Wait for the reply of a request sent with ``send`` (replies to other requests are kept for them).

        Raises:
            Timeout: no reply within ``timeout`` (default: the client's); its late reply will be dropped.
            ConnectionClosed, ProtocolError: the connection ended (it is closed).
        """
        wait = self.timeout if timeout is None else timeout
        deadline = time.monotonic() + wait
        with self._lock:
            while not pending.done:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    self.core.abandon(pending)
                    raise Timeout(f"no reply to {pending.request.NAME} within {wait:g} s")
                self._receive(remaining)
        return pending.result()

    def request(self, telegram: Telegram, timeout: float | None = None) -> Telegram:
        """Send an answered request (a GET_*) and return its reply telegram.

        Raises:
            InvalidArgument: the telegram is not answered, or a field value cannot be encoded.
            Timeout, ConnectionClosed, ProtocolError: as ``wait_reply``.
        """
        self._check_answered(telegram)
        pending = self.send(telegram)
        assert pending is not None  # an answered request always gets one
        return self.wait_reply(pending, timeout)

    def _receive(self, timeout: float) -> None:
        try:
            self._sock.settimeout(timeout)
            data = self._sock.recv(65536)
        except TimeoutError:
            return
        except OSError as exc:
            self._lost(f"receiving failed: {exc}")
            return
        try:
            self._received(data)
        except ProtocolError:
            self.close()
            raise
        if not data:
            self.close()

    def _lost(self, reason: str) -> None:
        self.core.connection_lost(reason)
        self.close()

    # ------------------------------------------------------------------------------------ waits
    def _poll(self, judge: Judge, poll: float) -> Status:
        while True:
            pending = self.send(self._status_request())
            assert pending is not None  # CMD_GET_STATUS is answered
            status = Status.from_telegram(self.wait_reply(pending))
            now = time.monotonic()
            if judge.observe(status, now, pending.seq):
                return status
            time.sleep(min(poll, judge.remaining(now)))

    @staticmethod
    def _status_request() -> Telegram:
        return build("request", "CMD_GET_STATUS")

    def wait_state(self, state: OperationState, timeout: float = 10.0, poll: float = 0.05) -> Status:
        """Poll the status until the operation state is ``state``; returns that status.

        Args:
            state: the operation state to wait for (guide 4.2 figure 2).
            timeout: seconds to wait.
            poll: seconds between two status requests.

        Raises:
            CommandRejected: the last state command sent (CMD_INIT_PLTF, CMD_START, CMD_BREAK, CMD_CONTINUE,
                CMD_STOP, CMD_SHUTDOWN_PLTF) leads to ``state`` and the state never came: the message says what
                the guide requires.
            Timeout: the state did not come (and no command sent here explains it).
        """
        return self._poll(StateWait(state, self.core.last_sent, time.monotonic(), timeout), poll)

    def wait_mode(self, mode: MotionMode, timeout: float = 10.0, poll: float = 0.05) -> Status:
        """Poll the status until the motion mode is ``mode``; returns that status.

        Raises:
            CommandRejected: CMD_SET_MODE was sent and the mode did not change (it needs state Ready).
            Timeout: the mode did not come.
        """
        return self._poll(ModeWait(mode, self.core.last_sent, time.monotonic(), timeout), poll)

    def wait_target_reached(self, timeout: float = 60.0, poll: float = 0.05) -> Status:
        """Poll the status until the platform reports its target reached; returns that status.

        Only statuses requested after the last move command (CMD_MOVE_ABS, _REL, _PATH, _TO_STATION) count.

        Raises:
            CommandRejected: the status shows the move cannot run: the state is not Running/Breaked, the
                mode is not MODE_MOTION_AUTOMATIC (guide 4.3), or the planner failed.
            Timeout: the target was not reached in time (the message gives the pose and planner state).
        """
        return self._poll(TargetWait(self.core.last_sent, time.monotonic(), timeout), poll)

    def wait_until(
        self, condition: Callable[[Status], bool], timeout: float = 10.0, poll: float = 0.05, what: str = "condition"
    ) -> Status:
        """Poll the status until ``condition(status)`` is true; returns that status.

        Raises:
            Timeout: the condition did not hold within ``timeout`` (the message names ``what``).
        """
        return self._poll(ConditionWait(condition, what, time.monotonic(), timeout), poll)

    def bring_up(self, timeout: float = 10.0, poll: float = 0.05) -> Status:
        """Connect and initialize the platform (CMD_CONNECT_TO_PLTF, CMD_INIT_PLTF) and wait for state Ready.

        Does nothing but the wait when the platform is already initialized.

        Raises:
            CommandRejected, Timeout: as ``wait_state``.
        """
        status = self.get_status()
        if status.operation_state != OperationState.ST_OP_NOT_INITIALIZED:
            return status
        self.connect_to_pltf()
        self.init_pltf()
        return self.wait_state(OperationState.ST_OP_READY, timeout, poll)
