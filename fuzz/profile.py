"""What the fuzzer learns about a target before it fuzzes it: the target profile (issue 32).

Rules:
- A short opening phase on the target's first port, before any case: blocking sockets with deadlines, like
  ``pltf.fuzz.target``. It measures how long a fresh connection takes to be served (the connection set-up) and a
  reply on a kept one; whether anything is answered before CMD_CONNECT_TO_PLTF; whether the target still answers
  what it owes after our half-close (FIN) or ends the session at it; what a newcomer meets while the port is busy
  (served, closed with FIN, reset, refused, kept in the listen backlog - and how many such connects complete);
  whether it ends a session with a reset (RST) instead of a FIN.
- Nothing here is a finding: each behaviour is a reading the guide allows (spec/errata/behaviour.yaml). The
  campaign then relies on none the target lacks: where our FIN ends the session, or the target ends it with a reset
  (which throws away what it had sent and we had not read yet: a big reply, read late on a loaded machine), a
  session waits for the replies it is owed before it half-closes (``Session.fin_waits``); where nothing is
  answered before CMD_CONNECT_TO_PLTF, every session opens with it (``Profile.adapt``, applied by the lanes and
  the replays); a fresh connection that costs far more than a reply makes the ports dear from the start, a listen
  backlog no deeper than the pipelining turns pipelining off (``pltf.fuzz.engine``).
- ``describe`` is the line the console and summary.json show: "ends the session at our FIN; turns newcomers away
  with RST; replies in 2 ms".
- Every failure to learn says what was seen and where: the port, the flag that named it, and what the target did
  ("connected, sent CMD_GET_POSITION, the target closed without a reply").
"""

from __future__ import annotations

import contextlib
import select
import socket
import statistics
import time
from collections.abc import Iterator
from dataclasses import asdict, dataclass, replace

from pltf.fuzz.gate import DEPTH
from pltf.fuzz.replies import reply_decoder
from pltf.fuzz.target import LEAD, Session, connect
from pltf.spec.codec import REQUESTS, encode

CONNECT_TO_PLTF = encode(REQUESTS.CMD_CONNECT_TO_PLTF())
SHUTDOWN_PLTF = encode(REQUESTS.CMD_SHUTDOWN_PLTF())
FIN_REPLIES = 4  # leads sent with our FIN: all answered, or the FIN ended the session
FIN_TRIES = 3  # a relay that forwards fast may deliver every reply once; any try that loses one is the evidence
# Requests and our FIN leave in one segment (TCP_CORK holds the requests, the FIN is tacked on to them): written
# apart, a loaded machine ran the target between the two system calls often enough that every reply came before
# the FIN reached it, and a target whose FIN ends the session was taken for one that answers after it (then the
# campaign half-closed at once, units came back unanswered, and a suspicion's replays were never served: the
# 'dropped' that no replay cleared, issue 32). Measured on loopback: written apart, the FIN was not there yet when
# the reader (a thread beside the writer) took the requests in 1,267 of 1,500 connections; corked, in none.
TCP_CORK = getattr(socket, "TCP_CORK", None)  # Linux; elsewhere the two writes as they come
REPLY_SAMPLES = 5
BACKLOG_PROBES = 4  # connects tried while the port is busy and keeps newcomers waiting
BACKLOG_WAIT = 0.5  # s a connect may take before its SYN counts as dropped
NEWCOMER_WAIT = 1.0  # s a newcomer on a busy port is watched at most
NO_REPLY = "the target sent no reply"
SLOW_SETUP_MS = 20.0  # a fresh connection served this much later than a reply, and ...
SLOW_SETUP_RATIO = 2.0  # ... this many replies' time later, is dear
SERVED_RETRIES = 20  # fresh connections tried at least while a port that frees slowly turns us away, ...
# ... and for as long as the deadline lasts: on a loaded machine a target (and a relay in front of it) may take
# far longer than twenty quick tries (0.1-0.4 s) to let our last client go (2026-11-28, load 18-25: two of 56
# starts of four campaigns side by side ended in a harness error, every try closed or reset without a reply)
TURN_AWAY = {  # what a newcomer on a busy port met -> how the profile says it
    "served": "serves a second client on a port",
    "fin": "turns newcomers away with FIN",
    "rst": "turns newcomers away with RST",
    "refused": "refuses newcomers (the port stops listening)",
    "backlog": "keeps newcomers waiting in the listen backlog",
}


class ProfileError(RuntimeError):
    """The target did not answer the opening phase (the harness cannot fuzz it: exit status 2)."""


@dataclass
class Profile:
    setup_ms: float = 0.0  # median over fresh connections: connect-to-first-reply less the same one's next reply
    reply_ms: float = 0.0  # median reply time on a kept connection
    fin_ends: bool = False  # our half-close ends the session: replies still owed are lost
    resets: bool = False  # it ends a session with RST (erratum E-BEH-002): what we had not read yet may be lost
    silent_before_connect: bool = False  # nothing is answered before CMD_CONNECT_TO_PLTF
    newcomer: str = ""  # a key of TURN_AWAY
    backlog: int | None = None  # connects that complete while the port is busy (a backlog target), else None

    @property
    def slow_setup(self) -> bool:
        """A fresh connection costs much more than a reply (a timer-driven accept, a slow handshake; the set-up is
        measured against the same connection's next reply, so a loaded machine inflates both alike): the campaign
        runs its batches on a kept connection from the start (``pltf.fuzz.trial`` settled)."""
        return self.setup_ms >= SLOW_SETUP_MS and self.setup_ms >= SLOW_SETUP_RATIO * self.reply_ms

    @property
    def small_backlog(self) -> bool:
        """The listen backlog holds fewer connects than the campaign pipelines on a port (``pltf.fuzz.gate.DEPTH``):
        the SYNs beyond it are dropped and a connect waits for the kernel's retry (a second or more)."""
        return self.backlog is not None and self.backlog <= DEPTH

    @property
    def fin_waits(self) -> bool:
        """Our FIN waits for the replies owed: the target ends the session at it, or ends it with a reset, whose
        RST discards the bytes the target sent and we had not read yet (matrix rows 1 and 3)."""
        return self.fin_ends or self.resets

    def describe(self) -> str:
        parts = ["ends the session at our FIN" if self.fin_ends else "answers after our FIN"]
        if self.resets:
            parts.append("ends a session with RST: our FIN waits for the replies owed")
        if self.silent_before_connect:
            parts.append("answers nothing before CMD_CONNECT_TO_PLTF")
        if self.newcomer:
            parts.append(TURN_AWAY[self.newcomer])
        if self.backlog is not None:
            parts.append(f"{self.backlog} connect(s) complete while the port is busy (its listen backlog)")
            if self.small_backlog:
                parts.append("no pipelining")
        parts.append(f"replies in {self.reply_ms:.3g} ms, a fresh connection is served in {self.setup_ms:.3g} ms more")
        if self.slow_setup:
            parts.append("fresh connections are dear: batches on a kept connection")
        return "; ".join(parts)

    def adapt(self, session: Session) -> Session:
        """``session`` as this target needs it: our FIN only after the replies owed (where it ends the session);
        where nothing is answered before CMD_CONNECT_TO_PLTF, it in front of the session's first frame (the lead,
        or on a session without one its prelude or case) and behind every CMD_SHUTDOWN_PLTF (a platform not
        connected answers nothing: a state it cannot be fuzzed in)."""
        if self.silent_before_connect:
            session = _connected(session)
        return replace(session, fin_waits=True) if self.fin_waits and not session.fin_waits else session

    def to_json(self) -> dict[str, object]:
        return asdict(self) | {"summary": self.describe()}


def _connected(session: Session) -> Session:
    """The session with CMD_CONNECT_TO_PLTF in its first frame and in each CMD_SHUTDOWN_PLTF's (frame indices and
    the replies asked for stay: CMD_CONNECT_TO_PLTF has no reply). Not only in the lead's: a session without a lead
    (past the first units, ``pltf.fuzz.lanes``) whose prelude does not connect would have its prelude's replies
    swallowed, and the target judged for replies it never owed."""
    frames = [f + CONNECT_TO_PLTF if f == SHUTDOWN_PLTF else f for f in session.frames]
    if frames and not frames[0].startswith(CONNECT_TO_PLTF):
        frames[0] = CONNECT_TO_PLTF + frames[0]
    return replace(session, frames=frames) if frames != session.frames else session


def learn(host: str, port: int, flag: str, deadline: float) -> Profile:
    """The profile of the target at ``host:port`` (``flag``: the option that named the port, for messages)."""
    where = f"{host}:{port} ({flag})"
    prof = Profile()
    first, setup = _first_served(host, port, deadline, where, prof)
    setups: list[float] = []
    try:
        prof.reply_ms = _reply_ms(first, deadline, setup, setups)
        prof.newcomer, prof.backlog = _newcomer(host, port, deadline)
    finally:
        _close(first, deadline)
    ends = [_fin_ends(host, port, deadline, prof, setups) for _ in range(FIN_TRIES)]
    prof.fin_ends = any(lost for lost, _ in ends)
    prof.resets = any(reset for _, reset in ends)
    prof.setup_ms = round(statistics.median(setups), 3) if setups else 0.0
    return prof


def _lead(prof: Profile) -> bytes:
    return CONNECT_TO_PLTF + LEAD if prof.silent_before_connect else LEAD


def _first_served(host: str, port: int, deadline: float, where: str, prof: Profile) -> tuple[socket.socket, float]:
    """A connection the target served (its lead answered) and the ms from the connect to that reply. A target that
    answers nothing before CMD_CONNECT_TO_PLTF is asked again with it in front."""
    seen = ""
    for lead in (LEAD, CONNECT_TO_PLTF + LEAD):
        prof.silent_before_connect = lead != LEAD
        for k in _tries(deadline):
            t0 = time.monotonic()
            try:
                s = connect(host, port, deadline)
            except ConnectionRefusedError:
                raise ProfileError(f"nothing listening on {where}: connection refused") from None
            except OSError as exc:
                raise ProfileError(f"cannot connect to {where}: {exc}") from None
            got, how = _ask(s, lead, 1, deadline)
            if got:
                return s, (time.monotonic() - t0) * 1000
            s.close()
            seen = how
            if how == NO_REPLY:
                break  # unanswered: try the next lead (a port held by another client turns us away at once)
            time.sleep(0.005 * (1 + k % 4))  # a port that frees slowly turned us away: again
    raise ProfileError(
        f"the target does not answer on {where}: connected, sent CMD_GET_POSITION (also behind "
        f"CMD_CONNECT_TO_PLTF), {seen} within {deadline:g} s"
    )


def _ask(s: socket.socket, data: bytes, want: int, deadline: float, fin: bool = False) -> tuple[int, str]:
    """Send ``data`` (then our FIN with ``fin``) and count replies until ``want`` of them, the target's close or
    the deadline; (replies, what ended the wait)."""
    dec = reply_decoder()
    end = time.monotonic() + deadline
    try:
        if fin and TCP_CORK is not None:
            s.setsockopt(socket.IPPROTO_TCP, TCP_CORK, 1)
        s.sendall(data)
        if fin:
            s.shutdown(socket.SHUT_WR)  # tacked on to the corked requests
    except OSError:
        return 0, "the target closed the connection before we had sent"
    got = 0
    while got < want:
        left = end - time.monotonic()
        if left <= 0:
            return got, NO_REPLY if not got else f"{got} of {want} replies came"
        s.settimeout(left)
        try:
            data = s.recv(1 << 16)
        except TimeoutError:
            continue
        except ConnectionResetError:
            return got, "the target reset the connection without a reply" if not got else "reset"
        except OSError as exc:
            return got, f"the connection failed: {exc}"
        if not data:
            return got, "the target closed without a reply" if not got else f"closed after {got} of {want} replies"
        dec.receive_data(data)
        got += sum(1 for _ in dec)
    return got, "answered"


def _reply_ms(s: socket.socket, deadline: float, first_ms: float, setups: list[float]) -> float:
    """The median reply time on ``s``; ``setups`` gets its first reply's time over its second's (``first_ms``:
    the connect to the first reply), measured side by side so that the machine's load cancels out."""
    times = []
    for _ in range(REPLY_SAMPLES):
        t0 = time.monotonic()
        if _ask(s, LEAD, 1, deadline)[0] != 1:
            break
        times.append((time.monotonic() - t0) * 1000)
    if times:
        setups.append(max(0.0, first_ms - times[0]))
    return round(statistics.median(times), 3) if times else 0.0


def _newcomer(host: str, port: int, deadline: float) -> tuple[str, int | None]:
    """What a second client meets while ``s`` holds the port, and for a backlog target how many connects
    complete."""
    try:
        t = connect(host, port, min(deadline, NEWCOMER_WAIT))
    except ConnectionRefusedError:
        return "refused", None
    except OSError:
        return "rst", None
    try:
        got, how = _ask(t, LEAD, 1, min(deadline, NEWCOMER_WAIT))
    finally:
        t.close()
    if got:
        return "served", None
    if how == NO_REPLY:
        return "backlog", _backlog(host, port)
    return ("rst" if "reset" in how else "fin"), None


def _backlog(host: str, port: int) -> int:
    """Connects that complete within ``BACKLOG_WAIT`` while the port is held (each a SYN the backlog took)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    socks = [socket.socket(family, socket.SOCK_STREAM) for _ in range(BACKLOG_PROBES)]
    try:
        for s in socks:
            s.setblocking(False)
            s.connect_ex((host, port))
        end, done = time.monotonic() + BACKLOG_WAIT, set[socket.socket]()
        while len(done) < len(socks) and (left := end - time.monotonic()) > 0:
            _, writable, _ = select.select([], [s for s in socks if s not in done], [], left)
            done |= {s for s in writable if s.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR) == 0}
        return len(done) + 1  # the one watched before these
    finally:
        for s in socks:
            s.close()


def _fin_ends(host: str, port: int, deadline: float, prof: Profile, setups: list[float]) -> tuple[bool, bool]:
    """(whether the replies owed at our FIN are lost, whether the session then ended with a reset): served (its
    lead answered), then ``FIN_REPLIES`` leads and our FIN in one write, read to the end. ``setups`` gets the ms
    the connection's first reply took over its second's (a port that frees slowly and turns us away first is dear
    anyway: ``pltf.fuzz.gate``)."""
    t0 = time.monotonic()
    s = _served_again(host, port, deadline, prof)
    if s is None:
        return False, False  # the port did not serve us again: nothing learnt (the campaign's start will say so)
    first_ms = (time.monotonic() - t0) * 1000
    try:
        t1 = time.monotonic()
        if _ask(s, LEAD, 1, deadline)[0] == 1:  # the same connection's second reply: the set-up is the difference
            setups.append(max(0.0, first_ms - (time.monotonic() - t1) * 1000))
        got, how = _ask(s, LEAD * FIN_REPLIES, FIN_REPLIES, deadline, fin=True)
        reset = "reset" in how or (got == FIN_REPLIES and _ends_with_reset(s, deadline))
    finally:
        s.close()
    return got < FIN_REPLIES, reset


def _ends_with_reset(s: socket.socket, deadline: float) -> bool:
    """Read ``s`` to its end: whether the target ended it with a reset (not a FIN, nor the deadline)."""
    s.settimeout(deadline)
    try:
        while s.recv(1 << 16):
            pass
    except ConnectionResetError:
        return True
    except OSError:
        return False
    return False


def _tries(deadline: float) -> Iterator[int]:
    """0, 1, 2, ...: ``SERVED_RETRIES`` tries at least, and more until ``deadline`` seconds have passed."""
    end = time.monotonic() + deadline
    k = 0
    while k < SERVED_RETRIES or time.monotonic() < end:
        yield k
        k += 1


def _served_again(host: str, port: int, deadline: float, prof: Profile) -> socket.socket | None:
    for k in _tries(deadline):
        try:
            s = connect(host, port, deadline)
        except OSError:
            s = None
        if s is not None and _ask(s, _lead(prof), 1, deadline)[0]:
            return s
        if s is not None:
            s.close()
        time.sleep(0.005 * (1 + k % 4))
    return None


def _close(s: socket.socket, deadline: float) -> None:
    """Our FIN, then the target's close (or the deadline): the port is free for what comes next."""
    with contextlib.suppress(OSError):
        s.shutdown(socket.SHUT_WR)
        s.settimeout(deadline)
        while s.recv(1 << 16):
            pass
    s.close()
