"""The forwarding core of ``pltf proxy``: asyncio, and the only module of the proxy with sockets and a clock.

Rules:
- Bytes first: a chunk is sent on to the other side as soon as it is read, unchanged (no reframing, no
  reassembly), and only then reported to the observer (the recorder: decode, view, session file, pcapng).
- Connections are plain non-blocking sockets on the loop's selector (``add_reader``), like the reference
  server's: no transport or protocol objects on the data path, one read and one send per chunk.
- Flow control: bytes the other side does not take yet wait in a buffer; above ``HIGH_WATER`` buffered bytes
  reading from the sending side pauses until the buffer is below ``LOW_WATER``, so a slow reader slows its
  sender as it would without the proxy.
- Ends travel: a FIN from one side becomes a FIN to the other once what it still had to send is sent
  (half-close); a reset becomes a reset (SO_LINGER 0). When both directions have ended, or one side is gone,
  both sockets close. A target that cannot be reached closes the client at once.
- One client connection, one target connection, on the route it arrived on; the proxy adds no policy of its
  own (a second client on a busy port is the target's to turn away, guide 6.1). When the target refuses a
  connection (its port no longer listens: CMD_EXIT, a restart), the proxy stops listening on that route too
  and listens again once the target accepts a probe (every ``PROBE_EVERY`` s): a client sees the port as it is.
- The proxy never dies of what passes through it: the observer is handed bytes after they are forwarded;
  should it fail, the failure is reported once and recording stops while forwarding goes on.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import socket
import struct
import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

FLUSH_EVERY = 0.25  # s between flushes of the observer (session file, pcapng, view)
READ_SIZE = 65536
HIGH_WATER = 1 << 20  # bytes waiting for a side above which reading from the other side pauses
LOW_WATER = 1 << 18
BACKLOG = 100
PROBE_EVERY = 0.5  # s between probes of a target that refused a connection
_LINGER_RESET = struct.pack("ii", 1, 0)


@dataclass(frozen=True)
class Route:
    listen_host: str
    listen_port: int
    target_host: str
    target_port: int


class _Conn:
    """One proxied connection: ``socks[True]`` is the client's socket (what it sends goes client -> target)."""

    def __init__(self, proxy: ProxyServer, number: int, route: Route, client: socket.socket, peer: Any) -> None:
        self.proxy, self.number, self.route = proxy, number, route
        self.loop = proxy.loop
        self.peer = (str(peer[0]), int(peer[1])) if isinstance(peer, tuple) else ("?", 0)
        self.socks: dict[bool, socket.socket | None] = {True: client, False: None}
        self.pending: dict[bool, bytearray] = {True: bytearray(), False: bytearray()}  # to send to that side
        self.eof: dict[bool, bool] = {True: False, False: False}  # that side sent its FIN
        self.shut: dict[bool, bool] = {True: False, False: False}  # we sent our FIN to that side
        self.paused: dict[bool, bool] = {True: False, False: False}  # reading from that side paused
        self.ended: str | None = None
        self.ended_at = 0.0
        self.done = False

    # ------------------------------------------------------------------ set-up
    async def connect(self) -> None:
        r = self.route
        try:
            infos = await self.loop.getaddrinfo(r.target_host, r.target_port, type=socket.SOCK_STREAM)
            family, kind, proto, _, addr = infos[0]
            sock = socket.socket(family, kind, proto)
            sock.setblocking(False)
            try:
                await self.loop.sock_connect(sock, addr)
            except BaseException:
                sock.close()
                raise
        except OSError as exc:
            self.proxy.observe(
                "opened", self.number, time.time(), r.target_port, self.peer, (r.target_host, r.target_port)
            )
            self._end(f"by proxy (target unreachable: {exc.strerror or exc})")
            self._close_all()
            if isinstance(exc, ConnectionRefusedError):
                self.proxy.target_refused(r)
            return
        _nodelay(sock)
        self.socks[False] = sock
        self.proxy.observe("opened", self.number, time.time(), r.target_port, self.peer, (r.target_host, r.target_port))
        for side in (True, False):
            self._reading(side, True)

    def _reading(self, side: bool, on: bool) -> None:
        sock = self.socks[side]
        if sock is None:
            return
        if on:
            self.loop.add_reader(sock, self._readable, side)
        else:
            self.loop.remove_reader(sock)

    # ------------------------------------------------------------------ data
    def _readable(self, side: bool) -> None:
        sock = self.socks[side]
        if sock is None:
            return
        try:
            data = sock.recv(READ_SIZE)
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:
            self._reset_by(side, exc)
            return
        if not data:
            self._eof_from(side)
            return
        self._send(not side, data)
        self.proxy.observe("data", self.number, time.time(), side, data)

    def _send(self, side: bool, data: bytes) -> None:
        """Bytes for ``side`` (True: the client): now when it takes them, else when it can."""
        sock, buf = self.socks[side], self.pending[side]
        if sock is None:
            return
        if not buf:
            try:
                n = sock.send(data)
            except (BlockingIOError, InterruptedError):
                n = 0
            except OSError as exc:
                self._reset_by(side, exc)
                return
            if n == len(data):
                return
            data = data[n:]
            self.loop.add_writer(sock, self._writable, side)
        buf += data
        if len(buf) > HIGH_WATER and not self.paused[not side]:
            self.paused[not side] = True
            self._reading(not side, False)

    def _writable(self, side: bool) -> None:
        sock, buf = self.socks[side], self.pending[side]
        if sock is None:
            return
        try:
            n = sock.send(buf)
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:
            self._reset_by(side, exc)
            return
        del buf[:n]
        if self.paused[not side] and len(buf) < LOW_WATER and not self.eof[not side]:
            self.paused[not side] = False
            self._reading(not side, True)
        if not buf:
            self.loop.remove_writer(sock)
            if self.eof[not side]:
                self._shutdown(side)

    # ------------------------------------------------------------------ ends
    def _end(self, how: str) -> None:
        """The first end (a FIN, a reset, a failed connect, the proxy stopping) is how the connection ended."""
        if self.ended is None:
            self.ended, self.ended_at = how, time.time()

    def _eof_from(self, side: bool) -> None:
        self._end(f"by {'client' if side else 'target'} (FIN)")
        self.eof[side] = True
        self._reading(side, False)
        self.proxy.observe("half_closed", self.number, time.time(), side)
        if not self.pending[not side]:
            self._shutdown(not side)

    def _shutdown(self, side: bool) -> None:
        """Our FIN to ``side`` (its peer sent one and everything before it is delivered)."""
        sock = self.socks[side]
        if sock is None or self.shut[side]:
            return
        self.shut[side] = True
        with contextlib.suppress(OSError):
            sock.shutdown(socket.SHUT_WR)
        if self.eof[side] and self.eof[not side] and not any(self.pending.values()):
            self._close_all()

    def _reset_by(self, side: bool, exc: OSError) -> None:
        """``side`` reset the connection (or is gone): the other side gets a reset too."""
        self._end(f"by {'client' if side else 'target'} (reset: {exc.strerror or exc})")
        self._close_all(reset=True)

    def _close_all(self, reset: bool = False) -> None:
        for side in (True, False):
            sock = self.socks[side]
            if sock is None:
                continue
            self.loop.remove_reader(sock)
            self.loop.remove_writer(sock)
            if reset:
                with contextlib.suppress(OSError):
                    sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, _LINGER_RESET)
            with contextlib.suppress(OSError):
                sock.close()
            self.socks[side] = None
        self._finish()

    def stop(self) -> None:
        self._end("by proxy (stopped)")
        self._close_all()

    def _finish(self) -> None:
        if self.done:
            return
        self.done = True
        self.proxy.conns.discard(self)
        self._end("by proxy (closed)")
        self.proxy.observe("closed", self.number, time.time(), self.ended, self.ended_at)


def _nodelay(sock: socket.socket) -> None:
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)


class ProxyServer:
    """Listens on each route and forwards; ``observer`` (a Recorder, or its pipe to a recorder process) gets
    ``opened``/``data``/``half_closed``/``closed`` calls after the bytes moved, ``flush`` now and then, ``close``
    at the end."""

    def __init__(self, routes: list[Route], observer: Any = None, flush: Callable[[], None] | None = None) -> None:
        self.routes = routes
        self.observer = observer
        self.flush_extra = flush
        self.conns: set[_Conn] = set()
        self.tasks: set[asyncio.Task[Any]] = set()
        self.listening: list[tuple[str, int]] = []
        self._listeners: dict[Route, socket.socket] = {}
        self._numbers = itertools.count(1)
        self._stopped = asyncio.Event()
        self.loop = asyncio.get_running_loop()

    def observe(self, what: str, *args: Any) -> None:
        """Hand an event to the observer; a failure stops recording, never forwarding."""
        if self.observer is None:
            return
        try:
            getattr(self.observer, what)(*args)
        except Exception:  # the proxy never dies of what passes through it
            print(
                "pltf proxy: internal error while recording; recording stopped, forwarding goes on:\n"
                + traceback.format_exc(limit=3),
                file=sys.stderr,
            )
            self.observer = None

    async def start(self) -> list[tuple[str, int]]:
        for route in self.routes:
            sock = self._listen(route, route.listen_port)
            self.listening.append(sock.getsockname()[:2])
        self._spawn(self._flusher())
        return self.listening

    def _listen(self, route: Route, port: int) -> socket.socket:
        sock = socket.create_server((route.listen_host, port), backlog=BACKLOG)
        sock.setblocking(False)
        self._listeners[route] = sock
        self.loop.add_reader(sock, self._accept, sock, route)
        return sock

    def target_refused(self, route: Route) -> None:
        """The target's port does not listen: neither does ours, until a probe finds it listening again."""
        sock = self._listeners.pop(route, None)
        if sock is None or self._stopped.is_set():
            return
        port = sock.getsockname()[1]
        self.loop.remove_reader(sock)
        sock.close()
        self._spawn(self._relisten(route, port))

    async def _relisten(self, route: Route, port: int) -> None:
        while not self._stopped.is_set():
            await asyncio.sleep(PROBE_EVERY)
            try:
                _, writer = await asyncio.open_connection(route.target_host, route.target_port)
            except OSError:
                continue
            writer.close()
            with contextlib.suppress(OSError):
                self._listen(route, port)
                return

    def _spawn(self, coro: Any) -> None:
        task = self.loop.create_task(coro)
        self.tasks.add(task)
        task.add_done_callback(self.tasks.discard)

    def _accept(self, listener: socket.socket, route: Route) -> None:
        for _ in range(BACKLOG):
            try:
                client, peer = listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:  # out of descriptors: try again later
                print(f"pltf proxy: accept failed: {exc.strerror or exc}", file=sys.stderr)
                return
            client.setblocking(False)
            _nodelay(client)
            conn = _Conn(self, next(self._numbers), route, client, peer)
            self.conns.add(conn)
            self._spawn(conn.connect())

    async def _flusher(self) -> None:
        while True:
            await asyncio.sleep(FLUSH_EVERY)
            self.flush()

    def flush(self) -> None:
        self.observe("flush")
        if self.flush_extra is not None:
            self.flush_extra()

    async def wait_stopped(self) -> None:
        await self._stopped.wait()

    def request_stop(self) -> None:
        self._stopped.set()

    async def close(self) -> None:
        self._stopped.set()
        for sock in self._listeners.values():
            self.loop.remove_reader(sock)
            sock.close()
        self._listeners.clear()
        for conn in list(self.conns):
            conn.stop()
        for task in list(self.tasks):
            task.cancel()
        await asyncio.sleep(0)
        self.observe("close", time.time())
        if self.flush_extra is not None:
            self.flush_extra()
