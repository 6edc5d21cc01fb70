"""Sessions in flight side by side: one non-blocking connection per port, driven by one ``select`` loop.

Rules:
- PlatformCtrl serves one client per port (guide 6.1) and both ports take every command, so two cases - one
  per port - can be in flight at once. The target works on one while we prepare or read the other; a
  sequential fuzzer leaves both sides idle half of the time.
- A ``Flight`` is a ``fuzz.target.Session`` on its own connection (whole delivery only: slow and bytewise
  cases keep the blocking path), with the same outcome and the same reply checks as ``fuzz.target.play``.
- ``fly`` runs flights to completion or to their deadlines; it never raises for anything the peer does.
"""

from __future__ import annotations

import contextlib
import errno
import select
import socket
import time

from fuzz.replies import reply_decoder
from fuzz.target import CUT, GET_STATUS, RECV, Outcome, Session, check_order, session_deadline, session_reply_ids
from spec import errors
from spec.codec import REQUESTS

CHUNK = 1 << 16
_RESET = (errno.ECONNRESET, errno.EPIPE)


class Flight:
    def __init__(self, host: str, port: int, session: Session, deadline_s: float) -> None:
        self.session = session
        self.out = Outcome()
        data = session.data
        self.expected = session_reply_ids(session)
        if session.sync:
            data += GET_STATUS
            self.expected.append(REQUESTS.CMD_GET_STATUS.ID)
        self.data, self.pos = data, 0
        self.want = len(self.expected) if session.sync and not session.half_close else None
        self.budget = session_deadline(deadline_s, len(session.frames), len(data))  # s from its turn
        self.deadline = time.monotonic() + self.budget
        self.decoder = reply_decoder()
        self.done = False
        self.reset = False  # the peer reset the connection (a close with our input unread)
        self.sending = True
        self.sock = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM)
        self.sock.setblocking(False)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.connected = False
        code = self.sock.connect_ex((host, port))
        if code not in (0, errno.EINPROGRESS):
            self._finish(refused=code == errno.ECONNREFUSED, closed=code != errno.ECONNREFUSED)
        else:
            self._send_now()

    def _send_now(self) -> None:
        """Send at once: on loopback the handshake is done when ``connect_ex`` returns (no select round)."""
        try:
            sent = self.sock.send(self.data[:CHUNK])
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
        self.pos = sent
        if self.pos >= len(self.data):
            self.sending = False
            if self.session.half_close:
                with contextlib.suppress(OSError):
                    self.sock.shutdown(socket.SHUT_WR)

    def fileno(self) -> int:
        return self.sock.fileno()

    def _finish(self, refused: bool = False, closed: bool = False, timed_out: bool = False) -> None:
        if self.done:
            return
        self.done = True
        self.out.refused, self.out.timed_out = refused, timed_out
        self.out.closed = closed or (self.want is not None and len(self.out.replies) < self.want)
        if self.out.bad_reply is None and not refused:
            self.out.bad_reply = check_order(self.out.replies, self.expected)
        self.sock.close()

    def writable(self) -> None:
        if not self.connected:
            code = self.sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if code:
                self._finish(refused=code == errno.ECONNREFUSED, closed=code != errno.ECONNREFUSED)
                return
            self.connected = True
        try:
            self.pos += self.sock.send(self.data[self.pos : self.pos + CHUNK])
        except BlockingIOError:
            return
        except OSError as exc:
            self.sending = False  # the peer is gone; read what it said before it went
            self.reset = exc.errno in _RESET
            return
        if self.pos >= len(self.data):
            self.sending = False
            if self.session.half_close:
                with contextlib.suppress(OSError):
                    self.sock.shutdown(socket.SHUT_WR)

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
            self.decoder.receive_data(data)
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


def fly(flights: list[Flight]) -> None:
    """Drive ``flights`` until each is done or past its deadline."""
    while live := [f for f in flights if not f.done]:
        _step(live)


def step_flights(flights: list[Flight]) -> list[Flight]:
    """Drive ``flights`` until at least one of them is done (or past its deadline); the ones done."""
    while not (done := [f for f in flights if f.done]):
        _step(flights)
    return done


def _step(live: list[Flight]) -> None:
    """One round over flights not done: finish those past their deadline; if none was, wait for the sockets
    of all of them until the nearest deadline and drive the ones that are ready."""
    now = time.monotonic()
    overdue = [f for f in live if now >= f.deadline]
    for f in overdue:
        f._finish(timed_out=True)
    if overdue:
        return  # the caller looks at the flights again
    wait = max(0.0, min(f.deadline for f in live) - now)
    writers = [f for f in live if f.sending or not f.connected]
    readable, writable, _ = select.select(live, writers, [], wait)
    for f in writable:
        if not f.done:
            f.writable()
    for f in readable:
        if not f.done:
            f.readable()
