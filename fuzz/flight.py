"""Sessions in flight side by side: one non-blocking connection per port, driven by one ``select`` loop.

Rules:
- PlatformCtrl serves one client per port (guide 6.1) and both ports take every command, so two cases - one
  per port - can be in flight at once. The target works on one while we prepare or read the other; a
  sequential fuzzer leaves both sides idle half of the time.
- A ``Flight`` is a ``pltf.fuzz.target.Session`` on its own connection, with the same outcome and the same reply
  checks as ``pltf.fuzz.target.play``. Slow and bytewise deliveries write piece by piece (one write each), the
  pauses between them kept by the ``select`` loop instead of a sleep, so the other flights go on meanwhile.
- ``fly`` runs flights to completion or to their deadlines; it never raises for anything the peer does.
- A *plain single* - one case the target should refuse, small, written whole with our FIN, on a fresh connection
  that is not gated and whose FIN waits for nothing (``plain``) - is about half of all units. It is a ``Single``:
  one object for the connection and its outcome, no ``Session``, ``Outcome`` or decoder unless asked (the replies
  are decoded once, when the connection has ended, and remembered by their bytes: ``decode_replies``), judged
  from its counters (``pltf.fuzz.verdict.judge_counts``). The same replies, checks and verdicts as a ``Flight``.
- The lanes wait on one ``Poller`` (epoll): each socket is registered once, for reading, and for writing only
  while it has something to send now; a closed socket leaves it by itself. ``fly`` and ``step_flights`` without
  a poller keep ``select`` (replays, checks: one flight at a time).
- Where the C extension ``_singles`` is built (``NATIVE``), a plain single's connection runs in C (``CSingle``:
  connect, write, FIN, read to the close, on the ``Poller``'s epoll, which is then ``_singles.Pool``, without a
  Python call) and Python decodes and judges only what came back; ``Single`` stays the fallback and the oracle
  (tests/fuzz/test_flight.py holds the two to the same verdicts). ``single`` makes whichever is there.
"""

from __future__ import annotations

import _socket
import collections
import contextlib
import errno
import itertools
import select
import socket
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

from pltf.fuzz.replies import reply_decoder
from pltf.fuzz.target import (
    CUT,
    GET_STATUS,
    LEAD,
    PER_FRAME,
    PER_MIB,
    RECV,
    Outcome,
    Session,
    check_order,
    session_deadline,
    session_reply_ids,
)
from pltf.fuzz.unit import Unit
from pltf.fuzz.verdict import Verdict, judge_counts
from pltf.fuzz.wire import answered_ids
from pltf.spec import errors
from pltf.spec.codec import REQUESTS
from pltf.spec.telegram import Telegram

try:
    from pltf.fuzz import _singles
except ImportError:  # built without a compiler, or PLTF_NO_EXTENSIONS=1
    _singles = None  # type: ignore[assignment]

NATIVE = _singles is not None

CHUNK = 1 << 16
AWAIT = -1.0  # the pause of a piece that waits for the peer's first byte (the rest of a gated session)
_RESET = (errno.ECONNRESET, errno.EPIPE)
# One write and our FIN on a fresh connection: Nagle holds back no segment (nothing of ours is unacknowledged
# before it, and a write of this size is one segment on any link), so TCP_NODELAY - a system call per connection,
# and about half of all cases are singles on a connection of their own - is set only for sessions written in
# pieces, kept open, or larger.
NAGLE_FREE = 1024  # bytes
_NONBLOCK = getattr(socket, "SOCK_NONBLOCK", 0)  # Linux: the socket is created non-blocking (no fcntl call)
# one order over every write of every flight (``Flight.sends``, ``pltf.fuzz.sent``), the C singles' writes among them
next_write: Callable[[], int] = _singles.next_write if _singles is not None else itertools.count().__next__


class Flight:
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
        self.sock = socket.socket(family, socket.SOCK_STREAM | _NONBLOCK)
        if not _NONBLOCK:
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
        try:
            sent = self.sock.send(self.data[self.pos : min(end, self.pos + CHUNK)])
        except (BlockingIOError, InterruptedError):
            return  # still connecting (or a full buffer): select says when
        except ConnectionRefusedError:
            self._finish(refused=True)
            return
        except OSError as exc:
            if exc.errno in (errno.ENOTCONN, errno.EINPROGRESS, errno.EALREADY):
                return
            self.connected, self.sending = True, False  # the peer is gone; read what it said before it went
            self.reset = exc.errno in _RESET
            return
        self.connected = True
        self.pos += sent
        self.sends.append((next_write(), self.pos))
        if self.pos < end:
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

    def writable(self) -> None:
        if not self.connected:
            code = self.sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if code:
                self._finish(refused=code == errno.ECONNREFUSED, closed=code != errno.ECONNREFUSED)
                return
            self.connected = True
        if self.due:
            self._send_some()

    def readable(self) -> None:
        try:
            data = self.sock.recv(RECV)
        except BlockingIOError:
            return
        except ConnectionRefusedError:
            self._finish(refused=True)
            return
        except OSError as exc:
            self.reset = exc.errno in _RESET
            data = b""
        if not self.connected and not data:
            code = self.sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if code == errno.ECONNREFUSED:
                self._finish(refused=True)
                return
        self.connected = True
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


def fly(flights: list[Flight | Single]) -> None:
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


def _step(live: list[Flight | Single], until: float | None = None) -> None:
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


# ---------------------------------------------------------------------------------------------- the plain single
# (ended, the replies' bytes) -> ``decode_replies``, for small streams
_MEMO: dict[tuple[bool, bytes], tuple[list[Telegram], str | None, int]] = {}
MEMO_BYTES = 256  # streams up to this size are remembered (the lead's reply is 33 bytes)
MEMO_ENTRIES = 1024
_EMPTY: tuple[list[Telegram], str | None, int] = ([], None, 0)


def decode_replies(data: bytes, ended: bool) -> tuple[list[Telegram], str | None, int]:
    """(replies, why they do not decode, bytes left over) of a connection's whole reply stream, as ``Flight``
    decodes it piece by piece: an error inside the stream does not decode, a frame cut off by the end (``ended``)
    is ``CUT``. Strict decoding is a function of the bytes alone: small streams are remembered."""
    if not data:
        return _EMPTY
    key = (ended, data)
    known = _MEMO.get(key)
    if known is not None:
        return known[0][:], known[1], known[2]
    decoder = reply_decoder()
    decoder.receive_data(data)
    replies: list[Telegram] = []
    bad = None
    try:
        while (t := decoder.next_telegram()) is not None:
            replies.append(t)
    except errors.RemoteProtocolError as exc:
        bad = f"reply does not decode: {type(exc).__name__}: {exc}"
    if bad is None and ended:
        decoder.receive_data(b"")
        try:
            decoder.next_telegram()
        except errors.RemoteProtocolError as exc:
            bad = f"{CUT}: {type(exc).__name__}: {exc}"
    got = (replies, bad, decoder.pending)
    if len(data) <= MEMO_BYTES:
        if len(_MEMO) >= MEMO_ENTRIES:
            _MEMO.clear()
        _MEMO[key] = (replies[:], bad, got[2])
    return got


def plain(unit: Unit, lead: bool, kept: bool, fin_waits: bool) -> bool:
    """Whether ``unit`` runs as a ``Single``: one case the target should refuse, written whole and small (no gate:
    it was never turned away), on a fresh connection, and our FIN waits for nothing (a target whose FIN ends the
    session, with replies owed, takes a ``Flight``)."""
    if kept or unit.keep or unit.tries or not unit.whole or len(unit.cases) != 1:
        return False
    return not fin_waits or not (lead or unit.prelude or unit.cases[0].answered is None or unit.cases[0].answered)


class Single:
    """A plain single on its own connection (``plain``): what ``Flight`` does for it, with the fewest objects and
    calls. ``session`` and ``out`` are built when something asks for them (a finding, a report)."""

    half_close = True
    kept = None
    sending = False
    next_at = 0.0
    poll_fd = -1  # its socket's number in the ``Poller`` (-1: not there)
    native = False

    def __init__(self, host: str, port: int, unit: Unit, lead: bool, deadline_s: float, fin_waits: bool) -> None:
        case = unit.cases[0]
        prelude = unit.prelude
        head = [LEAD] if lead else []
        if prelude:
            head += [*prelude, GET_STATUS]
        self.unit, self.led, self.fin_waits = unit, lead, fin_waits
        self.frames = [*head, *case.frames]
        self.data = data = b"".join(self.frames)
        ids = [*([LEAD_ID] if lead else []), *unit.prelude_ids]
        self.expected = [*ids, *case.answered] if case.answered is not None else answered_ids(data)
        self.owed = len(ids)
        self.budget = deadline_s + PER_FRAME * len(self.frames) + PER_MIB * len(data) / (1 << 20)
        self.started = now = time.monotonic()
        self.deadline = now + self.budget
        self.rx = b""
        self.got = 0
        self.pos = 0
        self.done = self.refused = self.timed_out = self.closed = self.reset = False
        self.fin_at: float | None = None
        self.end_at: float | None = None
        self.sends: list[tuple[int, int]] = []
        self.replies: list[Telegram] = []
        self.bad_reply: str | None = None
        self.pending = 0
        self._session: Session | None = None
        self._out: Outcome | None = None
        family = _socket.AF_INET6 if ":" in host else _socket.AF_INET
        self.sock = sock = _socket.socket(family, _socket.SOCK_STREAM | _NONBLOCK)
        if not _NONBLOCK:
            sock.setblocking(False)
        if len(data) > NAGLE_FREE:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        code = sock.connect_ex((host, port))
        self.connected = False
        if code not in (0, errno.EINPROGRESS):
            self._end(refused=code == errno.ECONNREFUSED, closed=code != errno.ECONNREFUSED)
            return
        self.sending = True
        self._send()  # on loopback the handshake is done when connect_ex returns

    def _send(self) -> None:
        try:
            sent = self.sock.send(self.data[self.pos :] if self.pos else self.data)
        except (BlockingIOError, InterruptedError):
            return
        except ConnectionRefusedError:
            self._end(refused=True)
            return
        except OSError as exc:
            if exc.errno in (errno.ENOTCONN, errno.EINPROGRESS, errno.EALREADY):
                return
            self.connected, self.sending = True, False  # the peer is gone; read what it said before it went
            self.reset = exc.errno in _RESET
            return
        self.connected = True
        self.pos += sent
        self.sends.append((next_write(), self.pos))
        if self.pos < len(self.data):
            return
        self.sending = False
        self.fin_at = time.monotonic()  # ``plain``: our FIN waits for nothing
        with contextlib.suppress(OSError):
            self.sock.shutdown(_socket.SHUT_WR)

    @property
    def due(self) -> bool:
        """Bytes to send now (a plain single has no pauses)."""
        return self.sending

    def fileno(self) -> int:
        return self.sock.fileno()

    def writable(self) -> None:
        if not self.connected:
            code = self.sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if code:
                self._end(refused=code == errno.ECONNREFUSED, closed=code != errno.ECONNREFUSED)
                return
            self.connected = True
        if self.sending:
            self._send()

    def readable(self) -> None:
        try:
            data = self.sock.recv(RECV)
        except BlockingIOError:
            return
        except ConnectionRefusedError:
            self._end(refused=True)
            return
        except OSError as exc:
            self.reset = exc.errno in _RESET
            data = b""
        if data:
            self.connected = True
            self.got += len(data)
            self.rx += data
            return
        if not self.connected:
            code = self.sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if code == errno.ECONNREFUSED:
                self._end(refused=True)
                return
        self.connected = True
        self._end(closed=True)

    def _finish(self, refused: bool = False, closed: bool = False, timed_out: bool = False) -> None:
        self._end(refused, closed, timed_out)

    def _end(self, refused: bool = False, closed: bool = False, timed_out: bool = False) -> None:
        if self.done:
            return
        self.done, self.sending = True, False
        self.refused, self.closed, self.timed_out = refused, closed, timed_out
        self.end_at = time.monotonic()
        if self.rx:
            self.replies, self.bad_reply, self.pending = decode_replies(self.rx, closed)
        if not refused and self.bad_reply is None and self.replies:
            self.bad_reply = check_order(self.replies, self.expected, self.data)
        self.sock.close()

    def verdict(self) -> Verdict:
        return judge_counts(
            self.refused, self.got, self.timed_out, self.bad_reply, len(self.replies), self.owed, self.led, False
        )

    # ------------------------------------------------------------------ built when asked for
    @property
    def session(self) -> Session:
        if self._session is None:
            self._session = replace(self.unit.session(lead=self.led), fin_waits=self.fin_waits)
        return self._session

    @property
    def out(self) -> Outcome:
        if self._out is None:
            ms = _ms_from(self.started)
            self._out = Outcome(
                refused=self.refused,
                closed=self.closed,
                timed_out=self.timed_out,
                bad_reply=self.bad_reply,
                replies=self.replies,
                got=self.got,
                fin_ms=ms(self.fin_at),
                end_ms=ms(self.end_at),
                reset=self.reset,
            )
        return self._out


LEAD_ID = LEAD[8]
_NOTHING: tuple[list[Telegram], str | None, int] = ([], None, 0)


class CSingle(_singles.Single if _singles is not None else object):  # type: ignore[misc]
    """``Single`` with its connection in C (``_singles.Single``: the socket, its writes and reads, how it ended);
    the replies decoded and judged here only when something came back, ``session`` and ``out`` built when asked
    for. Made by ``single``."""

    __slots__ = ("_decoded", "_out", "_session", "expected", "fin_waits", "led", "owed", "unit")
    half_close = True
    kept = None
    next_at = 0.0
    poll_fd = -1  # never in the ``Poller``'s own books: the pool drives it
    native = True
    unit: Unit
    led: bool
    fin_waits: bool
    expected: list[int]
    owed: int
    _decoded: tuple[list[Telegram], str | None, int]
    _session: Session
    _out: Outcome
    # the C type's attributes, for the type checker (its base is Any to it)
    data: bytes
    pos: int
    got: int
    rx: bytes
    started: float
    deadline: float
    budget: float
    done: bool
    refused: bool
    timed_out: bool
    closed: bool
    reset: bool
    connected: bool
    sending: bool
    sends: list[tuple[int, int]]
    fin_at: float | None
    end_at: float | None

    @property
    def due(self) -> bool:
        return self.sending

    def _finish(self, refused: bool = False, closed: bool = False, timed_out: bool = False) -> None:
        """Past its deadline (the only end the lanes give a single from outside)."""
        self.timeout()

    def decoded(self) -> tuple[list[Telegram], str | None, int]:
        """(replies, why they are bad, bytes left over), as ``Single._end`` finds them; once it is done, once."""
        try:
            return self._decoded
        except AttributeError:
            pass
        got = _NOTHING
        if self.got:
            replies, bad, pending = decode_replies(self.rx, self.closed)
            if not self.refused and bad is None and replies:
                bad = check_order(replies, self.expected, self.data)
            got = (replies, bad, pending)
        if self.done:
            self._decoded = got
        return got

    @property
    def replies(self) -> list[Telegram]:
        return self.decoded()[0]

    @property
    def bad_reply(self) -> str | None:
        return self.decoded()[1]

    @property
    def pending(self) -> int:
        return self.decoded()[2]

    def verdict(self) -> Verdict:
        if not self.got:  # most singles: nothing back (unled) or refused, turned away
            return judge_counts(self.refused, 0, self.timed_out, None, 0, self.owed, self.led, False)
        replies, bad, _ = self.decoded()
        return judge_counts(self.refused, self.got, self.timed_out, bad, len(replies), self.owed, self.led, False)

    @property
    def session(self) -> Session:
        try:
            return self._session
        except AttributeError:
            self._session = replace(self.unit.session(lead=self.led), fin_waits=self.fin_waits)
            return self._session

    @property
    def out(self) -> Outcome:
        try:
            return self._out
        except AttributeError:
            ms = _ms_from(self.started)
            replies, bad, _ = self.decoded()
            self._out = Outcome(
                refused=self.refused,
                closed=self.closed,
                timed_out=self.timed_out,
                bad_reply=bad,
                replies=replies,
                got=self.got,
                fin_ms=ms(self.fin_at),
                end_ms=ms(self.end_at),
                reset=self.reset,
            )
            return self._out


Flying = Flight | Single | CSingle  # what the lanes drive


def single(
    pool: Any, host: str, port: int, unit: Unit, lead: bool, deadline_s: float, fin_waits: bool
) -> Single | CSingle:
    """A plain single (``plain``) on a fresh connection: in C where ``_singles`` is built (its socket on ``pool``,
    a ``_singles.Pool``, or driven by ``select`` when None), else ``Single``."""
    if not NATIVE:
        return Single(host, port, unit, lead, deadline_s, fin_waits)
    case = unit.cases[0]
    prelude = unit.prelude
    if lead or prelude:
        head = [LEAD] if lead else []
        if prelude:
            head += [*prelude, GET_STATUS]
        frames = len(head) + len(case.frames)
        data = b"".join(head) + case.data
        ids = [*([LEAD_ID] if lead else []), *unit.prelude_ids]
    else:
        frames, data, ids = len(case.frames), case.data, []
    budget = deadline_s + PER_FRAME * frames + PER_MIB * len(data) / (1 << 20)
    s = CSingle(pool, host, port, data, budget)
    s.unit, s.led, s.fin_waits, s.owed = unit, lead, fin_waits, len(ids)
    s.expected = [*ids, *case.answered] if case.answered is not None else answered_ids(data)
    return s


def _ms_from(start: float) -> Any:
    return lambda t: None if t is None else round((t - start) * 1000, 1)


# ---------------------------------------------------------------------------------------------- one epoll
_IN = select.EPOLLIN
_OUT = select.EPOLLOUT


class Poller:
    """The lanes' flights on one epoll: registered once (reading; writing only while a flight has bytes due), a
    socket closed leaves it by itself; a kept connection is taken out when its flight is done."""

    def __init__(self) -> None:
        self.ep: Any = _singles.Pool() if _singles is not None else select.epoll()  # ``CSingle``s enrol themselves
        self.masks: dict[int, int] = {}
        self.by_fd: dict[int, Any] = {}

    def close(self) -> None:
        self.ep.close()

    def step(self, live: list[Any], until: float | None) -> None:
        """One round, as ``_step``: finish the flights past their deadline, else wait for the nearest deadline (or
        ``until``, or a slow delivery's next piece) and drive the ones ready."""
        now = time.monotonic()
        nearest = until if until is not None else now + 3600.0
        overdue = False
        masks, by_fd, ep = self.masks, self.by_fd, self.ep
        for f in live:
            if now >= f.deadline:
                f._finish(timed_out=True)
                overdue = True
                continue
            nearest = min(nearest, f.deadline)
            if f.native:
                continue
            if f.sending:
                if f.connected and f.next_at > now:
                    nearest = min(nearest, f.next_at)
                want = _IN | _OUT if not f.connected or f.due else _IN
            else:
                want = _IN
            fd = f.poll_fd if f.poll_fd >= 0 else f.fileno()
            if masks.get(fd) != want:
                self._arm(fd, want, f)
        if overdue:
            self.forget(live)
            return
        for fd, ev in ep.poll(max(0.0, nearest - now)):
            f = by_fd.get(fd)
            if f is None or f.done:
                continue
            if ev & _OUT:
                f.writable()
            if ev & ~_OUT and not f.done:
                f.readable()
        self.forget(live)

    def _arm(self, fd: int, want: int, f: Any) -> None:
        """Register ``fd`` for ``want`` (or change what it waits for). The number of a socket closed meanwhile
        (it left epoll by itself) may be a new socket's."""
        if f.poll_fd != fd:
            f.poll_fd = fd
            self.masks.pop(fd, None)
        try:
            if fd in self.masks:
                self.ep.modify(fd, want)
            else:
                self.ep.register(fd, want)
        except FileNotFoundError:  # closed and reused since
            self.ep.register(fd, want)
        except FileExistsError:
            self.ep.modify(fd, want)
        self.masks[fd] = want
        self.by_fd[fd] = f

    def forget(self, flights: list[Any]) -> None:
        """The flights done leave the poller: a closed socket has left epoll by itself, a kept one is taken out
        (between its flights a byte from the target would wake every wait)."""
        for f in flights:
            fd, kept = f.poll_fd, f.kept
            if f.done and fd >= 0:
                f.poll_fd = -1
                if self.by_fd.get(fd) is f:
                    del self.by_fd[fd], self.masks[fd]
                    if kept is not None:
                        with contextlib.suppress(OSError):
                            self.ep.unregister(fd)
