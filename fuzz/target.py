"""The socket side of the fuzzer: sessions on the fuzzed port, the liveness probe on the other one.

Rules:
- Blocking sockets with deadlines (one client, no concurrency needed: a Python event loop would only add
  overhead). Loopback only is the caller's choice: nothing here resolves names or picks addresses.
- A ``Session`` is what one connection carries: frames, how they are written, whether our side shuts its
  write half, and whether a GET_STATUS ``sync`` is appended so that a kept connection proves it processed
  everything. ``play`` runs one and returns an ``Outcome``; it never raises for anything the peer does.
- Reply sanity (guide 6.4, erratum E-WIRE-001): every reply decodes strictly, and reply ids come in the
  order of the answered requests (a prefix of it when the peer closes early).
"""

from __future__ import annotations

import contextlib
import ipaddress
import select
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from pltf.fuzz.case import WHOLE, Delivery
from pltf.fuzz.gate import BACKOFF_FIRST, BACKOFF_GROWTH, BACKOFF_MAX
from pltf.fuzz.replies import reply_decoder
from pltf.fuzz.wire import answered_ids, skipping_ids
from pltf.spec import errors
from pltf.spec.codec import REQUESTS, encode
from pltf.spec.telegram import Telegram

GET_STATUS = encode(REQUESTS.CMD_GET_STATUS())
# The lead of every session (``pltf.fuzz.verdict``): any answered request proves a connection was served; this is
# the one a server answers at least cost (the reference server: ~60 us and a 33-byte reply, where GET_STATUS costs
# ~150 us and 2.7 KB). The state comes from the batches' sync GET_STATUS and the preludes' check.
LEAD = encode(REQUESTS.CMD_GET_POSITION())
LEAD_IDS = frozenset({REQUESTS.CMD_GET_POSITION.ID, REQUESTS.CMD_GET_STATUS.ID})  # the replies of lead and syncs
RECV = 1 << 16
CUT = "reply cut off by the close"
BIG_SEND = 1 << 16  # bytes; bigger writes interleave reading (see Conn._send_reading)
PER_FRAME = 0.002  # s of deadline added per frame of a session (floods of slow commands are not hangs)
PER_MIB = 1.0  # s of deadline added per MiB sent (documents take time to validate)


def session_deadline(base: float, frames: int, size: int) -> float:
    """The time a session may take: the base deadline plus an allowance for its amount of work."""
    return base + PER_FRAME * frames + PER_MIB * size / (1 << 20)


@dataclass
class Session:
    frames: list[bytes]
    delivery: Delivery = WHOLE
    half_close: bool = False
    sync: bool = False
    answered: list[int] | None = None  # ids of the answered requests among the frames, when known already
    gate: bool = False  # the first frame (the lead GET_STATUS) goes alone; the rest waits for a byte back
    led: bool = False  # the first frame is the lead GET_STATUS: a byte back proves the target served us
    fin_waits: bool = False  # our FIN only once the replies asked for came (a target whose FIN ends the session)

    @property
    def gate_bytes(self) -> int:
        """Bytes written before the gate (0: no gate)."""
        return len(self.frames[0]) if self.gate and len(self.frames) > 1 else 0

    @property
    def data(self) -> bytes:
        return b"".join(self.frames)

    def with_frames(self, frames: list[bytes]) -> Session:
        """The same session with other frames (their answered ids to be decoded again)."""
        return replace(self, frames=frames, answered=None)

    def to_json(self) -> dict[str, object]:
        d = self.delivery
        return {
            "frames": [f.hex() for f in self.frames],
            "delivery": {"mode": d.mode, "pieces": d.pieces, "pause": d.pause},
            "half_close": self.half_close,
            "sync": self.sync,
            "gate": self.gate,
            "led": self.led,
            "fin_waits": self.fin_waits,
        }


@dataclass
class Outcome:
    refused: bool = False  # connect refused: nobody listens any more
    closed: bool = False  # the peer closed (EOF or reset)
    timed_out: bool = False  # neither the expected replies nor a close within the deadline
    bad_reply: str | None = None
    replies: list[Telegram] = field(default_factory=list)
    got: int = 0  # bytes the peer sent us (none at all: it never served the connection)
    sent: list[tuple[float, bytes]] = field(default_factory=list)  # (time, bytes) for the pcapng
    fin_ms: float | None = None  # ms from the connect to our FIN (None: not sent); flights only
    end_ms: float | None = None  # ms from the connect to the end of the flight (the peer's close, the deadline)
    reset: bool = False  # the peer reset the connection
    received: list[tuple[float, bytes]] = field(default_factory=list)


def expected_reply_ids(data: bytes) -> list[int]:
    """Ids of the answered requests among the frames of ``data``, up to the first malformed frame."""
    return answered_ids(data)


def session_reply_ids(session: Session) -> list[int]:
    """``expected_reply_ids`` of the session's frames (known already, or decoded now)."""
    return list(session.answered) if session.answered is not None else answered_ids(session.data)


def connect(host: str, port: int, timeout: float) -> socket.socket:
    try:  # an address literal needs no resolver call (tens of microseconds per connection)
        family = socket.AF_INET6 if ipaddress.ip_address(host).version == 6 else socket.AF_INET
    except ValueError:
        s = socket.create_connection((host, port), timeout=timeout)
    else:
        s = socket.socket(family, socket.SOCK_STREAM)
        s.settimeout(timeout)
        try:
            s.connect((host, port))
        except OSError:
            s.close()
            raise
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return s


class Conn:
    """One connection with its reply decoder; ``send`` and ``read_replies`` record what passed."""

    def __init__(self, host: str, port: int, timeout: float, record: bool = False) -> None:
        self.sock = connect(host, port, timeout)
        self.decoder = reply_decoder()
        self.record = record
        self.sent: list[tuple[float, bytes]] = []
        self.received: list[tuple[float, bytes]] = []
        self.eof = False
        self.got = 0  # bytes received

    def close(self) -> None:
        with contextlib.suppress(OSError):
            self.sock.close()

    def send(self, data: bytes, delivery: Delivery = WHOLE) -> None:
        for chunk, pause in delivery.chunks(data):
            if pause:
                time.sleep(pause)
            if len(chunk) <= BIG_SEND:
                self.sock.sendall(chunk)
            else:
                self._send_reading(chunk)
            if self.record:
                self.sent.append((time.time(), chunk))

    def _send_reading(self, data: bytes) -> None:
        """Send a big chunk while reading replies, so a peer blocked on writing to us cannot deadlock us."""
        view, pos = memoryview(data), 0
        deadline = time.monotonic() + session_deadline(self.sock.gettimeout() or 1.0, 0, len(data))
        while pos < len(data):
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("send timed out")
            readable, writable, _ = select.select([self.sock], [self.sock], [], left)
            if readable and not self.eof:
                got = self.sock.recv(RECV)
                if not got:
                    self.eof = True
                    raise ConnectionResetError("peer closed while we were sending")
                if self.record:
                    self.received.append((time.time(), got))
                self.got += len(got)
                self.decoder.receive_data(got)
            if writable:
                pos += self.sock.send(view[pos : pos + BIG_SEND])

    def shut_write(self) -> None:
        with contextlib.suppress(OSError):
            self.sock.shutdown(socket.SHUT_WR)

    def read_replies(self, want: int | None, deadline: float) -> tuple[list[Telegram], str | None, bool]:
        """Replies until ``want`` of them (None: until EOF); (replies, bad reply reason, timed out)."""
        replies: list[Telegram] = []
        while want is None or len(replies) < want:
            try:
                t = self.decoder.next_telegram()
            except errors.RemoteProtocolError as exc:
                return replies, f"reply does not decode: {type(exc).__name__}: {exc}", False
            if t is not None:
                replies.append(t)
                continue
            if self.eof:
                try:
                    self.decoder.receive_data(b"")
                    self.decoder.next_telegram()
                except errors.RemoteProtocolError as exc:
                    return replies, f"{CUT}: {exc}", False
                return replies, None, False
            left = deadline - time.monotonic()
            if left <= 0:
                return replies, None, True
            self.sock.settimeout(left)
            try:
                data = self.sock.recv(RECV)
            except TimeoutError:
                return replies, None, True
            except OSError:
                data = b""
            if self.record and data:
                self.received.append((time.time(), data))
            if not data:
                self.eof = True
                continue
            self.got += len(data)
            self.decoder.receive_data(data)
        return replies, None, False


def check_order(replies: list[Telegram], expected: list[int], data: bytes = b"") -> str | None:
    """Why the replies do not answer the requests in order, or None. Replies past a malformed frame are allowed
    where they answer the well-formed frames of ``data`` in order: a target that skips a malformed frame and
    goes on (errata E-WIRE-006 and E-BEH-005, zoo lenient-framing) answers what follows it."""
    got = [r.ID for r in replies]
    if got == expected[: len(got)] and len(got) <= len(expected):
        return None
    if data and len(got) > len(expected) and got == skipping_ids(data)[: len(got)]:
        return None
    return f"reply ids {got[:20]} do not follow the answered requests {expected[:20]}"


def play(host: str, port: int, session: Session, deadline_s: float, record: bool = False) -> Outcome:
    """Run one session on a fresh connection."""
    out = Outcome()
    try:
        conn = Conn(host, port, deadline_s, record)
    except ConnectionRefusedError:
        out.refused = True
        return out
    except OSError:
        out.closed = True
        return out
    try:
        play_on(conn, session, deadline_s, out)
    finally:
        conn.close()
        out.sent, out.received = conn.sent, conn.received
    return out


def play_on(conn: Conn, session: Session, deadline_s: float, out: Outcome) -> None:
    """Run ``session`` on an open connection (a kept batch connection, or a fresh one)."""
    data = session.data
    expected = session_reply_ids(session)
    deadline = time.monotonic() + session_deadline(deadline_s, len(session.frames), len(data))
    gate = session.gate_bytes
    try:
        if gate:  # the lead alone, then the rest once the target has answered it
            conn.send(data[:gate])
            lead, bad, timed_out = conn.read_replies(1, deadline)
            out.replies.extend(lead)
            if bad is not None or timed_out or not lead:
                out.bad_reply, out.timed_out, out.closed, out.got = bad, timed_out, conn.eof, conn.got
                return
            data = data[gate:]
        conn.send(data, session.delivery)
        if session.sync:
            conn.send(GET_STATUS)
            expected.append(REQUESTS.CMD_GET_STATUS.ID)
        if session.half_close and session.fin_waits:  # the replies asked for first: our FIN ends the session
            owed, bad, timed_out = conn.read_replies(len(expected) - len(out.replies), deadline)
            out.replies.extend(owed)
            if bad is not None or timed_out or conn.eof:
                out.bad_reply, out.timed_out, out.closed, out.got = bad, timed_out, conn.eof, conn.got
                out.bad_reply = out.bad_reply or check_order(out.replies, expected, data)
                return
        if session.half_close:
            conn.shut_write()
    except OSError:
        conn.eof = True  # the peer is gone; read what it said before it went
    want = len(expected) - len(out.replies) if session.sync and not session.half_close else None
    replies, bad, timed_out = conn.read_replies(want, deadline)
    out.replies.extend(replies)
    out.bad_reply = bad or check_order(out.replies, expected, session.data)
    out.timed_out = timed_out
    out.closed = conn.eof or (want is not None and len(replies) < want)
    out.got = conn.got


def served(out: Outcome, session: Session) -> bool:
    """Whether the target served the connection: for a led session, anything came back; else not refused."""
    return out.got > 0 or bool(out.replies) if session.led else not out.refused


def play_admitted(
    host: str,
    port: int,
    session: Session,
    deadline_s: float,
    patience: float,
    record: bool = False,
    alive: Callable[[], bool] | None = None,
) -> tuple[Outcome, bool]:
    """``play`` again, after a growing pause, while the target turns the connection away (``pltf.fuzz.gate``), for
    ``patience`` seconds at most; (the last outcome, served). One left unanswered for the deadline is not tried
    again: the port is held (by a stalled connection, or a target that stopped); nor one of a process that
    ``alive`` says has ended."""
    end = time.monotonic() + patience
    backoff = BACKOFF_FIRST
    while True:
        out = play(host, port, session, deadline_s, record)
        gone = alive is not None and not alive()
        if served(out, session) or out.timed_out or gone or time.monotonic() >= end:
            return out, served(out, session)
        time.sleep(backoff)
        backoff = min(BACKOFF_MAX, backoff * BACKOFF_GROWTH)
