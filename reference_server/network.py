"""The asyncio shell of the reference server: sockets, the simulated clock and the control loop.

Rules:
- The only module of the server that does network I/O or reads a clock; the platform model gets the
  simulated time as ``now``.
- Guide 6.1: the server "listens for clients on the socket ports 10000 and 10002. For each port one client
  is able to connect": both ports take the full command set; a second client on a busy port is logged and
  closed at once (erratum: the guide leaves this open), the first is not disturbed.
- Replies are framed like requests (erratum E-WIRE-001). Malformed input - any RemoteProtocolError of the
  decoder, or a partial frame that stalls for ``stall_timeout`` wall seconds - is logged with the peer and
  the reason and closes only that connection.
- The control loop ticks the platform at 50 Hz simulated time: ``dt`` = 0.02 s simulated, i.e. every
  0.02 / time_scale wall seconds; when the loop falls behind it catches up, within limits.
- ``serve`` returns 0 after CMD_EXIT, SIGINT or SIGTERM, having closed every listener and connection.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import logging
import math
import signal
from collections.abc import Callable, Sequence

from reference_server.platform import Platform
from spec.codec import DEFAULT_MAX_LENGTH, TelegramDecoder, encode
from spec.errors import RemoteProtocolError

log = logging.getLogger("pltf.server")

CONTROL_PERIOD = 0.02  # simulated s (50 Hz)
STALL_TIMEOUT = 5.0  # wall s a partial frame may wait for its rest
MAX_CATCH_UP = 500  # periods (10 s simulated) caught up at once; beyond that they are skipped
READ_SIZE = 65536


class SimClock:
    """Simulated seconds since start: wall time on the loop's monotonic clock times ``time_scale``."""

    def __init__(self, loop: asyncio.AbstractEventLoop, time_scale: float) -> None:
        if not time_scale > 0:
            raise ValueError(f"time scale must be > 0, not {time_scale}")
        self.loop = loop
        self.time_scale = time_scale
        self._t0 = loop.time()

    def now(self) -> float:
        return (self.loop.time() - self._t0) * self.time_scale

    def wall_at(self, sim: float) -> float:
        """The loop time at which the simulated clock reads ``sim``."""
        return self._t0 + sim / self.time_scale


class Server:
    def __init__(
        self,
        platform: Platform,
        host: str,
        ports: Sequence[int],
        time_scale: float = 1.0,
        *,
        stall_timeout: float = STALL_TIMEOUT,
        max_length: int = DEFAULT_MAX_LENGTH,
    ) -> None:
        self.platform = platform
        self.host = host
        self.requested_ports = list(ports)
        self.time_scale = time_scale
        self.stall_timeout = stall_timeout
        self.max_length = max_length
        self.ports: list[int] = []
        self._listeners: list[asyncio.Server] = []
        self._busy: dict[int, asyncio.StreamWriter] = {}
        self._stopped = asyncio.Event()
        self._clock: SimClock | None = None
        self.exit_code = 0

    @property
    def clock(self) -> SimClock:
        assert self._clock is not None, "server not started"
        return self._clock

    async def start(self) -> list[int]:
        self._clock = SimClock(asyncio.get_running_loop(), self.time_scale)
        try:
            for index, port in enumerate(self.requested_ports):
                listener = await asyncio.start_server(
                    functools.partial(self._client, index=index), self.host, port, reuse_address=True
                )
                self._listeners.append(listener)
                self.ports.append(listener.sockets[0].getsockname()[1])
                log.info("server started at port %d", self.ports[-1])
        except OSError:
            for listener in self._listeners:
                listener.close()
            raise
        return self.ports

    def stop(self) -> None:
        self._stopped.set()

    async def run(self) -> int:
        """Boot the platform, run the control loop until ``stop``, then close everything."""
        self.platform.boot(self.clock.now())
        sim = asyncio.create_task(self._simulate())
        try:
            await self._stopped.wait()
        finally:
            sim.cancel()
            for listener in self._listeners:
                listener.close()
            for writer in list(self._busy.values()):
                writer.close()
            for listener in self._listeners:
                with contextlib.suppress(Exception):
                    await listener.wait_closed()
            with contextlib.suppress(asyncio.CancelledError):
                await sim
            log.info("server stopped")
        return self.exit_code

    # ---- the control loop (50 Hz simulated)
    async def _simulate(self) -> None:
        clock, loop = self.clock, asyncio.get_running_loop()
        ticks = int(clock.now() / CONTROL_PERIOD)
        warned_at = -math.inf
        while True:
            due = int(clock.now() / CONTROL_PERIOD) - ticks
            if due > MAX_CATCH_UP:  # the loop was blocked (or the time scale is beyond this machine)
                if ticks * CONTROL_PERIOD - warned_at >= 10.0:
                    log.warning("control loop %d periods behind: skipped", due - 1)
                    warned_at = ticks * CONTROL_PERIOD
                ticks += due - 1
                due = 1
            for _ in range(due):
                ticks += 1
                self.platform.tick(ticks * CONTROL_PERIOD)
            await asyncio.sleep(max(0.0, clock.wall_at((ticks + 1) * CONTROL_PERIOD) - loop.time()))

    # ---- one connection
    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, index: int) -> None:
        port = self.ports[index]
        peer = _peer(writer)
        if index in self._busy or self._stopped.is_set():
            log.warning("port %d busy: second client %s turned away", port, peer)
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()
            return
        self._busy[index] = writer
        log.info("client %s connected at port %d", peer, port)
        try:
            reason = await self._serve_client(reader, writer)
            log.info("client %s at port %d: %s", peer, port, reason)
        except RemoteProtocolError as exc:
            log.warning("client %s at port %d: %s: %s; connection closed", peer, port, type(exc).__name__, exc)
        except (ConnectionError, OSError) as exc:
            log.warning("client %s at port %d: %s; connection closed", peer, port, exc)
        except Exception:  # a bug of the platform model must not take the server down
            log.exception("client %s at port %d: internal error; connection closed", peer, port)
        finally:
            del self._busy[index]
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()

    async def _serve_client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> str:
        decoder = TelegramDecoder("request", self.max_length)
        platform, clock = self.platform, self.clock
        while True:
            if decoder.pending:
                try:
                    data = await asyncio.wait_for(reader.read(READ_SIZE), self.stall_timeout)
                except TimeoutError:
                    return (
                        f"partial frame stalled for {self.stall_timeout:g} s ({decoder.pending} bytes); "
                        "connection closed"
                    )
            else:
                data = await reader.read(READ_SIZE)
            decoder.receive_data(data)
            while (telegram := decoder.next_telegram()) is not None:
                outcome = platform.handle(telegram, clock.now())
                if outcome.reply is not None:
                    writer.write(encode(outcome.reply))
                if outcome.exit_server:
                    self.stop()
                    return "CMD_EXIT: server exits"
                if outcome.close_connection:
                    await writer.drain()
                    return "CMD_CLOSE_SOCKET: connection closed"
            if not data:
                return "disconnected"
            await writer.drain()


def _peer(writer: asyncio.StreamWriter) -> str:
    info = writer.get_extra_info("peername")
    if isinstance(info, tuple) and len(info) >= 2:
        return f"{info[0]}:{info[1]}"
    return str(info)


async def serve(
    platform: Platform,
    host: str,
    ports: Sequence[int],
    time_scale: float = 1.0,
    *,
    stall_timeout: float = STALL_TIMEOUT,
    max_length: int = DEFAULT_MAX_LENGTH,
    ready: Callable[[Server], None] | None = None,
    handle_signals: bool = True,
) -> int:
    """Listen on ``ports`` and run the platform until CMD_EXIT (or SIGINT/SIGTERM); returns the exit code."""
    server = Server(platform, host, ports, time_scale, stall_timeout=stall_timeout, max_length=max_length)
    await server.start()
    if handle_signals:
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, _on_signal, server, sig)
    if ready is not None:
        ready(server)
    return await server.run()


def _on_signal(server: Server, sig: signal.Signals) -> None:
    log.info("%s received: server exits", sig.name)
    server.stop()


def run(platform: Platform, host: str, ports: Sequence[int], time_scale: float = 1.0, **options: object) -> int:
    """Blocking entry point for the command line."""
    return asyncio.run(serve(platform, host, ports, time_scale, **options))  # type: ignore[arg-type]
