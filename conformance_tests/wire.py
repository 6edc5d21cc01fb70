"""A blocking TCP session with a PlatformCtrl target, and the wire log of everything it saw.

Rules:
- Only this module (and the launcher, the mutant proxy and the stateful replay) opens sockets. Every byte sent
  and received is appended to the case's ``WireLog`` with a timestamp, so a report can show the exchange.
- A reply is read frame by frame (guide 6.2: header FF 01 FE 02, uint32 N, N data bytes) and decoded strictly
  by ``readings.decode_reply``: no trailing bytes, counts consistent, enums in range. A frame whose first
  four bytes are not the header but read as a plausible length followed by the expected identifier is taken
  as a header-less reply, an alternative reading of erratum E-WIRE-001 (recorded as a deviation).
- Frames that arrive while a reply is awaited but carry another identifier are unsolicited (guide 6.1: the
  interface "returns data only on request"); they are logged and reported to the observer, then skipped.
- Pipelining (``exchange``, erratum E-WIRE-008): several requests leave back to back before their replies are
  read; the replies are read in the order asked. A reply to a request asked later that comes first is a
  ``BadReply`` (E-WIRE-008), never taken for the one awaited. A ``Pause`` between two requests is a wait
  between two writes (a command's chance to show an effect before the status that judges it is asked).
- ``Session.events`` counts what could change the target since a status was read: every write, connect and
  close of any session of the run (context.py keeps a status only while it has not moved).
- Target misbehaviour raises ``outcome.TargetFailure`` subclasses; only harness bugs raise anything else.
"""

from __future__ import annotations

import contextlib
import select
import socket
import struct
import time
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar, Protocol

from pltf.conformance_tests import readings
from pltf.conformance_tests.outcome import (
    BadReply,
    BudgetSpent,
    ConnectionClosed,
    Deviation,
    ReplyTimeout,
    Unreachable,
)
from pltf.spec.codec import DEFAULT_MAX_LENGTH, HEADER, REQUESTS, encode
from pltf.spec.telegram import Telegram

LOG_BYTES = 512  # bytes of one wire-log entry kept in full; the rest is summarised


@dataclass(frozen=True)
class WireEntry:
    t: float  # seconds since the log began
    port: str  # the session's label ("A", "B", "A2", ...)
    direction: str  # "tx", "rx" or "ev" (connect, close, timeout, ...)
    data: bytes
    note: str = ""
    size: int = 0  # the full size when ``data`` was cut to LOG_BYTES

    def hex(self) -> str:
        text = self.data.hex()
        if self.size > len(self.data):
            text += f"... ({self.size} bytes)"
        return text


@dataclass
class WireLog:
    t0: float = field(default_factory=time.monotonic)
    entries: list[WireEntry] = field(default_factory=list)
    max_entries: int = 2000
    sent: int = 0  # writes logged (kept counting past ``max_entries``): has anything been sent since?

    def add(self, port: str, direction: str, data: bytes = b"", note: str = "") -> None:
        self.sent += direction == "tx"
        if len(self.entries) >= self.max_entries:
            if len(self.entries) == self.max_entries:
                self.entries.append(WireEntry(time.monotonic() - self.t0, port, "ev", b"", "wire log truncated"))
            return
        self.entries.append(
            WireEntry(time.monotonic() - self.t0, port, direction, bytes(data[:LOG_BYTES]), note, len(data))
        )


class Observer(Protocol):
    def on_sent(self, telegram: Telegram) -> None: ...
    def on_received(self, telegram: Telegram) -> None: ...
    def on_deviation(self, deviation: Deviation) -> None: ...
    def on_unsolicited(self, port: str, data: bytes) -> None: ...


class NullObserver:
    """An observer that records nothing (reachability probes, sessions nobody watches)."""

    def on_sent(self, telegram: Telegram) -> None:
        pass

    def on_received(self, telegram: Telegram) -> None:
        pass

    def on_deviation(self, deviation: Deviation) -> None:
        pass

    def on_unsolicited(self, port: str, data: bytes) -> None:
        pass


_LEN = struct.Struct(">I")


@dataclass(frozen=True)
class Pause:
    """A wait of ``seconds`` between two writes of an ``exchange``."""

    seconds: float


def answered(name: str) -> bool:
    """Guide 6.1: only the telegrams with a reply table (the GET_* requests) are answered (E-CMD-013)."""
    return REQUESTS[name].DEF.answered


@dataclass
class CaseBudget:
    """The wall-clock end of the running case's budget (monotonic s; None: none). Every read of a session that
    carries it ends there with ``BudgetSpent`` (conformance_tests/pace.py sets it)."""

    deadline: float | None = None
    seconds: float = 0.0

    def clip(self, deadline: float) -> float:
        return deadline if self.deadline is None else min(deadline, self.deadline)

    def check(self) -> None:
        if self.deadline is not None and time.monotonic() >= self.deadline:
            raise BudgetSpent(
                f"case budget of {self.seconds:.0f} s spent: the target is too slow to finish this case in it"
            )


class Session:
    """One TCP connection to one port of the target."""

    events: ClassVar[int] = 0  # writes, connects and closes of every session (see the module rules)

    def __init__(
        self,
        host: str,
        port: int,
        *,
        label: str = "A",
        log: WireLog | None = None,
        timeout: float = 3.0,
        observer: Observer | None = None,
        profile: str = "strict",
        budget: CaseBudget | None = None,
    ) -> None:
        self.host, self.port, self.label = host, port, label
        self.budget = budget
        self.log = log if log is not None else WireLog()
        self.timeout = timeout
        self.observer: Observer = observer or NullObserver()
        self.profile = profile
        self.sock: socket.socket | None = None
        self._rx = bytearray()
        self._asked: deque[str] = deque()  # requests sent by ``send_pipelined`` whose replies are still unread
        self.eof = False

    # ---- connection
    def connect(self, timeout: float | None = None) -> Session:
        try:
            self.sock = socket.create_connection((self.host, self.port), timeout=timeout or self.timeout)
        except OSError as exc:
            self.log.add(self.label, "ev", note=f"connect to {self.host}:{self.port} failed: {exc}")
            raise Unreachable(f"cannot connect to {self.host}:{self.port}: {exc}") from None
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        Session.events += 1
        self._rx.clear()
        self.eof = False
        self.log.add(self.label, "ev", note=f"connected to {self.host}:{self.port}")
        return self

    @property
    def is_open(self) -> bool:
        return self.sock is not None and not self.eof

    def close(self) -> None:
        if self.sock is not None:
            Session.events += 1
            with contextlib.suppress(OSError):
                self.sock.close()
            self.log.add(self.label, "ev", note="closed by us")
        self.sock = None
        self._asked.clear()

    def shutdown_write(self) -> None:
        """TCP half-close: we send no more, the target may still send."""
        assert self.sock is not None
        with contextlib.suppress(OSError):
            self.sock.shutdown(socket.SHUT_WR)
        self.log.add(self.label, "ev", note="half-closed (SHUT_WR) by us")

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---- sending
    def send(self, telegram: Telegram) -> None:
        data = encode(telegram)
        self._sendall(data, telegram.NAME)
        self.observer.on_sent(telegram)

    def send_many(self, telegrams: list[Telegram], note: str) -> None:
        """Send several telegrams back to back in one write, logged as one entry."""
        self._sendall(b"".join(encode(t) for t in telegrams), note)
        for t in telegrams:
            self.observer.on_sent(t)

    def send_raw(self, data: bytes, note: str = "raw bytes") -> None:
        self._sendall(data, note)

    def send_chunks(self, chunks: list[bytes], gap: float = 0.0, note: str = "chunk") -> None:
        for i, chunk in enumerate(chunks):
            self._sendall(chunk, f"{note} {i + 1}/{len(chunks)}")
            if gap and i + 1 < len(chunks):
                time.sleep(gap)

    def _sendall(self, data: bytes, note: str) -> None:
        if self.sock is None:
            raise ConnectionClosed(f"port {self.label}: not connected")
        Session.events += 1
        self.log.add(self.label, "tx", data, note)
        try:
            self.sock.sendall(data)
        except (BrokenPipeError, ConnectionResetError, ConnectionAbortedError) as exc:
            self.eof = True
            self.log.add(self.label, "ev", note=f"send failed: {exc}")
            raise ConnectionClosed(f"port {self.label}: the target closed the connection ({exc})") from None
        except TimeoutError:
            raise ReplyTimeout(f"port {self.label}: the target did not take {len(data)} bytes in time") from None

    # ---- receiving
    def _fill(self, deadline: float) -> bool:
        """Receive some bytes before ``deadline``; False on timeout; ConnectionClosed at EOF."""
        if self.eof or self.sock is None:
            raise ConnectionClosed(f"port {self.label}: the connection is closed")
        if self.budget is not None:
            self.budget.check()
            deadline = self.budget.clip(deadline)
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            return False
        self.sock.settimeout(remaining)
        try:
            data = self.sock.recv(65536)
        except TimeoutError:
            if self.budget is not None:
                self.budget.check()
            return False
        except (ConnectionResetError, ConnectionAbortedError) as exc:
            data = b""
            self.log.add(self.label, "ev", note=f"reset by the target: {exc}")
        if not data:
            self.eof = True
            self.log.add(self.label, "ev", note="EOF: closed by the target")
            raise ConnectionClosed(f"port {self.label}: the target closed the connection")
        self._rx += data
        return True

    def _need(self, n: int, deadline: float, what: str) -> None:
        while len(self._rx) < n:
            try:
                ok = self._fill(deadline)
            except ConnectionClosed:
                if self._rx:
                    self.log.add(self.label, "rx", bytes(self._rx), f"incomplete {what}")
                    raise ConnectionClosed(
                        f"port {self.label}: the target closed the connection inside {what} "
                        f"({len(self._rx)} of {n} bytes)"
                    ) from None
                raise
            if not ok:
                if self._rx:
                    self.log.add(self.label, "rx", bytes(self._rx), f"incomplete {what}")
                raise ReplyTimeout(
                    f"port {self.label}: no complete {what} within {self.timeout:.1f} s "
                    f"({len(self._rx)} of {n} bytes received)"
                )

    def read_frame(self, timeout: float | None = None, expect_id: int | None = None) -> tuple[bytes, bool]:
        """The data of the next frame (identifier first) and whether it came without a header."""
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        self._need(8, deadline, "reply frame header")
        head = bytes(self._rx[:4])
        if head == HEADER:
            (length,) = _LEN.unpack_from(self._rx, 4)
            start, headerless = 8, False
        else:
            (length,) = _LEN.unpack_from(self._rx, 0)
            start, headerless = 4, True
            plausible = 0 < length <= DEFAULT_MAX_LENGTH and (expect_id is None or self._rx[4] == expect_id)
            if not plausible:
                self.log.add(self.label, "rx", bytes(self._rx[:64]), "bad reply header")
                raise BadReply(
                    f"port {self.label}: reply does not start with the header ff01fe02 (got {head.hex()})",
                    erratum="E-WIRE-001",
                )
        if length > DEFAULT_MAX_LENGTH:
            raise BadReply(
                f"port {self.label}: reply frame length {length} over {DEFAULT_MAX_LENGTH}", erratum="E-WIRE-004"
            )
        if length == 0:
            self.log.add(self.label, "rx", bytes(self._rx[:start]), "empty reply frame")
            raise BadReply(f"port {self.label}: reply frame with length 0 (no telegram identifier)")
        self._need(start + length, deadline, "reply frame")
        raw = bytes(self._rx[: start + length])
        del self._rx[: start + length]
        data = raw[start:]
        name = REQUESTS.by_id[data[0]].NAME if data[0] in REQUESTS.by_id else f"id {data[0]}"
        self.log.add(self.label, "rx", raw, f"{name}{' (no header)' if headerless else ''}")
        return data, headerless

    def read_reply(self, name: str, timeout: float | None = None) -> Telegram:
        """The next reply to request ``name``, decoded strictly (unsolicited frames are reported and skipped).
        Replies pipelined before and not read yet are read and dropped first."""
        while self._asked:
            self.next_reply(timeout)
        return self._read_reply(name, timeout, ())

    def _read_reply(self, name: str, timeout: float | None, later: Sequence[str]) -> Telegram:
        """``read_reply``; a reply to one of ``later`` (asked after ``name``) that comes first is out of order."""
        expect = REQUESTS[name].ID
        ahead = {REQUESTS[n].ID for n in later} - {expect}
        while True:
            try:
                data, headerless = self.read_frame(timeout, expect)
            except (ConnectionClosed, ReplyTimeout) as exc:
                raise type(exc)(self._awaited(name, exc)) from None
            if data[0] in ahead:
                raise BadReply(
                    f"port {self.label}: the reply to {REQUESTS.by_id[data[0]].NAME} came before the reply to "
                    f"{name}, asked before it (replies come in the order asked)",
                    erratum="E-WIRE-008",
                )
            if data[0] != expect:
                self.observer.on_unsolicited(self.label, data)
                continue
            if headerless:
                self.observer.on_deviation(Deviation("E-WIRE-001", 0, f"{name} reply came without the header ff01fe02"))
            telegram, deviations = readings.decode_reply(data, name)
            for dev in deviations:
                self.observer.on_deviation(dev)
            self.observer.on_received(telegram)
            return telegram

    def _awaited(self, name: str, exc: Exception) -> str:
        """What a failed read of the reply to ``name`` saw, naming the port and what was sent (issue 32):
        "port A (127.0.0.1:10000): sent CMD_GET_POSITION, the target closed the connection without a reply"."""
        seen = str(exc).removeprefix(f"port {self.label}: ")
        if isinstance(exc, ConnectionClosed) and "inside" not in seen:
            seen += " without a reply"
        return f"port {self.label} ({self.host}:{self.port}): sent {name}, {seen}"

    def exchange(self, items: Sequence[Telegram | Pause], timeout: float | None = None) -> list[Telegram]:
        """Pipelining (erratum E-WIRE-008): send ``items`` back to back (one write between two pauses), then read
        the replies of the answered ones in the order asked; the replies, in that order."""
        while self._asked:
            self.next_reply(timeout)
        return [self.next_reply(timeout) for _ in range(self.send_pipelined(items))]

    def send_pipelined(self, items: Sequence[Telegram | Pause]) -> int:
        """Send ``items`` back to back (one write between two pauses) without reading; how many replies are due
        (``next_reply`` reads them in order)."""
        batch: list[Telegram] = []
        asked = 0
        for item in items:
            if isinstance(item, Pause):
                self._send_batch(batch)
                batch = []
                time.sleep(item.seconds)
                continue
            batch.append(item)
            if answered(item.NAME):
                self._asked.append(item.NAME)
                asked += 1
        self._send_batch(batch)
        return asked

    def next_reply(self, timeout: float | None = None) -> Telegram:
        """The reply to the first request ``send_pipelined`` sent that is not read yet."""
        name = self._asked.popleft()
        return self._read_reply(name, timeout, list(self._asked))

    def _send_batch(self, batch: list[Telegram]) -> None:
        if len(batch) == 1:
            self.send(batch[0])
        elif batch:
            self.send_many(batch, " + ".join(t.NAME for t in batch))

    def pending(self) -> bool:
        """Whether reply bytes wait to be read (buffered, or on the socket now): a read would not block long."""
        if self._rx:
            return True
        if self.eof or self.sock is None:
            return False
        return bool(select.select([self.sock], [], [], 0)[0])

    def request(self, telegram: Telegram, timeout: float | None = None) -> Telegram:
        self.send(telegram)
        return self.read_reply(telegram.NAME, timeout)

    def silence(self, duration: float) -> bytes:
        """Wait ``duration`` s; return whatever arrived (b"" when the target stayed silent)."""
        deadline = time.monotonic() + duration
        before = len(self._rx)
        with contextlib.suppress(ConnectionClosed):
            while self._fill(deadline):
                pass
        got = bytes(self._rx[before:])
        if got:
            self.log.add(self.label, "rx", got, "unexpected data")
        return got

    def wait_closed(self, within: float) -> bool:
        """True when the target closes the connection within ``within`` s (data meanwhile is kept)."""
        deadline = time.monotonic() + within
        try:
            while True:
                if not self._fill(deadline):
                    return False
        except ConnectionClosed:
            return True


def wait_port_closed(host: str, port: int, within: float) -> bool:
    """True when nothing accepts connections on ``port`` within ``within`` seconds."""
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        try:
            with socket.create_connection((host, port), timeout=0.5):
                pass
        except OSError:
            return True
        time.sleep(0.05)
    return False
