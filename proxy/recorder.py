"""What the proxy does with the bytes after it has forwarded them: decode (tap), show (view), keep (session
file, pcapng). Sans-IO: the network module calls it with ``now``; it never sees a socket.

Rules: one ``Recorder`` per proxy run; the network module reports every connection's opening, each chunk it
forwarded (``c2s`` True: client to target), each half-close and the end. Records go to every sink in the
order they happened on each connection.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

from pltf.proxy.capture import PcapngWriter
from pltf.proxy.session import SessionWriter
from pltf.proxy.tap import CLOSE, OPEN, Record, Tap

Sink = Callable[[Record], None]


@dataclass
class _Conn:
    port: int
    request: Tap
    reply: Tap
    closed: set[bool] = field(default_factory=set)  # the directions that saw their end (c2s True)


class Recorder:
    def __init__(
        self,
        sinks: list[Sink],
        pcapng: PcapngWriter | None = None,
        session: SessionWriter | None = None,
        max_length: int | None = None,
        flushes: list[Callable[[], None]] | None = None,
        closes: list[Callable[[], None]] | None = None,
    ) -> None:
        self.sinks = list(sinks)
        self.flushes = list(flushes or [])  # e.g. the view's output
        self.closes = list(closes or [])  # e.g. the MCAP file's (pltf proxy --mcap), after the last record
        self.pcapng, self.session = pcapng, session
        if session is not None:
            self.sinks.append(session.write)
        self.max_length = max_length
        self._conns: dict[int, _Conn] = {}
        self.counts: Counter[str] = Counter()  # telegrams by name, "malformed", connections

    def _emit(self, records: list[Record]) -> None:
        for rec in records:
            if rec.kind not in (OPEN, CLOSE):
                self.counts[rec.name] += 1
            for sink in self.sinks:
                sink(rec)

    def opened(self, conn: int, now: float, port: int, client: tuple[str, int], target: tuple[str, int]) -> None:
        kw = {} if self.max_length is None else {"max_length": self.max_length}
        self._conns[conn] = _Conn(port, Tap("request", conn, port, **kw), Tap("reply", conn, port, **kw))
        self.counts["connections"] += 1
        if self.pcapng is not None:
            self.pcapng.opened(conn, now, client, target)
        self._emit([Record(now, conn, port, OPEN, detail=f"client {client[0]}:{client[1]}")])

    def data(self, conn: int, now: float, c2s: bool, chunk: bytes) -> None:
        c = self._conns.get(conn)
        if c is None:
            return
        if self.pcapng is not None:
            self.pcapng.data(conn, now, c2s, chunk)
        self._emit((c.request if c2s else c.reply).feed(chunk, now))

    def half_closed(self, conn: int, now: float, c2s: bool) -> None:
        """One side sent its FIN: what it left unfinished is Truncated."""
        c = self._conns.get(conn)
        if c is None or c2s in c.closed:
            return
        c.closed.add(c2s)
        if self.pcapng is not None:
            self.pcapng.fin(conn, now, c2s)
        self._emit((c.request if c2s else c.reply).end(now))

    def closed(self, conn: int, now: float, detail: str, ended_at: float | None = None) -> None:
        """Both sides are gone; ``ended_at``: when the first of them ended it (the close record's time)."""
        c = self._conns.pop(conn, None)
        if c is None:
            return
        for c2s in (True, False):
            if c2s not in c.closed:
                self._emit((c.request if c2s else c.reply).end(now))
        if self.pcapng is not None:
            for c2s in (True, False):
                if c2s not in c.closed:
                    self.pcapng.fin(conn, now, c2s)
            self.pcapng.forget(conn)
        self._emit([Record(ended_at if ended_at is not None else now, conn, c.port, CLOSE, detail=detail)])

    def flush(self) -> None:
        for w in (self.pcapng, self.session):
            if w is not None:
                w.flush()
        for f in self.flushes:
            f()

    def close(self, now: float) -> None:
        for conn in list(self._conns):
            self.closed(conn, now, "the proxy stopped")
        for w in (self.pcapng, self.session):
            if w is not None:
                w.close()
        for f in self.closes:
            f()
        for f in self.flushes:
            f()
