"""The asyncio shell of the reference server: sockets, the simulated clock and the control loop.

Rules:
- The only module of the server that does network I/O or reads a clock; the platform model gets the
  simulated time as ``now``.
- Guide 6.1: the server "listens for clients on the socket ports 10000 and 10002. For each port one client
  is able to connect": both ports take the full command set; a second client on a busy port is logged and
  closed at once (erratum E-WIRE-007: the guide leaves this open), the first is not disturbed. Before it is
  judged, what the first client sent is read: a client that has left (its EOF not yet read) is no longer there.
- Replies are framed like requests (erratum E-WIRE-001). Malformed input - any RemoteProtocolError of the
  decoder, or a partial frame that stalls for ``stall_timeout`` wall seconds - is logged with the peer and
  the reason and closes only that connection.
- Connections are plain sockets on the loop's selector (``add_reader``), not asyncio streams: a connection
  costs an accept, a read and a close - no task, transport or stream objects, no system call to make it
  non-blocking (reads and writes say MSG_DONTWAIT) - so a client that opens a connection per request (a
  fuzzer, a test harness) is served at thousands of connections per second. The data that came with the
  connection is read at once; the replies to one read go out in one write; replies the client does not take
  wait (reading pauses above ``HIGH_WATER`` buffered bytes, as ``StreamWriter.drain`` would), and a closing
  connection sends what it owes before it closes. Per-connection log lines are formatted only when enabled.
- The platform is ticked at 50 Hz simulated time by the rules of reference_server/control_loop.py: every
  tick one period, at whole periods, at every time scale. The clock (``SimClock``) reads the loop's monotonic
  clock through the ``ControlLoop``: the timer works the ticks off every period (``SimClock.work``, a burst at
  most between two looks at the sockets), and the telegrams of one read are handed to the platform at one fresh
  reading (they arrived together) that first runs the ticks a late timer left, never on a state left behind.
  A loop that falls too far behind holds the simulated time instead of skipping it.
- The stall timeout of a partial frame is in wall seconds at every time scale: it guards the connection (a TCP
  peer pauses in wall time), not the platform, and no telegram's meaning depends on it.
- ``serve`` returns 0 after CMD_EXIT, SIGINT or SIGTERM, having closed every listener and connection.
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import logging
import signal
import socket
from collections.abc import Callable, Sequence
from typing import Any, Protocol, TypeVar

from pltf.reference_server.control_loop import CONTROL_PERIOD, MAX_CATCH_UP, ControlLoop
from pltf.reference_server.platform import Platform
from pltf.spec.codec import DEFAULT_MAX_LENGTH, TelegramDecoder, encode
from pltf.spec.errors import RemoteProtocolError

log = logging.getLogger("pltf.server")

STALL_TIMEOUT = 5.0  # wall s a partial frame may wait for its rest
READ_SIZE = 65536
BACKLOG = 100  # listen backlog, and connections accepted per wake-up (asyncio's defaults)
HIGH_WATER = 1 << 16  # bytes of unsent replies above which reading pauses (asyncio's default high-water mark)
LOW_WATER = 1 << 14  # ... and below which it resumes
ACCEPT_RETRY = 1.0  # s before accepting again when out of file descriptors
DRAIN_READS = 16  # reads of a busy port's client before a second client is turned away (1 MiB at most)
# Non-blocking calls on an accepted socket without making it non-blocking (one system call less per connection)
_DONTWAIT: int = getattr(socket, "MSG_DONTWAIT", 0)
_ACCEPT_ERRORS = (errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM)


class SimClock:
    """Simulated seconds since start: the loop's monotonic clock read through the ``ControlLoop``, which ticks the
    platform up to the time it reads (reference_server/control_loop.py)."""

    def __init__(self, loop: asyncio.AbstractEventLoop, control: ControlLoop) -> None:
        self.loop = loop
        self.control = control

    @property
    def time_scale(self) -> float:
        return self.control.time_scale

    def begin(self) -> float:
        """The simulated time now, at which the platform boots: the ticks before it do not happen."""
        return self.control.begin(self.loop.time())

    def now(self) -> float:
        """The simulated time for what the platform is handed now (a telegram, a control request): the ticks due
        run first unless they are a backlog, which is the timer's (``work``)."""
        return self.control.now(self.loop.time(), burst=0)

    def work(self) -> None:
        """The timer: run the ticks due, a burst at most."""
        self.control.now(self.loop.time())

    def wall_at(self, sim: float) -> float:
        """The loop time at which the simulated clock reads ``sim``."""
        return self.control.wall_at(sim)


class _Peer:
    """A peer address, formatted only when a log line is emitted."""

    __slots__ = ("addr",)

    def __init__(self, addr: Any) -> None:
        self.addr = addr

    def __str__(self) -> str:
        info = self.addr
        if isinstance(info, tuple) and len(info) >= 2:
            return f"{info[0]}:{info[1]}"
        return str(info)


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
        control: ControlLoop | None = None,
    ) -> None:
        self.platform = platform
        self._shared = control  # a fleet's one control loop (reference_server/fleet/network.py), which it runs
        self.host = host
        self.requested_ports = list(ports)
        self.time_scale = time_scale
        self.stall_timeout = stall_timeout
        self.max_length = max_length
        self.ports: list[int] = []
        self._listeners: list[tuple[int, socket.socket]] = []  # (port index, listening socket)
        self._busy: dict[int, _Connection] = {}  # port index -> its client
        self._open: set[_Connection] = set()  # every connection not yet closed (a closing one flushes its replies)
        self._stopped = asyncio.Event()
        self._clock: SimClock | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self.exit_code = 0

    @property
    def clock(self) -> SimClock:
        assert self._clock is not None, "server not started"
        return self._clock

    async def start(self) -> list[int]:
        loop = self._loop = asyncio.get_running_loop()
        self.control = self._shared or ControlLoop(self.platform, self.time_scale, loop.time())
        self._clock = SimClock(loop, self.control)
        try:
            for index, port in enumerate(self.requested_ports):
                socks = await self._listen(loop, port)
                for sock in socks:
                    self._listeners.append((index, sock))
                    loop.add_reader(sock.fileno(), self._accept, index, sock)
                self.ports.append(socks[0].getsockname()[1])
                log.info("server started at port %d", self.ports[-1])
        except OSError:
            self._close_listeners()
            raise
        return self.ports

    async def _listen(self, loop: asyncio.AbstractEventLoop, port: int) -> list[socket.socket]:
        """Listening sockets on every address of ``host`` (as ``asyncio.start_server`` binds them)."""
        infos = await loop.getaddrinfo(self.host or None, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
        socks: list[socket.socket] = []
        try:
            for family, kind, proto, _, addr in dict.fromkeys(infos):
                sock = socket.socket(family, kind, proto)
                socks.append(sock)
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                if family == socket.AF_INET6:
                    sock.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
                sock.bind(addr)
                sock.listen(BACKLOG)
                sock.setblocking(False)
        except OSError:
            for sock in socks:
                sock.close()
            raise
        return socks

    def _close_listeners(self) -> None:
        loop = self._loop
        for _, sock in self._listeners:
            if loop is not None:
                loop.remove_reader(sock.fileno())
            sock.close()
        self._listeners.clear()

    def stop(self) -> None:
        self._stopped.set()

    async def run(self) -> int:
        """Boot the platform, run the control loop until ``stop``, then close everything."""
        self.platform.boot(self.clock.begin())
        self.clock.begin()  # the boot took its time (documents, the world): the first tick is one period after it
        sim = asyncio.create_task(self._simulate())
        try:
            await self._stopped.wait()
        finally:
            sim.cancel()
            self.close()
            with contextlib.suppress(asyncio.CancelledError):
                await sim
            log.info("server stopped")
        return self.exit_code

    async def wait_stopped(self) -> None:
        await self._stopped.wait()

    def close(self) -> None:
        """Close the listeners and every connection (what a stopping server does; a fleet's member on its own)."""
        self._close_listeners()
        for conn in list(self._open):
            conn.abort()

    # ---- the control loop (50 Hz simulated; reference_server/control_loop.py)
    async def _simulate(self) -> None:
        clock, loop = self.clock, asyncio.get_running_loop()
        while True:
            clock.work()
            await asyncio.sleep(max(0.0, clock.wall_at(self.control.next_tick) - loop.time()))

    # ---- connections
    def _accept(self, index: int, listener: socket.socket) -> None:
        """The listening socket is readable: take every pending connection (up to ``BACKLOG``)."""
        for _ in range(BACKLOG):
            try:
                sock, addr = listener.accept()
            except (BlockingIOError, InterruptedError, ConnectionAbortedError):
                return
            except OSError as exc:
                if exc.errno not in _ACCEPT_ERRORS:
                    raise
                log.error(
                    "port %d: cannot accept a connection: %s; retrying in %g s", self.ports[index], exc, ACCEPT_RETRY
                )
                self._pause_accepting(listener, index)
                return
            if not _DONTWAIT:
                sock.setblocking(False)
            busy = self._busy.get(index)
            if busy is not None:  # its client may have left already: its last bytes and EOF not yet read
                self._drain(index, busy)
            if index in self._busy or self._stopped.is_set():
                log.warning("port %d busy: second client %s turned away", self.ports[index], _Peer(addr))
                sock.close()
                continue
            conn = _Connection(self, sock, _Peer(addr), index)
            self._busy[index] = conn
            self._open.add(conn)
            log.info("client %s connected at port %d", conn.peer, conn.port)
            conn.start()

    def _drain(self, index: int, conn: _Connection) -> None:
        """Read what the port's client has sent so far (up to ``DRAIN_READS`` reads) before a newcomer is judged:
        a client that sent its last request and left (E-WIRE-007) frees the port for the one right behind it."""
        for _ in range(DRAIN_READS):
            if self._busy.get(index) is not conn or not conn.reading or not conn._readable():
                return

    def _pause_accepting(self, listener: socket.socket, index: int) -> None:
        loop = self._loop
        assert loop is not None
        loop.remove_reader(listener.fileno())

        def resume() -> None:
            if any(sock is listener for _, sock in self._listeners):
                loop.add_reader(listener.fileno(), self._accept, index, listener)

        loop.call_later(ACCEPT_RETRY, resume)

    def _released(self, conn: _Connection) -> None:
        """``conn`` no longer takes input: its port is free for the next client."""
        if self._busy.get(conn.index) is conn:
            del self._busy[conn.index]

    def _closed(self, conn: _Connection) -> None:
        self._released(conn)
        self._open.discard(conn)


class _Connection:
    """One client: read, decode, let the platform handle each telegram, write the replies back."""

    __slots__ = (
        "closing",
        "decoder",
        "fd",
        "index",
        "loop",
        "nodelay",
        "out",
        "peer",
        "port",
        "reading",
        "server",
        "sock",
        "stall_at",
        "stall_timer",
        "writing",
    )

    def __init__(self, server: Server, sock: socket.socket, peer: _Peer, index: int) -> None:
        self.server, self.sock, self.peer, self.index = server, sock, peer, index
        self.fd = sock.fileno()
        self.port = server.ports[index]
        assert server._loop is not None
        self.loop = server._loop
        self.decoder = TelegramDecoder("request", server.max_length)
        self.out = bytearray()  # replies not yet taken by the socket
        self.reading = self.writing = self.closing = self.nodelay = False
        self.stall_at: float | None = None  # loop time at which a pending partial frame is given up
        self.stall_timer: asyncio.TimerHandle | None = None

    def start(self) -> None:
        self._readable()  # what came with the connection (a request usually has): no selector round trip
        if not self.closing and not self.reading and len(self.out) <= HIGH_WATER:
            self._resume_reading()

    # ---- reading
    def _resume_reading(self) -> None:
        if not self.reading:
            self.reading = True
            self.loop.add_reader(self.fd, self._readable)

    def _pause_reading(self) -> None:
        if self.reading:
            self.reading = False
            self.loop.remove_reader(self.fd)

    def _readable(self) -> bool:
        """Read once and handle what came; False when there was nothing to read (or the read failed)."""
        try:
            data = self.sock.recv(READ_SIZE, _DONTWAIT)
        except (BlockingIOError, InterruptedError):
            return False
        except OSError as exc:
            self._end(logging.WARNING, "%s; connection closed", exc)
            return False
        self._received(data)
        return True

    def _received(self, data: bytes) -> None:
        self.decoder.receive_data(data)
        replies: list[bytes] = []
        try:
            ended = self._handle_telegrams(replies)
        except RemoteProtocolError as exc:
            self._write(replies)
            self._end(logging.WARNING, "%s: %s; connection closed", type(exc).__name__, exc)
            return
        except Exception:  # a bug of the platform model must not take the server down
            log.exception("client %s at port %d: internal error; connection closed", self.peer, self.port)
            self._write(replies)
            self._end(None)
            return
        if ended is not None:
            self._write(replies)
            self._end(logging.INFO, "%s", ended)
            return
        self._write(replies)
        if self.closing:  # the write failed
            return
        if not data:
            self._end(logging.INFO, "%s", "disconnected")
            return
        if self.decoder.pending:
            self._arm_stall()
        else:
            self.stall_at = None
        if len(self.out) > HIGH_WATER:
            self._pause_reading()

    def _handle_telegrams(self, replies: list[bytes]) -> str | None:
        """Hand every complete telegram read to the platform, the replies into ``replies``; why the connection
        ends (CMD_EXIT, CMD_CLOSE_SOCKET), or None."""
        decoder, platform, clock = self.decoder, self.server.platform, self.server.clock
        now: float | None = None  # one simulated time for the telegrams of one read, the ticks due run first
        while (telegram := decoder.next_telegram()) is not None:
            if now is None:
                now = clock.now()
            outcome = platform.handle(telegram, now)
            if outcome.frame is not None:
                replies.append(outcome.frame)
            elif outcome.reply is not None:
                replies.append(encode(outcome.reply))
            if outcome.exit_server:
                self.server.stop()
                return "CMD_EXIT: server exits"
            if outcome.close_connection:
                return "CMD_CLOSE_SOCKET: connection closed"
        return None

    # ---- the stall timeout of a partial frame
    def _arm_stall(self) -> None:
        """(Re)start the partial frame's timeout; one timer per connection, moved only when it fires early."""
        self.stall_at = self.loop.time() + self.server.stall_timeout
        if self.stall_timer is None:
            self.stall_timer = self.loop.call_at(self.stall_at, self._stall_check)

    def _stall_check(self) -> None:
        self.stall_timer = None
        if self.closing or self.stall_at is None:
            return
        if self.loop.time() < self.stall_at:  # data came since: wait for the new deadline
            self.stall_timer = self.loop.call_at(self.stall_at, self._stall_check)
            return
        timeout = self.server.stall_timeout
        self._end(
            logging.INFO, "partial frame stalled for %g s (%d bytes); connection closed", timeout, self.decoder.pending
        )

    # ---- writing
    def _write(self, replies: list[bytes]) -> None:
        if not replies:
            return
        if self.out:
            self.out += b"".join(replies)
            return
        data = replies[0] if len(replies) == 1 else b"".join(replies)
        if not self.nodelay:  # replies go out at once (asyncio sets it on every TCP transport); set at the first
            self.nodelay = True
            with contextlib.suppress(OSError):
                self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        try:
            sent = self.sock.send(data, _DONTWAIT)
        except (BlockingIOError, InterruptedError):
            sent = 0
        except OSError as exc:
            self._end(logging.WARNING, "%s; connection closed", exc)
            return
        if sent < len(data):
            self.out += data[sent:]
            self.writing = True
            self.loop.add_writer(self.fd, self._writable)

    def _writable(self) -> None:
        try:
            sent = self.sock.send(self.out, _DONTWAIT)
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:
            self.out.clear()
            self._end(logging.WARNING, "%s; connection closed", exc)
            return
        del self.out[:sent]
        if self.out:
            if not self.closing and not self.reading and len(self.out) <= LOW_WATER:
                self._resume_reading()
            return
        self.writing = False
        self.loop.remove_writer(self.fd)
        if self.closing:
            self._close()
        elif not self.reading:
            self._resume_reading()

    # ---- the end
    def _end(self, level: int | None, msg: str = "", *args: object) -> None:
        """No more input: log why, free the port, close once the replies owed are sent."""
        if self.closing:
            return
        if level is not None and log.isEnabledFor(level):
            log.log(level, "client %s at port %d: " + msg, self.peer, self.port, *args)
        self.closing = True
        self.stall_at = None
        if self.stall_timer is not None:
            self.stall_timer.cancel()
            self.stall_timer = None
        self._pause_reading()
        self.server._released(self)
        if not self.writing:
            self._close()

    def _close(self) -> None:
        if self.writing:
            self.writing = False
            self.loop.remove_writer(self.fd)
        self.server._closed(self)
        self.sock.close()

    def abort(self) -> None:
        """The server stops: send what the socket takes at once, then close."""
        if self.out:
            with contextlib.suppress(OSError):
                self.sock.send(self.out, _DONTWAIT)
        self.closing = True
        if self.stall_timer is not None:
            self.stall_timer.cancel()
            self.stall_timer = None
        self._pause_reading()
        self._close()


R = TypeVar("R", bound="Runnable")


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
    return await serve_until_stopped(server, ready, handle_signals)


class Runnable(Protocol):
    """What ``serve_until_stopped`` runs: a server of one platform or of a fleet."""

    async def start(self) -> object: ...
    async def run(self) -> int: ...
    def stop(self) -> None: ...


async def serve_until_stopped(
    server: R, ready: Callable[[R], None] | None, handle_signals: bool, what: str = "server"
) -> int:
    """Start ``server``, stop it at SIGINT/SIGTERM (``handle_signals``), tell ``ready``, run it to its exit code."""
    await server.start()
    if handle_signals:
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, _on_signal, server, sig, what)
    if ready is not None:
        ready(server)
    return await server.run()


def _on_signal(server: Runnable, sig: signal.Signals, what: str) -> None:
    log.info("%s received: %s exits", sig.name, what)
    server.stop()


def run(platform: Platform, host: str, ports: Sequence[int], time_scale: float = 1.0, **options: object) -> int:
    """Blocking entry point for the command line."""
    return asyncio.run(serve(platform, host, ports, time_scale, **options))  # type: ignore[arg-type]


__all__ = [
    "CONTROL_PERIOD",
    "MAX_CATCH_UP",
    "STALL_TIMEOUT",
    "Runnable",
    "Server",
    "SimClock",
    "run",
    "serve",
    "serve_until_stopped",
]
