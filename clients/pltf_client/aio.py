"""The asyncio client: asyncio streams around the sans-IO ``ClientCore``.

Rules:
- All protocol decisions live in ``core`` and ``waits``; this module moves bytes, keeps time and sleeps.
- One reader task feeds every received chunk to the core and wakes the tasks whose replies arrived, so
  many tasks may have requests in flight on one connection; each gets its own reply (matched by id).
- A request's frame is written synchronously right after the core numbered it, so the wire order is the
  order of the sequence numbers the waits rely on.
- Any transport or protocol failure closes the connection; every later call raises ConnectionClosed.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable
from types import TracebackType
from typing import Unpack

from pltf.client._commands import AsyncCommands
from pltf.client._enums import MotionMode, OperationState
from pltf.client._replies import Status
from pltf.client.base import DEFAULT_PORT, ClientBase, ClientOptions
from pltf.client.core import PendingReply
from pltf.client.errors import ConnectionClosed, ProtocolError, Timeout
from pltf.client.waits import ConditionWait, Judge, ModeWait, StateWait, TargetWait
from pltf.spec.codec import build
from pltf.spec.telegram import Telegram


class AsyncPlatformClient(ClientBase, AsyncCommands):
    """An asyncio connection to PlatformCtrl: one coroutine method per command, typed replies, waits.

    Connect with ``await AsyncPlatformClient.connect(host, port)`` or ``async with AsyncPlatformClient(host,
    port) as pltf:`` (which connects on entry and closes on exit)::

        async with AsyncPlatformClient("127.0.0.1", 10002) as pltf:
            await pltf.bring_up()
            status = await pltf.get_status()

    Args: those of ``ClientBase`` (host, port, timeout, connect_timeout, wire_log, max_length).
    """

    def _setup(self) -> None:
        self._writer: asyncio.StreamWriter | None = None
        self._reader_task: asyncio.Task[None] | None = None
        self._changed = asyncio.Condition()  # notified whenever a pending request may have completed
        self._drain_lock = asyncio.Lock()

    @classmethod
    async def connect(
        cls, host: str = "127.0.0.1", port: int = DEFAULT_PORT, **options: Unpack[ClientOptions]
    ) -> AsyncPlatformClient:
        """Create a client and open its connection (arguments as for the constructor).

        Raises:
            ConnectionClosed: the TCP connection could not be made (the OSError is the cause).
        """
        client = cls(host, port, **options)
        await client.open()
        return client

    async def open(self) -> None:
        """Open the TCP connection and start the reader task.

        Raises:
            ConnectionClosed: the connection could not be made, or the client was already used.
        """
        if self._writer is not None or self.core.closed:
            raise ConnectionClosed("this client was already connected; create a new one")
        try:
            reader, writer = await asyncio.wait_for(asyncio.open_connection(self.host, self.port), self.connect_timeout)
        except (OSError, TimeoutError) as exc:
            self.core.connection_lost(f"cannot connect to {self.host}:{self.port}: {exc!r}")
            raise ConnectionClosed(f"cannot connect to {self.host}:{self.port}: {exc!r}") from exc
        self._writer = writer
        self._reader_task = asyncio.get_running_loop().create_task(self._read_loop(reader))

    # ------------------------------------------------------------------------------------ lifecycle
    async def __aenter__(self) -> AsyncPlatformClient:
        if self._writer is None:
            await self.open()
        return self

    async def __aexit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.close()

    async def close(self) -> None:
        """Close the connection (idempotent). Requests still waiting fail with ConnectionClosed."""
        self.core.close()
        await self._wake()
        task, self._reader_task = self._reader_task, None
        if task is not None and task is not asyncio.current_task():
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
        writer, self._writer = self._writer, None
        if writer is not None:
            writer.close()
            with contextlib.suppress(OSError):
                await writer.wait_closed()

    # ------------------------------------------------------------------------------------ telegrams
    async def send(self, telegram: Telegram) -> PendingReply | None:
        """Send one request telegram; returns its PendingReply when the platform answers it (GET_*).

        Raises:
            InvalidArgument: a field value cannot be encoded.
            ConnectionClosed: the connection is closed or sending failed.
        """
        if self._writer is None and not self.core.closed:
            raise ConnectionClosed("not connected: call open() or use `async with`")
        frame, pending = self._frame(telegram)
        assert self._writer is not None  # core.send raised if the connection was closed
        try:
            self._writer.write(frame)
            async with self._drain_lock:
                await self._writer.drain()
        except OSError as exc:
            await self._lost(f"sending {telegram.NAME} failed: {exc!r}")
            raise ConnectionClosed(f"sending {telegram.NAME} failed: {exc!r}") from exc
        return pending

    async def wait_reply(self, pending: PendingReply, timeout: float | None = None) -> Telegram:
        """Wait for the reply of a request sent with ``send`` (replies to other requests go to their waiters).

        Raises:
            Timeout: no reply within ``timeout`` (default: the client's); its late reply will be dropped.
            ConnectionClosed, ProtocolError: the connection ended (it is closed).
        """
        wait = self.timeout if timeout is None else timeout
        try:
            async with self._changed:
                await asyncio.wait_for(self._changed.wait_for(lambda: pending.done), wait)
        except TimeoutError:
            self.core.abandon(pending)
            raise Timeout(f"no reply to {pending.request.NAME} within {wait:g} s") from None
        except asyncio.CancelledError:
            if not pending.done:
                self.core.abandon(pending)  # nobody will take this reply: drop it when it comes
            raise
        return pending.result()

    async def request(self, telegram: Telegram, timeout: float | None = None) -> Telegram:
        """Send an answered request (a GET_*) and return its reply telegram.

        Raises:
            InvalidArgument: the telegram is not answered, or a field value cannot be encoded.
            Timeout, ConnectionClosed, ProtocolError: as ``wait_reply``.
        """
        self._check_answered(telegram)
        pending = await self.send(telegram)
        assert pending is not None  # an answered request always gets one
        return await self.wait_reply(pending, timeout)

    async def _read_loop(self, reader: asyncio.StreamReader) -> None:
        try:
            while not self.core.closed:
                try:
                    data = await reader.read(65536)
                except OSError as exc:
                    self.core.connection_lost(f"receiving failed: {exc!r}")
                    break
                try:
                    self._received(data)
                except ProtocolError:
                    break
                finally:
                    await self._wake()
        finally:
            await self._wake()
            if self.core.closed and self._reader_task is asyncio.current_task():
                await self.close()

    async def _wake(self) -> None:
        async with self._changed:
            self._changed.notify_all()

    async def _lost(self, reason: str) -> None:
        self.core.connection_lost(reason)
        await self.close()

    # ------------------------------------------------------------------------------------ waits
    async def _poll(self, judge: Judge, poll: float) -> Status:
        loop = asyncio.get_running_loop()
        while True:
            pending = await self.send(build("request", "CMD_GET_STATUS"))
            assert pending is not None  # CMD_GET_STATUS is answered
            status = Status.from_telegram(await self.wait_reply(pending))
            now = loop.time()
            if judge.observe(status, now, pending.seq):
                return status
            await asyncio.sleep(min(poll, judge.remaining(now)))

    async def wait_state(self, state: OperationState, timeout: float = 10.0, poll: float = 0.05) -> Status:
        """Poll the status until the operation state is ``state``; returns that status.

        Args and Raises: as ``PlatformClient.wait_state``.
        """
        judge = StateWait(state, self.core.last_sent, asyncio.get_running_loop().time(), timeout)
        return await self._poll(judge, poll)

    async def wait_mode(self, mode: MotionMode, timeout: float = 10.0, poll: float = 0.05) -> Status:
        """Poll the status until the motion mode is ``mode``; returns that status.

        Raises:
            CommandRejected: CMD_SET_MODE was sent and the mode did not change (it needs state Ready).
            Timeout: the mode did not come.
        """
        judge = ModeWait(mode, self.core.last_sent, asyncio.get_running_loop().time(), timeout)
        return await self._poll(judge, poll)

    async def wait_target_reached(self, timeout: float = 60.0, poll: float = 0.05) -> Status:
        """Poll the status until the platform reports its target reached; returns that status.

        Which statuses count, and Raises: as ``PlatformClient.wait_target_reached``.
        """
        judge = TargetWait(self.core.last_sent, asyncio.get_running_loop().time(), timeout)
        return await self._poll(judge, poll)

    async def wait_until(
        self, condition: Callable[[Status], bool], timeout: float = 10.0, poll: float = 0.05, what: str = "condition"
    ) -> Status:
        """Poll the status until ``condition(status)`` is true; returns that status.

        Raises:
            Timeout: the condition did not hold within ``timeout`` (the message names ``what``).
        """
        judge = ConditionWait(condition, what, asyncio.get_running_loop().time(), timeout)
        return await self._poll(judge, poll)

    async def bring_up(self, timeout: float = 10.0, poll: float = 0.05) -> Status:
        """Connect and initialize the platform (CMD_CONNECT_TO_PLTF, CMD_INIT_PLTF) and wait for state Ready.

        Does nothing but the wait when the platform is already initialized.

        Raises:
            CommandRejected, Timeout: as ``wait_state``.
        """
        status = await self.get_status()
        if status.operation_state != OperationState.ST_OP_NOT_INITIALIZED:
            return status
        await self.connect_to_pltf()
        await self.init_pltf()
        return await self.wait_state(OperationState.ST_OP_READY, timeout, poll)
