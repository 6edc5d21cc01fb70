"""The zoo's network shell: one listening socket per port of the target behind, the member's rules applied.

Rules:
- One asyncio loop in one thread. Port i of the relay leads to port i of the upstream; each client admitted
  gets its own upstream connection, opened when it is admitted and closed when it leaves (members.py: admit).
- Client -> target: a member that does not look at requests passes the bytes on as they come (a split frame
  stays split); one with a bug, a ``malformed`` rule or ``silent`` cuts whole frames first, shows each to the
  bug, closes at or skips a malformed one, swallows what comes before CMD_CONNECT_TO_PLTF - so it acts before
  the target does. A stream out of step is passed on raw (frames.py): the target behind judges it.
- Target -> client: passed on as it comes, or, for a member that shapes replies, cut into frames, held until
  due and written coalesced and in segments (schedule.py): with TCP_NODELAY and a gap between them each write
  is one send(), one segment on the wire.
- Half-close travels (a client's end-of-stream is passed on and the target may still answer) unless the member
  ends the session at it (``on_fin`` "end": both connections closed at once, replies not yet written lost); when
  the target closes, the client is closed after the replies still held for it - with a reset for ``close``
  "rst" (SO_LINGER 0, set when the client is admitted); a client silent for ``idle_drop`` seconds is closed.
- ``restart_every``: the accept loops and every client are cancelled, the ports closed, ``on_restart`` starts
  the target behind afresh (its new ports), and after ``restart_down`` seconds the same ports listen again.
- A member with ``accept_every`` accepts on a timer: every tick it takes all newcomers waiting in the backlog.
- A member with ``absurd`` rewrites the doubles of the position and status replies (values.py) as it passes them.
- A crash calls ``on_exit`` (the member stops the target it started) and ends the process with status 134; a
  hang blocks the loop's thread for ``hang_seconds`` and then ends the process the same way with status 3.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import random
import socket
import struct
import sys
import time
from collections.abc import Callable, Coroutine, Sequence
from dataclasses import dataclass, field
from typing import Any

from pltf.zoo.bugs import ID, Bug, Fault
from pltf.zoo.frames import FrameCutter, Piece, well_formed
from pltf.zoo.members import Member
from pltf.zoo.schedule import ReplySchedule, segments
from pltf.zoo.values import rewrite

CONNECT_TO_PLTF_ID = ID["CMD_CONNECT_TO_PLTF"]
SEGMENT_GAP = 0.001  # s between two writes of one chunk (slow link)
HALF_CLOSE_WAIT = 15.0  # s the target may take to answer and close after a client's end-of-stream


async def _guarded(pump: Coroutine[Any, Any, None]) -> bool:
    """Run one direction's pump; True when it ended at an end-of-stream, False when a socket failed."""
    try:
        await pump
    except (OSError, ConnectionError):
        return False
    return True


async def _pump(
    loop: asyncio.AbstractEventLoop, src: socket.socket, dst: socket.socket, *, eof: bool = True, idle: float = 0.0
) -> None:
    """``src`` to ``dst`` until ``src``'s end-of-stream, which is passed on (half-close) when ``eof``; with ``idle``,
    a ``src`` silent that long ends the pump (TimeoutError)."""
    while data := await _recv(loop, src, idle):
        await loop.sock_sendall(dst, data)
    if eof:
        with contextlib.suppress(OSError):
            dst.shutdown(socket.SHUT_WR)


async def _recv(loop: asyncio.AbstractEventLoop, src: socket.socket, idle: float) -> bytes:
    if idle <= 0:
        return await loop.sock_recv(src, 65536)
    return await asyncio.wait_for(loop.sock_recv(src, 65536), idle)


@dataclass
class PortState:
    index: int
    busy: bool = False
    free_at: float = 0.0
    idle: asyncio.Event = field(default_factory=asyncio.Event)


class Relay:
    def __init__(
        self,
        member: Member,
        upstream_host: str,
        upstream_ports: list[int],
        *,
        host: str = "127.0.0.1",
        ports: tuple[int, int] = (0, 0),
        seed: int = 1,
        hang_seconds: float = 600.0,
        on_exit: Callable[[], None] = lambda: None,
        on_restart: Callable[[], Sequence[int]] = lambda: (),
        log: Callable[[str], None] = print,
    ) -> None:
        self.member = member
        self.upstream = (upstream_host, list(upstream_ports))
        self.host, self.want = host, ports
        self.rng = random.Random(seed)
        self.bug: Bug | None = member.bug() if member.bug is not None else None
        self.hang_seconds = hang_seconds
        self.on_exit = on_exit
        self.on_restart = on_restart  # starts the target behind afresh; its new ports (empty: the same)
        self.log = log
        self.ports: list[int] = []
        self.served = [0, 0]  # clients admitted, per port
        self.refused = [0, 0]  # newcomers turned away, per port
        self._tasks: set[asyncio.Task[None]] = set()

    # ---- start
    def _listen(self, want: int) -> socket.socket:
        ls = socket.socket(socket.AF_INET6 if ":" in self.host else socket.AF_INET, socket.SOCK_STREAM)
        ls.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        if ":" in self.host:  # row 12: IPv6 only, no IPv4-mapped addresses
            ls.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
        ls.bind((self.host, want))
        ls.listen(self.member.backlog)
        ls.setblocking(False)
        return ls

    async def serve_forever(self, ready: Callable[[list[int]], None] = lambda ports: None) -> None:
        listeners = [self._listen(want) for want in self.want]
        self.ports = [ls.getsockname()[1] for ls in listeners]
        ready(self.ports)
        while True:
            loops = asyncio.gather(*(self._accept_loop(PortState(i), ls) for i, ls in enumerate(listeners)))
            try:
                if not self.member.restart_every:
                    await loops
                    return
                await asyncio.wait({asyncio.ensure_future(loops)}, timeout=self.member.restart_every)
            finally:
                loops.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await loops
                for ls in listeners:
                    ls.close()
            listeners = await self._restart()

    async def _restart(self) -> list[socket.socket]:
        """Row 10: every connection dropped, the ports gone for ``restart_down`` s, a fresh target behind.

        Every task but this one is cancelled and awaited: the clients and the pumps each runs (a client's pumps
        outlived it before, still registered with the selector for sockets its clean-up had closed; the numbers,
        reused by the next connections, then failed with ENOENT from epoll_ctl - "upstream port N unreachable:
        [Errno 2]" - and the member accepted and closed every newcomer after its first restart)."""
        loop = asyncio.get_running_loop()
        began = loop.time()
        stale = [task for task in asyncio.all_tasks() if task is not asyncio.current_task()]
        for task in stale:
            task.cancel()
        await asyncio.gather(*stale, return_exceptions=True)
        self.log(f"zoo {self.member.name}: restarting")
        ports = await loop.run_in_executor(None, self.on_restart)
        if ports:
            self.upstream = (self.upstream[0], list(ports))
        await asyncio.sleep(max(0.0, self.member.restart_down - (loop.time() - began)))
        self.log(f"zoo {self.member.name}: back")
        return [self._listen(port) for port in self.ports]

    async def _accept_loop(self, port: PortState, ls: socket.socket | None) -> None:
        loop = asyncio.get_running_loop()
        port.idle.set()
        admit = self.member.admit
        while True:
            if admit == "backlog" or ls is None:
                await port.idle.wait()  # the next client stays in the listen backlog (or is refused) until then
            if ls is None:
                ls = self._listen(self.ports[port.index])
            for sock in await self._newcomers(loop, ls):
                ls = self._admit(loop, port, ls, sock)

    async def _newcomers(self, loop: asyncio.AbstractEventLoop, ls: socket.socket) -> list[socket.socket]:
        """The next client, or, on a timer-driven accept loop, every client waiting when the timer fires."""
        every = self.member.accept_every
        if every <= 0:
            return [(await loop.sock_accept(ls))[0]]
        await asyncio.sleep(every - loop.time() % every)  # the timer's next tick
        out: list[socket.socket] = []
        while True:
            try:
                sock, _ = ls.accept()
            except (BlockingIOError, InterruptedError):
                return out
            sock.setblocking(False)
            out.append(sock)

    def _admit(
        self, loop: asyncio.AbstractEventLoop, port: PortState, ls: socket.socket | None, sock: socket.socket
    ) -> socket.socket | None:
        """Serve ``sock`` or turn it away (members.py: admit); the listening socket, None once it stopped."""
        admit = self.member.admit
        if admit == "turn-away" and (port.busy or loop.time() < port.free_at):
            self.refused[port.index] += 1
            self._turn_away(sock)
            return ls
        if admit != "transparent":
            port.busy = True
            port.idle.clear()
        if admit == "turn-away" and self.member.turn_away == "refuse" and ls is not None:
            ls.close()  # the port stops listening: a newcomer's connect is refused until the port is free
            ls = None
        self.served[port.index] += 1
        task = asyncio.create_task(self._client(port, sock))
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        return ls

    @property
    def stats(self) -> dict[str, list[int]]:
        """The clients served and the newcomers turned away, per port (``--stats``)."""
        return {"served": list(self.served), "turned_away": list(self.refused)}

    def _turn_away(self, sock: socket.socket) -> None:
        if self.member.turn_away == "rst":
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        else:  # FIN first; what the newcomer sent is read away, else the close would reset the connection
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_WR)
                sock.setblocking(False)
                while sock.recv(65536):
                    pass
        sock.close()

    # ---- one client
    async def _client(self, port: PortState, sock: socket.socket) -> None:
        loop = asyncio.get_running_loop()
        try:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            if self.member.close == "rst":  # row 3: every close of this connection is a reset
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
            if not (self.member.cuts_requests or self.member.shapes_replies):
                await self._plain(sock, port)
            else:
                await self._shaped(sock, port)
        except OSError:
            pass
        finally:
            with contextlib.suppress(OSError):
                sock.close()
            if self.member.admit != "transparent":
                port.busy = False
                lo, hi = self.member.release
                wait = self.rng.uniform(lo, hi) if hi > 0 else 0.0
                port.free_at = loop.time() + wait
                loop.call_later(wait, port.idle.set)

    async def _both_ways(self, up: Coroutine[Any, Any, None], down: Coroutine[Any, Any, None]) -> None:
        """Run both directions; after the client's end-of-stream the target may still answer (and close)."""
        t_up, t_down = asyncio.create_task(_guarded(up)), asyncio.create_task(_guarded(down))
        done, _ = await asyncio.wait({t_up, t_down}, return_when=asyncio.FIRST_COMPLETED)
        if t_up in done and t_up.result() and self.member.on_fin == "pass":
            await asyncio.wait({t_down}, timeout=HALF_CLOSE_WAIT)
        for task in (t_up, t_down):
            task.cancel()

    async def _plain(self, sock: socket.socket, port: PortState) -> None:
        """Bytes passed on as they come, on the raw sockets (no streams: a member that only decides who is
        admitted costs a connection as little as it can - the benchmarks fuzz through it)."""
        loop = asyncio.get_running_loop()
        sock.setblocking(False)
        up = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        up.setblocking(False)
        up.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        try:
            try:
                await loop.sock_connect(up, (self.upstream[0], self.upstream[1][port.index]))
            except OSError as exc:
                self.log(f"upstream port {self.upstream[1][port.index]} unreachable: {exc}")
                return
            m = self.member
            await self._both_ways(_pump(loop, sock, up, idle=m.idle_drop), _pump(loop, up, sock, eof=m.close == "fin"))
        finally:
            up.close()

    async def _shaped(self, sock: socket.socket, port: PortState) -> None:
        """Through the member's bug (requests cut into frames) and reply schedule (delays, coalescing, segments)."""
        c_reader, c_writer = await asyncio.open_connection(sock=sock)
        try:
            u_reader, u_writer = await asyncio.open_connection(self.upstream[0], self.upstream[1][port.index])
        except OSError as exc:
            self.log(f"upstream port {self.upstream[1][port.index]} unreachable: {exc}")
            c_writer.close()
            return
        u_writer.get_extra_info("socket").setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        await self._both_ways(self._to_target(c_reader, u_writer), self._to_client(u_reader, c_writer))
        for w in (c_writer, u_writer):
            with contextlib.suppress(OSError, RuntimeError):
                w.close()

    async def _to_target(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        cutter = FrameCutter() if self.member.cuts_requests else None
        idle = self.member.idle_drop or None
        greeted = [not self.member.silent]  # this connection has sent CMD_CONNECT_TO_PLTF (silent members)
        while data := await asyncio.wait_for(reader.read(65536), idle):
            if cutter is None:
                writer.write(data)
            elif not self._requests(cutter.feed(data), writer, greeted):
                break  # a strict member closes: the target answers what came before, then the client is closed
            await writer.drain()
        else:
            if cutter is not None:
                for piece in cutter.flush():
                    writer.write(piece.data)
        with contextlib.suppress(OSError):
            writer.write_eof()

    def _requests(self, pieces: list[Piece], writer: asyncio.StreamWriter, greeted: list[bool]) -> bool:
        """Pass the pieces on through the member's rules; False when a strict member ends the connection.
        ``greeted[0]``: the connection has sent CMD_CONNECT_TO_PLTF (before it a silent member swallows the rest)."""
        for piece in pieces:
            if self.member.malformed and not well_formed(piece):
                if self.member.malformed == "close":
                    return False
                if piece.frame:
                    continue  # skipped unanswered; bytes out of step go on, the target judges them
            if piece.frame and self.bug is not None:
                fault = self.bug.on_request(piece, time.monotonic())
                if fault is not None:
                    self._fault(fault)
            if not greeted[0] and piece.ident == CONNECT_TO_PLTF_ID:
                greeted[0] = True
            if greeted[0]:
                writer.write(piece.data)
        return True

    async def _to_client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        if not self.member.shapes_replies:
            while data := await reader.read(65536):
                writer.write(data)
                await writer.drain()
            return
        loop = asyncio.get_running_loop()
        cutter, schedule = FrameCutter(), ReplySchedule(self.member.delay, self.rng)
        more = asyncio.Event()
        ended = False

        async def read() -> None:
            nonlocal ended
            try:
                while data := await reader.read(65536):
                    for piece in cutter.feed(data):
                        schedule.push(self._reply(piece), loop.time())
                    more.set()
                for piece in cutter.flush():
                    schedule.push(piece, loop.time())
            finally:
                ended = True
                more.set()

        reading = asyncio.create_task(read())
        try:
            while not (ended and not schedule):
                due = schedule.next_due
                if due is None or due > loop.time():
                    more.clear()
                    timeout = None if due is None else due - loop.time()
                    with contextlib.suppress(TimeoutError):
                        await asyncio.wait_for(more.wait(), timeout)
                    continue
                for i, seg in enumerate(segments(schedule.due(loop.time()), self.rng, self.member.segment)):
                    if i:
                        await asyncio.sleep(SEGMENT_GAP)  # one TCP segment per write (TCP_NODELAY), apart in time
                    writer.write(seg)
                    await writer.drain()
        finally:
            reading.cancel()

    def _reply(self, piece: Piece) -> Piece:
        """A reply frame as the member reports it (absurd values rewritten)."""
        if not (self.member.absurd and piece.frame):
            return piece
        return Piece(rewrite(piece, self.member.absurd), True)

    # ---- faults
    def _fault(self, fault: Fault) -> None:
        self.log(f"zoo {self.member.name}: {fault.kind}: {fault.why}")
        if fault.kind == "hang":
            time.sleep(self.hang_seconds)  # the one thread is stuck: nothing is accepted, read or answered
            self._exit(3)
        self._exit(134)

    def _exit(self, status: int) -> None:
        with contextlib.suppress(Exception):
            self.on_exit()
        sys.stdout.flush()
        os._exit(status)
