"""The forwarding core of ``pltf proxy``: asyncio, and the only module of the proxy with sockets and a clock.

Rules:
- Bytes first: a chunk is written to the other side as soon as it arrives, unchanged (no reframing, no
  reassembly), and only then handed to the recorder (decode, view, session file, pcapng).
- Flow control: when one side's write buffer is above asyncio's high-water mark, reading from the other side
  pauses until it drains, so a slow reader slows its sender as it would without the proxy.
- Ends travel: a FIN from one side becomes a FIN to the other (half-close); a reset becomes a reset (abort);
  when both directions have ended, or one side is gone, the connection ends on both sides. A target that
  cannot be reached closes the client at once.
- One client connection, one target connection, on the route it arrived on; the proxy adds no policy of its
  own (a second client on a busy port is the target's to turn away, guide 6.1).
- The proxy never dies of what passes through it: the recorder is sans-IO and handles malformed bytes; should
  it fail anyway, the failure is reported once and recording stops while forwarding goes on.
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

from pltf.proxy.recorder import Recorder

FLUSH_EVERY = 0.25  # s between flushes of the session file, the pcapng and the view


@dataclass(frozen=True)
class Route:
    listen_host: str
    listen_port: int
    target_host: str
    target_port: int


def _reset(transport: asyncio.Transport) -> None:
    """Close with a reset (RST), as the peer did: SO_LINGER 0, then abort (asyncio alone would send a FIN)."""
    sock = transport.get_extra_info("socket")
    if sock is not None:
        with contextlib.suppress(OSError):
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    transport.abort()


class _Side(asyncio.Protocol):
    """One of the two sockets of a proxied connection; ``c2s``: what it receives goes client -> target."""

    def __init__(self, pair: _Pair, c2s: bool) -> None:
        self.pair, self.c2s = pair, c2s
        self.transport: asyncio.Transport | None = None
        self.eof = False  # its peer sent FIN
        self.lost = False

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        if self.c2s:
            self.pair.client_connected(self)

    def data_received(self, data: bytes) -> None:
        self.pair.forward(self, data)

    def eof_received(self) -> bool:
        self.pair.eof(self)
        return True  # keep writing the other direction

    def connection_lost(self, exc: Exception | None) -> None:
        self.pair.lost(self, exc)

    def pause_writing(self) -> None:
        self.pair.throttle(self, pause=True)

    def resume_writing(self) -> None:
        self.pair.throttle(self, pause=False)


class _Pair:
    def __init__(self, proxy: ProxyServer, conn: int, route: Route) -> None:
        self.proxy, self.conn, self.route = proxy, conn, route
        self.client: _Side | None = None
        self.target: _Side | None = None
        self.ended: str | None = None  # how it ended, as the close record says it
        self.ended_at = 0.0  # when one side ended it first (the close record's time)
        self.done = False

    def other(self, side: _Side) -> _Side | None:
        return self.target if side.c2s else self.client

    def end(self, how: str) -> None:
        """The first end of the connection (a FIN, a reset, a failed connect, the proxy stopping) is how it ended."""
        if self.ended is None:
            self.ended, self.ended_at = how, time.time()

    def client_connected(self, side: _Side) -> None:
        self.client = side
        assert side.transport is not None
        side.transport.pause_reading()  # until the target is connected
        self.proxy.pairs.add(self)
        self.proxy.tasks.add(task := asyncio.get_running_loop().create_task(self._connect()))
        task.add_done_callback(self.proxy.tasks.discard)

    async def _connect(self) -> None:
        assert self.client is not None and self.client.transport is not None
        r = self.route
        peer = self.client.transport.get_extra_info("peername") or ("?", 0)
        loop = asyncio.get_running_loop()
        try:
            _, side = await loop.create_connection(lambda: _Side(self, False), r.target_host, r.target_port)
        except OSError as exc:
            self.proxy.observe("opened", self.conn, time.time(), r.target_port, (peer[0], peer[1]),
                               (r.target_host, r.target_port))  # fmt: skip
            self.end(f"by proxy (target unreachable: {exc.strerror or exc})")
            self.client.transport.close()
            return
        self.target = side
        self.proxy.observe("opened", self.conn, time.time(), r.target_port, (peer[0], peer[1]),
                           (r.target_host, r.target_port))  # fmt: skip
        if self.client.lost:  # the client left while we connected
            self.end("by client (before the target answered)")
            assert side.transport is not None
            side.transport.close()
            return
        self.client.transport.resume_reading()

    def forward(self, side: _Side, data: bytes) -> None:
        other = self.other(side)
        if other is not None and other.transport is not None and not other.lost:
            other.transport.write(data)
        self.proxy.observe("data", self.conn, time.time(), side.c2s, data)

    def eof(self, side: _Side) -> None:
        side.eof = True
        who = "client" if side.c2s else "target"
        self.end(f"by {who} (FIN)")
        other = self.other(side)
        if other is not None and other.transport is not None and not other.lost and other.transport.can_write_eof():
            other.transport.write_eof()
        self.proxy.observe("half_closed", self.conn, time.time(), side.c2s)
        if other is not None and other.eof:
            self._close_both()

    def lost(self, side: _Side, exc: Exception | None) -> None:
        side.lost = True
        who = "client" if side.c2s else "target"
        self.end(f"by {who} (reset: {exc})" if exc is not None else f"by {who} (closed)")
        other = self.other(side)
        if other is not None and other.transport is not None and not other.lost:
            if exc is not None:
                _reset(other.transport)
            else:
                other.transport.close()  # after what it still has to write
        if other is None or other.lost or other.transport is None:
            self._finish()

    def throttle(self, side: _Side, pause: bool) -> None:
        other = self.other(side)
        if other is not None and other.transport is not None and not other.lost:
            with contextlib.suppress(RuntimeError):
                (other.transport.pause_reading if pause else other.transport.resume_reading)()

    def _close_both(self) -> None:
        for s in (self.client, self.target):
            if s is not None and s.transport is not None and not s.lost:
                s.transport.close()

    def stop(self) -> None:
        self.end("by proxy (stopped)")
        self._close_both()

    def _finish(self) -> None:
        if self.done:
            return
        self.done = True
        self.proxy.pairs.discard(self)
        if self.target is not None or self.ended is not None:
            self.end("by proxy (closed)")
            self.proxy.observe("closed", self.conn, time.time(), self.ended, self.ended_at)


class ProxyServer:
    def __init__(self, routes: list[Route], recorder: Recorder | None = None,
                 flush: Callable[[], None] | None = None) -> None:  # fmt: skip
        self.routes = routes
        self.recorder = recorder
        self.flush_extra = flush
        self.pairs: set[_Pair] = set()
        self.tasks: set[asyncio.Task[Any]] = set()
        self.listening: list[tuple[str, int]] = []
        self._servers: list[asyncio.Server] = []
        self._numbers = itertools.count(1)
        self._stopped = asyncio.Event()

    def observe(self, what: str, *args: Any) -> None:
        """Hand an event to the recorder; a recorder failure stops recording, never forwarding."""
        if self.recorder is None:
            return
        try:
            getattr(self.recorder, what)(*args)
        except Exception:  # the proxy never dies of what passes through it
            print("pltf proxy: internal error while recording; recording stopped, forwarding goes on:\n"
                  + traceback.format_exc(limit=3), file=sys.stderr)  # fmt: skip
            self.recorder = None

    async def start(self) -> list[tuple[str, int]]:
        loop = asyncio.get_running_loop()
        for route in self.routes:
            server = await loop.create_server(self._factory(route), route.listen_host, route.listen_port)
            self._servers.append(server)
            host, port = server.sockets[0].getsockname()[:2]
            self.listening.append((host, port))
        self.tasks.add(task := loop.create_task(self._flusher()))
        task.add_done_callback(self.tasks.discard)
        return self.listening

    def _factory(self, route: Route) -> Callable[[], _Side]:
        return lambda: _Side(_Pair(self, next(self._numbers), route), True)

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
        for server in self._servers:
            server.close()
        for pair in list(self.pairs):
            pair.stop()
        await asyncio.sleep(0.05)  # let the closes reach the recorder
        for task in list(self.tasks):
            task.cancel()
        for server in self._servers:
            with contextlib.suppress(Exception):
                await server.wait_closed()
        if self.recorder is not None:
            self.observe("close", time.time())
        if self.flush_extra is not None:
            self.flush_extra()
