"""The plain single: one case the target should refuse, on a connection of its own, with the fewest objects.

Rules:
- A *plain single* - one case the target should refuse, small, written whole with our FIN, on a fresh connection
  that is not gated and whose FIN waits for nothing (``plain``) - is about half of all units. It is a ``Single``:
  one object for the connection and its outcome, no ``Session``, ``Outcome`` or decoder unless asked (the replies
  are decoded once, when the connection has ended, and remembered by their bytes: ``decode_replies``), judged
  from its counters (``pltf.fuzz.verdict.judge_counts``). The same replies, checks and verdicts as a
  ``pltf.fuzz.flight.Flight``.
- Where the C extension ``_singles`` is built (``NATIVE``), a plain single's connection runs in C (``CSingle``:
  connect, write, FIN, read to the close, on the ``pltf.fuzz.poller.Poller``'s epoll, which is then
  ``_singles.Pool``, without a Python call) and Python decodes and judges only what came back; ``Single`` stays
  the fallback and the oracle (tests/fuzz/test_single.py holds the two to a ``Flight``'s verdicts). ``single``
  makes whichever is there.
"""

from __future__ import annotations

import _socket
import contextlib
import errno
import socket
import time
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from pltf.fuzz.flight import NAGLE_FREE, NATIVE, NONBLOCK, Connection, Flight
from pltf.fuzz.replies import reply_decoder
from pltf.fuzz.target import (
    CUT,
    GET_STATUS,
    LEAD,
    PER_FRAME,
    PER_MIB,
    Outcome,
    Session,
    check_order,
)
from pltf.fuzz.unit import Unit
from pltf.fuzz.verdict import Verdict, judge_counts
from pltf.fuzz.wire import answered_ids
from pltf.spec import errors
from pltf.spec.telegram import Telegram

try:
    from pltf.fuzz import _singles
except ImportError:  # built without a compiler, or PLTF_NO_EXTENSIONS=1
    _singles = None  # type: ignore[assignment]

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


class Single(Connection):
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
        self.sock = sock = _socket.socket(family, _socket.SOCK_STREAM | NONBLOCK)
        if not NONBLOCK:
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
        if not self._write(self.data[self.pos :] if self.pos else self.data) or self.pos < len(self.data):
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

    def _send_due(self) -> None:
        self._send()

    def readable(self) -> None:
        data = self._recv()
        if data is None:
            return
        if data:
            self.got += len(data)
            self.rx += data
            return
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


if TYPE_CHECKING:  # the C type's attributes as _singles.pyi declares them
    _CBase = _singles.Single
else:
    _CBase = _singles.Single if _singles is not None else object


class CSingle(_CBase):
    """``Single`` with its connection in C (``_singles.Single``: the socket, its writes and reads, how it ended);
    the replies decoded and judged here only when something came back, ``session`` and ``out`` built when asked
    for. Made by ``single``."""

    __slots__ = ("_decoded", "_out", "_session", "entry", "expected", "fin_waits", "led", "owed", "unit")
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
    entry: Any  # its ``pltf.fuzz.lanes.InFlight`` where a ``_singles.Run`` drives it
    _decoded: tuple[list[Telegram], str | None, int]
    _session: Session
    _out: Outcome

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
    pool: Any, host: str, port: int, unit: Unit, lead: bool, deadline_s: float, fin_waits: bool, start: bool = True
) -> Single | CSingle:
    """A plain single (``plain``) on a fresh connection: in C where ``_singles`` is built (its socket on ``pool``,
    a ``_singles.Pool``, or driven by ``select`` when None), else ``Single``. ``start`` False (C only): made, not
    connected - a ``_singles.Run`` of the pool starts it in its turn (``pltf.fuzz.lanes``)."""
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
    s = CSingle(pool, host, port, data, budget, start)
    s.unit, s.led, s.fin_waits, s.owed = unit, lead, fin_waits, len(ids)
    s.expected = [*ids, *case.answered] if case.answered is not None else answered_ids(data)
    return s


def _ms_from(start: float) -> Any:
    return lambda t: None if t is None else round((t - start) * 1000, 1)
