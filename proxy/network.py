"""The forwarding core of ``pltf proxy``, and the only module of the proxy with sockets and a clock.

Rules:
- Bytes first: a chunk read is sent on at once, unchanged (no reframing, no reassembly). Two forwarding cores:
  - the C loop (``_forward.c``, built with the package; ``ProxyServer(threads=False)``, the default when it is
    importable): one thread per connection moves both directions with the GIL released and, after it moved
    bytes, polls both sockets for ``SPIN_US`` (yielding the CPU between polls) before it sleeps in ``poll``, so
    the next request or the reply is picked up without a thread wakeup, which on a virtual machine costs about
    as much as the reference server takes to answer (proxy/README.md, "Measured");
  - Python threads (the fallback, and ``threads=True``): each direction is one thread blocking in ``recv`` and
    ``sendall`` (the GIL is released while blocked, so a hop costs a wakeup and two system calls, not a turn of
    an event loop).
  The observer (the recorder: decode, view, session file, pcapng) gets each chunk with the time it was read:
  the Python threads queue it between reading and sending (an append to a deque, which the event loop delivers
  every ``DELIVER_EVERY`` s, or a pack and an append for the recorder process's pipe); the C loop keeps a copy
  before it sends and hands its copies over in order when it is about to sleep, before it reports an end, and
  every 20 ms while bytes flow (a call into Python per chunk cost more than the hop saves). Kept before it is
  sent, a request is always recorded before the reply it causes (queued after, the other direction's thread
  could get in first); recording never holds up a forwarded byte.
- The event loop (asyncio) does the rest: listening, accepting, connecting to the target, probing a target
  that refused, delivering to the observer, stopping.
- Flow control: a direction whose chunk waits for its receiver does not read (the C loop goes on with the other
  direction; a Python thread blocks in ``sendall``); what the slow side does not take stays in the kernel's
  buffers, so a slow reader slows its sender as it would without the proxy.
- Ends travel: a FIN from one side becomes a FIN to the other (everything before it was sent already:
  half-close); a reset becomes a reset (SO_LINGER 0). When both directions have ended, or one side is gone,
  both sockets close; the last thread of the connection closes them. A target that cannot be reached closes the
  client at once.
- One client connection, one target connection, on the route it arrived on; the proxy adds no policy of its
  own (a second client on a busy port is the target's to turn away, guide 6.1). The order of connections
  travels too: a new connection reaches the target only after the earlier ones on its route have passed on
  what their clients had sent when it arrived, their FINs included (at most ``ORDER_WAIT`` s). A client that
  closes and reconnects at once is not turned away through the proxy when it would not be without it: its
  FIN would otherwise wait for a forwarding thread (the interpreter, a full recorder pipe) while the accepting
  loop already connects the next. When the target refuses a connection (its port no longer listens:
  CMD_EXIT, a restart), the proxy stops listening on that route too and listens again once the target accepts
  a probe (every ``PROBE_EVERY`` s): a client sees the port as it is.
- The proxy never dies of what passes through it: should the observer fail, the failure is reported once and
  recording stops while forwarding goes on.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import itertools
import os
import socket
import struct
import sys
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

try:
    from pltf.proxy import _forward

    HAVE_C = True
except ImportError:  # not built (a source checkout without a compiler): the Python threads forward
    HAVE_C = False

DELIVER_EVERY = 0.02  # s between deliveries of the queued events to the observer
FLUSH_EVERY = 0.25  # s between flushes of the observer (session file, pcapng, view) when nothing happens
READ_SIZE = 65536
BACKLOG = 100
PROBE_EVERY = 0.5  # s between probes of a target that refused a connection
ORDER_WAIT = 1.0  # s a new connection waits at most for the earlier ones on its route to pass their input on
ORDER_POLL = 0.001  # s between looks while it waits for bytes its thread has not read (an end passed on wakes it)
STOP_WAIT = 2.0  # s the proxy waits, when it stops, for a connection's threads to leave
SPIN_US = 200  # us the C loop keeps polling after it moved bytes (0-400 measured: proxy/README.md, "Measured")
MAX_SPIN_US = 1_000_000
_LINGER_RESET = struct.pack("ii", 1, 0)


@dataclass(frozen=True)
class Route:
    listen_host: str
    listen_port: int
    target_host: str
    target_port: int


def _who(side: bool) -> str:
    return "client" if side else "target"


class _Conn:
    """One proxied connection: ``socks[True]`` is the client's socket (what it sends goes client -> target).

    The two forwarding threads and the loop (``stop``) meet under ``lock``: the first end decides how the
    connection ended; ``closing`` tells a thread woken by the teardown to leave without a word."""

    def __init__(self, proxy: ProxyServer, number: int, route: Route, client: socket.socket, peer: Any) -> None:
        self.proxy, self.number, self.route = proxy, number, route
        self.accepted_at = time.time()  # the open's time: connections open in the order they were accepted
        self.peer = (str(peer[0]), int(peer[1])) if isinstance(peer, tuple) else ("?", 0)
        self.socks: dict[bool, socket.socket | None] = {True: client, False: None}
        self.eof: dict[bool, bool] = {True: False, False: False}  # that side sent its FIN
        self.lock = threading.Lock()
        self.threads: list[threading.Thread] = []
        self.running = 0  # forwarding threads not yet finished
        self.closing = False  # torn down (a reset, the proxy stopping): the threads leave
        self.reset = False  # the teardown resets both sides (SO_LINGER 0)
        self.ended: str | None = None
        self.ended_at = 0.0
        self.done = False
        self.wake = -1  # the C loop's eventfd: written by the teardown, it returns at once
        self.watchers: list[Callable[[], None]] = []  # newer connections waiting for its client's end (the loop's)

    # ------------------------------------------------------------------ set-up
    async def connect(self) -> None:
        r, loop = self.route, self.proxy.loop
        await self._after_earlier()
        try:
            infos = await loop.getaddrinfo(r.target_host, r.target_port, type=socket.SOCK_STREAM)
            family, kind, proto, _, addr = infos[0]
            sock = socket.socket(family, kind, proto)
            sock.setblocking(False)
            try:
                await loop.sock_connect(sock, addr)
            except BaseException:
                sock.close()
                raise
        except OSError as exc:
            self._opened()
            with self.lock:
                self._end(f"by proxy (target unreachable: {exc.strerror or exc})")
                self._close_all()
            if isinstance(exc, ConnectionRefusedError):
                self.proxy.target_refused(r)
            return
        with self.lock:
            if self.closing:  # the proxy stopped while we connected
                sock.close()
                return
            _nodelay(sock)
            self.socks[False] = sock
            self._opened()
            fast = not self.proxy.threads
            for side in (True, False):
                s = self.socks[side]
                assert s is not None
                s.setblocking(not fast)
            if fast:
                self.wake = os.eventfd(0, os.EFD_NONBLOCK | os.EFD_CLOEXEC)
                self.running = 1
                runs: list[tuple[str, Callable[..., None], tuple[Any, ...]]] = [(f"proxy-{self.number}", self._run, ())]
            else:
                self.running = 2
                runs = [(f"proxy-{self.number}-{'c2s' if s else 's2c'}", self._pump, (s,)) for s in (True, False)]
            for name, target, args in runs:
                thread = threading.Thread(target=target, args=args, name=name, daemon=True)
                self.threads.append(thread)
                thread.start()

    async def _after_earlier(self) -> None:
        """Wait (at most ``ORDER_WAIT`` s) until the earlier connections of this route have passed on what
        their clients sent before this one arrived: the target sees the ends and the opens in the client's order."""
        earlier = [c for c in self.proxy.conns if c.route == self.route and c.number < self.number]
        deadline = time.monotonic() + ORDER_WAIT
        woken = asyncio.Event()
        try:
            while earlier and (left := deadline - time.monotonic()) > 0:
                woken.clear()
                for c in earlier:  # before the look: an end passed on after it wakes us
                    if woken.set not in c.watchers:
                        c.watchers.append(woken.set)
                earlier = [c for c in earlier if not c.passed_on()]
                if earlier:
                    with contextlib.suppress(TimeoutError):
                        await asyncio.wait_for(woken.wait(), min(left, ORDER_POLL))
        finally:
            for c in self.proxy.conns:
                with contextlib.suppress(ValueError):
                    c.watchers.remove(woken.set)

    def passed_on(self) -> bool:
        """Nothing its client sent waits in the proxy: it is connected to the target and its FIN was passed on,
        or its socket has nothing unread (a look that takes nothing). Not while a forwarding thread holds the lock
        (it may be passing an end on)."""
        if not self.lock.acquire(blocking=False):
            return False
        try:
            client = self.socks[True]
            if client is None or self.closing or self.eof[True]:
                return True
            if self.socks[False] is None:
                return False  # still connecting: its open goes first
            try:
                client.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT)
            except (BlockingIOError, InterruptedError):
                return True  # nothing unread: the client is still there and quiet
            except OSError:
                return True  # a failed socket: its thread ends the connection
            return False  # bytes or a FIN not yet taken by its thread
        finally:
            self.lock.release()

    def _opened(self) -> None:
        r = self.route
        self.proxy.observe(
            "opened", self.number, self.accepted_at, r.target_port, self.peer, (r.target_host, r.target_port)
        )

    # ------------------------------------------------------------------ data (one thread per direction)
    def _forward(self, side: bool) -> tuple[bool, OSError] | None:
        """Chunks from ``side`` to the other until ``side``'s FIN (None) or a failure (whose side, the error)."""
        src, dst = self.socks[side], self.socks[not side]
        assert src is not None and dst is not None
        observe, number, clock = self.proxy.observe, self.number, time.time
        recv, sendall = src.recv, dst.sendall
        while True:
            try:
                data = recv(READ_SIZE)
            except OSError as exc:
                return side, exc
            if not data:
                return None
            observe("data", number, clock(), side, data)  # before the send: a reply is never queued before its request
            try:
                sendall(data)
            except OSError as exc:
                return not side, exc

    def _run(self) -> None:
        """The C loop, both directions (``_forward.run``): ends and failures are handled here as ``_pump`` does."""
        client, target = self.socks[True], self.socks[False]
        assert client is not None and target is not None
        observe, number = self.proxy.observe, self.number

        def data(chunks: list[tuple[bool, float, bytes]]) -> None:  # kept before they were sent, in order
            for side, when, chunk in chunks:
                observe("data", number, when, side, chunk)

        def eof(side: bool) -> bool:
            with self.lock:
                if not self.closing:
                    self._eof_from(side)
                return self.closing

        failed = _forward.run(client.fileno(), target.fileno(), self.wake, self.proxy.spin_us, data, eof)
        with self.lock:
            self.running = 0
            if failed is not None and not self.closing:
                side, err = failed
                self._reset_by(side, OSError(err, os.strerror(err)))
            self.closing = True
            self._close_all()

    def _pump(self, side: bool) -> None:
        failed = self._forward(side)
        with self.lock:
            self.running -= 1
            if self.closing:
                pass  # woken by the teardown
            elif failed is not None:
                self._reset_by(*failed)
            else:
                self._eof_from(side)
            if self.closing and self.running == 0:
                self._close_all()

    # ------------------------------------------------------------------ ends (under ``lock``)
    def _end(self, how: str) -> None:
        """The first end (a FIN, a reset, a failed connect, the proxy stopping) is how the connection ended."""
        if self.ended is None:
            self.ended, self.ended_at = how, time.time()

    def _eof_from(self, side: bool) -> None:
        """``side`` sent its FIN; all it sent before is sent on: our FIN to the other side."""
        self._end(f"by {_who(side)} (FIN)")
        self.eof[side] = True
        self.proxy.observe("half_closed", self.number, time.time(), side)
        other = self.socks[not side]
        if other is not None:
            with contextlib.suppress(OSError):
                other.shutdown(socket.SHUT_WR)
        if side:
            self._tell_watchers()
        if self.eof[not side]:
            self.closing = True

    def _tell_watchers(self) -> None:
        """Its client's input is passed on (or never will be): wake the newer connections waiting for it."""
        watchers, self.watchers = self.watchers, []
        for wake in watchers:
            with contextlib.suppress(RuntimeError):  # the loop is closed: the proxy has stopped
                self.proxy.loop.call_soon_threadsafe(wake)

    def _reset_by(self, side: bool, exc: OSError) -> None:
        """``side`` reset the connection (or is gone): the other side gets a reset too."""
        self._end(f"by {_who(side)} (reset: {exc.strerror or exc})")
        self._teardown(reset=True)

    def _teardown(self, reset: bool) -> None:
        """Wake a thread still blocked in ``recv`` (SHUT_RD says nothing on the wire; SHUT_RDWR sends FINs)."""
        self.closing, self.reset = True, reset
        for sock in self.socks.values():
            if sock is not None:
                with contextlib.suppress(OSError):
                    sock.shutdown(socket.SHUT_RD if reset else socket.SHUT_RDWR)
        if self.wake >= 0:
            with contextlib.suppress(OSError):
                os.eventfd_write(self.wake, 1)

    def _close_all(self) -> None:
        for side in (True, False):
            sock = self.socks[side]
            if sock is None:
                continue
            if self.reset:
                with contextlib.suppress(OSError):
                    sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, _LINGER_RESET)
            with contextlib.suppress(OSError):
                sock.close()
            self.socks[side] = None
        if self.wake >= 0:
            with contextlib.suppress(OSError):
                os.close(self.wake)
            self.wake = -1
        self._tell_watchers()
        self._finish()

    def _finish(self) -> None:
        if self.done:
            return
        self.done = True
        self.proxy.conns.discard(self)
        self._end("by proxy (closed)")
        self.proxy.observe("closed", self.number, time.time(), self.ended, self.ended_at)

    # ------------------------------------------------------------------ the loop's side
    def stop(self) -> None:
        """The proxy stops: FINs to both sides; the threads leave and the last one closes."""
        with self.lock:
            self._end("by proxy (stopped)")
            if self.running:
                self._teardown(reset=False)
            else:
                self.closing = True
                self._close_all()

    def join(self, deadline: float) -> None:
        for thread in self.threads:
            thread.join(max(0.0, deadline - time.monotonic()))


def _nodelay(sock: socket.socket) -> None:
    with contextlib.suppress(OSError):
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)


class ProxyServer:
    """Listens on each route and forwards; ``observer`` (a Recorder, or its pipe to a recorder process) gets
    ``opened``/``data``/``half_closed``/``closed`` calls after the bytes moved, in the order they happened, from
    the loop's thread (``DELIVER_EVERY``), then ``flush``; ``close`` at the end."""

    def __init__(
        self,
        routes: list[Route],
        observer: Any = None,
        flush: Callable[[], None] | None = None,
        threads: bool = False,
        spin_us: int = SPIN_US,
    ) -> None:
        self.routes = routes
        self.threads = threads or not HAVE_C  # the Python threads forward (else the C loop)
        if not 0 <= spin_us <= MAX_SPIN_US:
            raise ValueError(f"spin_us: 0 to {MAX_SPIN_US}, got {spin_us}")
        self.spin_us = spin_us
        self.observer = observer
        self.flush_extra = flush
        self.conns: set[_Conn] = set()
        self.tasks: set[asyncio.Task[Any]] = set()
        self.listening: list[tuple[str, int]] = []
        self._listeners: dict[Route, socket.socket] = {}
        self._numbers = itertools.count(1)
        self._events: collections.deque[tuple[str, tuple[Any, ...]]] = collections.deque()
        self._direct = bool(getattr(observer, "threadsafe", False))  # may be called from the forwarding threads
        self._stopped = asyncio.Event()
        self.loop = asyncio.get_running_loop()

    def observe(self, what: str, *args: Any) -> None:
        """An event for the observer, from any thread: handed over at once to a ``threadsafe`` observer, else
        queued (a deque's append is atomic) for the loop to deliver."""
        if self._direct:
            self._call(what, args)
        else:
            self._events.append((what, args))

    def _call(self, what: str, args: tuple[Any, ...]) -> None:
        """A failure of the observer stops recording, never forwarding."""
        observer = self.observer
        if observer is None:
            return
        try:
            getattr(observer, what)(*args)
        except Exception:  # the proxy never dies of what passes through it
            if self.observer is not None:
                self.observer = None
                print(
                    "pltf proxy: internal error while recording; recording stopped, forwarding goes on:\n"
                    + traceback.format_exc(limit=3),
                    file=sys.stderr,
                )

    def deliver(self) -> bool:
        """Hand the queued events to the observer (the loop's thread); True when there were any."""
        events, delivered = self._events, False
        while events:
            what, args = events.popleft()
            delivered = True
            self._call(what, args)
        return delivered

    async def start(self) -> list[tuple[str, int]]:
        for route in self.routes:
            sock = self._listen(route, route.listen_port)
            self.listening.append(sock.getsockname()[:2])
        self._spawn(self._deliverer())
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
            _nodelay(client)
            conn = _Conn(self, next(self._numbers), route, client, peer)
            self.conns.add(conn)
            self._spawn(conn.connect())

    async def _deliverer(self) -> None:
        idle = 0.0
        while True:
            await asyncio.sleep(DELIVER_EVERY)
            idle += DELIVER_EVERY
            if self.deliver() or self._direct or idle >= FLUSH_EVERY:
                idle = 0.0
                self.flush()

    def flush(self) -> None:
        self.deliver()
        self._call("flush", ())
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
        for task in list(self.tasks):
            task.cancel()
        await asyncio.sleep(0)
        conns = list(self.conns)
        for conn in conns:
            conn.stop()
        deadline = time.monotonic() + STOP_WAIT
        for conn in conns:  # their last events (the closes) before the observer's close
            conn.join(deadline)
        self.observe("close", time.time())
        self.deliver()
        if self.flush_extra is not None:
            self.flush_extra()
