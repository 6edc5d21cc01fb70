"""Sessions in flight side by side: one non-blocking connection per port, driven by a ``select`` loop.

Rules:
- PlatformCtrl serves one client per port (guide 6.1) and both ports take every command, so two cases - one
  per port - can be in flight at once. The target works on one while we prepare or read the other; a
  sequential fuzzer leaves both sides idle half of the time.
- A ``Flight`` is a ``pltf.fuzz.target.Session`` on its own connection, with the same outcome and the same reply
  checks as ``pltf.fuzz.target.play``. Slow and bytewise deliveries write piece by piece (one write each), the
  pauses between them kept by the ``select`` loop instead of a sleep, so the other flights go on meanwhile.
- ``fly`` runs flights to completion or to their deadlines; it never raises for anything the peer does.
- A *plain single* (about half of all units) runs as ``pltf.fuzz.single.Single`` or, where the C extension is
  built, ``CSingle``; the lanes wait on one epoll (``pltf.fuzz.poller.Poller``). ``fly`` and ``step_flights``
  without a poller keep ``select`` (replays, checks: one flight at a time).
"""

from __future__ import annotations

import _socket
import abc
import collections
import contextlib
import errno
import itertools
import select
import socket
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from pltf.fuzz.replies import reply_decoder
from pltf.fuzz.target import (
    CUT,
    GET_STATUS,
    RECV,
    Outcome,
    Session,
    check_order,
    session_deadline,
    session_reply_ids,
)
from pltf.spec import errors
from pltf.spec.codec import REQUESTS

if TYPE_CHECKING:
    from pltf.fuzz.poller import Poller
    from pltf.fuzz.single import Flying

try:
    from pltf.fuzz import _singles
except ImportError:  # built without a compiler, or PLTF_NO_EXTENSIONS=1
    _singles = None  # type: ignore[assignment]

NATIVE = _singles is not None

CHUNK = 1 << 16
AWAIT = -1.0  # the pause of a piece that waits for the peer's first byte (the rest of a gated session)
RESET = (errno.ECONNRESET, errno.EPIPE)
# One write and our FIN on a fresh connection: Nagle holds back no segment (nothing of ours is unacknowledged
# before it, and a write of this size is one segment on any link), so TCP_NODELAY - a system call per connection,
# and about half of all cases are singles on a connection of their own - is set only for sessions written in
# pieces, kept open, or larger.
NAGLE_FREE = 1024  # bytes
NONBLOCK = getattr(socket, "SOCK_NONBLOCK", 0)  # Linux: the socket is created non-blocking (no fcntl call)
# one order over every write of every flight (``Flight.sends``, ``pltf.fuzz.sent``), the C singles' writes among them
next_write: Callable[[], int] = _singles.next_write if _singles is not None else itertools.count().__next__


class Connection(abc.ABC):
    """What a ``Flight`` and a ``pltf.fuzz.single.Single`` share: the events of a non-blocking connection being made,
    written and read. A subclass has ``sock``, ``connected``, ``reset``, ``due``, ``_send_due`` (write what is due)
    and ``_finish``."""

    sock: _socket.socket
    connected: bool
    reset: bool
    sending: bool
    pos: int  # bytes sent
    sends: list[tuple[int, int]]  # (the write's place among all writes, bytes sent after it)

    @property
    @abc.abstractmethod
    def due(self) -> bool:
        """Whether it has bytes to send now."""

    @abc.abstractmethod
    def _send_due(self) -> None:
        """Write what is due."""

    @abc.abstractmethod
    def _finish(self, refused: bool = False, closed: bool = False, timed_out: bool = False) -> None:
        """The connection has ended (or is given up): its outcome is settled, its socket closed or kept."""

    def writable(self) -> None:
        if not self.connected:
            code = self.sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if code:
                self._finish(refused=code == errno.ECONNREFUSED, closed=code != errno.ECONNREFUSED)
                return
            self.connected = True
        if self.due:
            self._send_due()

    def _write(self, chunk: bytes) -> bool:
        """One send of ``chunk``, counted in ``pos`` and ``sends``; False when nothing went: still connecting or a
        full buffer (the poll says when), the connect refused (finished), or the peer gone (``reset``; what it said
        before it went is read)."""
        try:
            sent = self.sock.send(chunk)
        except (BlockingIOError, InterruptedError):
            return False
        except ConnectionRefusedError:
            self._finish(refused=True)
            return False
        except OSError as exc:
            if exc.errno not in (errno.ENOTCONN, errno.EINPROGRESS, errno.EALREADY):
                self.connected, self.sending = True, False
                self.reset = exc.errno in RESET
            return False
        self.connected = True
        self.pos += sent
        self.sends.append((next_write(), self.pos))
        return True

    def _recv(self) -> bytes | None:
        """What a readable socket brought: bytes, ``b""`` at the peer's close or reset (``reset`` set), or None:
        nothing yet, or the connect was refused (then finished)."""
        try:
            data = self.sock.recv(RECV)
        except BlockingIOError:
            return None
        except ConnectionRefusedError:
            self._finish(refused=True)
            return None
        except OSError as exc:
            self.reset = exc.errno in RESET
            data = b""
        if not self.connected and not data:
            code = self.sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if code == errno.ECONNREFUSED:
                self._finish(refused=True)
                return None
        self.connected = True
        return data


class Flight(Connection):
    sock: socket.socket
    native = False  # its socket is not driven in C (``CSingle``)

    def __init__(
        self, host: str, port: int, session: Session, deadline_s: float, sock: socket.socket | None = None
    ) -> None:
        """``sock``: a connection kept from the flight before (``keep``), already served by the target."""
        self.session = session
        self.out = Outcome()
        self.replies = self.out.replies  # the same list
        self.half_close = session.half_close
        data = session.data
        self.expected = session_reply_ids(session)
        if session.sync:
            data += GET_STATUS
            self.expected.append(REQUESTS.CMD_GET_STATUS.ID)
        self.sends: list[tuple[int, int]] = []  # (place in the order of all flights' writes, end offset) per write
        self.pieces, pauses = _pieces(session, data)
        self.data, self.pos = data, 0
        self.next_at = 0.0  # monotonic time before which the next piece waits (a slow delivery's pause)
        self.awaiting = False  # the next piece waits for a byte back (a gated session's lead)
        self.want = len(self.expected) if session.sync and not session.half_close else None
        self.budget = pauses + session_deadline(deadline_s, len(session.frames), len(data))  # s from its turn
        self.started = time.monotonic()
        self.deadline = self.started + self.budget
        self.decoder = reply_decoder()
        self.done = False
        self.reset = False  # the peer reset the connection (a close with our input unread)
        self.sending = True
        self.kept: socket.socket | None = None  # the connection, still open, after a clean finish of ``want``
        self.fin_due = False  # all sent; our FIN waits for the replies asked for (``Session.fin_waits``)
        self.closed = False  # ``out.closed`` once done
        self.poll_fd = -1  # its socket's number in a ``Poller`` (-1: not there)
        if sock is not None:
            self.sock, self.connected = sock, True
            self._send_some()
            return
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        self.sock = socket.socket(family, socket.SOCK_STREAM | NONBLOCK)
        if not NONBLOCK:
            self.sock.setblocking(False)
        if len(self.pieces) > 1 or not session.half_close or len(data) > NAGLE_FREE:
            self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.connected = False
        code = self.sock.connect_ex((host, port))
        if code not in (0, errno.EINPROGRESS):
            self._finish(refused=code == errno.ECONNREFUSED, closed=code != errno.ECONNREFUSED)
        else:
            self._send_some()  # on loopback the handshake is done when connect_ex returns: no select round

    @property
    def due(self) -> bool:
        """Whether it has bytes to send now (not waiting for a slow delivery's pause or a gated lead's reply)."""
        return self.sending and not self.awaiting and time.monotonic() >= self.next_at

    def _send_some(self) -> None:
        """One write of the current piece (at most ``CHUNK`` bytes); after a piece, the next one's pause."""
        if not self.pieces:  # nothing to send at all
            self._sent_all()
            return
        end = self.pieces[0][0]
        if not self._write(self.data[self.pos : min(end, self.pos + CHUNK)]) or self.pos < end:
            return
        self.pieces.popleft()
        if self.pieces:
            pause = self.pieces[0][1]
            if pause == AWAIT:
                self.awaiting = self.out.got == 0
            elif pause > 0:
                self.next_at = time.monotonic() + pause
            return
        self._sent_all()

    def _sent_all(self) -> None:
        self.sending = False
        if self.session.half_close:
            self.fin_due = True
            self._fin()

    def _fin(self) -> None:
        """Our FIN once it is due: at once, or where it ends the session once every reply asked for came."""
        if self.fin_due and (not self.session.fin_waits or len(self.out.replies) >= len(self.expected)):
            self.fin_due = False
            self.out.fin_ms = self._ms()
            with contextlib.suppress(OSError):
                self.sock.shutdown(socket.SHUT_WR)

    def _ms(self) -> float:
        return round((time.monotonic() - self.started) * 1000, 1)

    def fileno(self) -> int:
        return self.sock.fileno()

    def _finish(self, refused: bool = False, closed: bool = False, timed_out: bool = False) -> None:
        if self.done:
            return
        self.done = True
        self.out.refused, self.out.timed_out = refused, timed_out
        self.out.end_ms, self.out.reset = self._ms(), self.reset
        self.out.closed = closed or (self.want is not None and len(self.out.replies) < self.want)
        self.closed = self.out.closed
        if self.out.bad_reply is None and not refused:
            self.out.bad_reply = check_order(self.out.replies, self.expected, self.data)
        clean = not (refused or timed_out or self.out.closed or self.out.bad_reply or self.decoder.pending)
        if self.want is not None and clean:
            self.kept = self.sock  # a kept connection: the next flight goes on with it
        else:
            self.sock.close()

    def _send_due(self) -> None:
        self._send_some()

    def readable(self) -> None:
        data = self._recv()
        if data is None:
            return
        if not data:
            self.decoder.receive_data(b"")
        else:
            self.out.got += len(data)
            self.decoder.receive_data(data)
            if self.awaiting:
                self.awaiting = False
        self._take_replies(data)

    def _take_replies(self, data: bytes) -> None:
        """The replies decoded so far; the end of the flight (``data`` empty: the peer closed) or our FIN due."""
        try:
            while (t := self.decoder.next_telegram()) is not None:
                self.out.replies.append(t)
        except errors.RemoteProtocolError as exc:
            cut = CUT if not data else "reply does not decode"
            self.out.bad_reply = f"{cut}: {type(exc).__name__}: {exc}"
            self._finish(closed=True)
            return
        if not data:
            self._finish(closed=True)
        elif self.want is not None and len(self.out.replies) >= self.want:
            self._finish()
        else:
            self._fin()


def _pieces(session: Session, data: bytes) -> tuple[collections.deque[tuple[int, float]], float]:
    """(end offset, pause before it) of each piece ``data`` is written in (a sync's GET_STATUS at its end), and the
    pauses' sum."""
    pieces: collections.deque[tuple[int, float]] = collections.deque()
    gate = session.gate_bytes
    if not gate and session.delivery.mode == "whole":  # most units: one write
        if data:
            pieces.append((len(data), 0.0))
        return pieces, 0.0
    body = data[: len(data) - len(GET_STATUS)] if session.sync else data
    chunks = [(body[:gate], 0.0)] if gate else []
    chunks += session.delivery.chunks(body[gate:])  # (bytes, pause before them)
    if gate and len(chunks) > 1:
        chunks[1] = (chunks[1][0], AWAIT)
    if session.sync:
        chunks.append((GET_STATUS, 0.0))
    end = 0
    for piece, pause in chunks:
        if piece:
            end += len(piece)
            pieces.append((end, pause))
    return pieces, sum(pause for _, pause in chunks if pause > 0)


def fly(flights: list[Flying]) -> None:
    """Drive ``flights`` until each is done or past its deadline."""
    while live := [f for f in flights if not f.done]:
        _step(live)


def step_flights(flights: list[Any], until: float | None = None, poller: Poller | None = None) -> list[Any]:
    """Drive ``flights`` until at least one of them is done (or past its deadline), or the monotonic time
    ``until`` has come; the ones done. ``poller``: wait on its epoll instead of a ``select``."""
    while not (done := [f for f in flights if f.done]):
        if until is not None and time.monotonic() >= until:
            break
        if poller is not None:
            poller.step(flights, until)
        else:
            _step(flights, until)
    return done


def _step(live: list[Flying], until: float | None = None) -> None:
    """One round over flights not done: finish those past their deadline; if none was, wait for the sockets
    of all of them until the nearest deadline (or ``until``) and drive the ones that are ready."""
    now = time.monotonic()
    overdue = [f for f in live if now >= f.deadline]
    for f in overdue:
        f._finish(timed_out=True)
    if overdue:
        return  # the caller looks at the flights again
    wait = max(0.0, min(f.deadline for f in live) - now)
    if until is not None:
        wait = min(wait, max(0.0, until - now))
    paused = [f.next_at for f in live if f.sending and f.connected and f.next_at > now]  # slow deliveries
    if paused:
        wait = min(wait, max(0.0, min(paused) - now))
    writers = [f for f in live if not f.connected or f.due]
    readable, writable, _ = select.select(live, writers, [], wait)
    for f in writable:
        if not f.done:
            f.writable()
    for f in readable:
        if not f.done:
            f.readable()
