"""Was anything lost on the way into the recording? A streaming check of a session file of any size.

Rules (one pass, constant memory per connection, so an hour's recording of gigabytes is fine):
- Every frame decodes again from its ``hex`` (``pltf.spec.codec.decode_frame``) to the telegram the line names;
  a frame the proxy marked malformed, raw bytes, or a line that does not parse is counted as a problem.
- Per connection: an ``open`` and a ``close``; the answered requests (GET_*: the spec's ``answered``) and the
  replies. A reply with no request before it is a problem (a lost request); a request without its reply is
  counted per port and close detail (the reference server turning a newcomer away closes it unanswered, guide
  6.1: expected, and the reconnecting client counts those itself).
"""

from __future__ import annotations

import collections
import json
from dataclasses import dataclass, field
from pathlib import Path

from pltf.spec import errors
from pltf.spec.codec import REQUESTS, decode_frame
from pltf.spec.model import Direction


@dataclass
class _Conn:
    port: int
    owed: int = 0  # answered requests not replied to yet
    replies: int = 0
    opened: bool = False
    closed: str = ""


@dataclass
class Integrity:
    frames: int = 0
    problems: list[str] = field(default_factory=list)
    connections: collections.Counter[int] = field(default_factory=collections.Counter)  # per port
    unanswered: collections.Counter[tuple[int, str]] = field(default_factory=collections.Counter)  # (port, close)
    answered_connections: collections.Counter[int] = field(default_factory=collections.Counter)  # per port, >=1 reply

    @property
    def clean(self) -> bool:
        return not self.problems

    def summary(self) -> str:
        ports = ", ".join(
            f"port {p}: {n} connections ({self.answered_connections[p]} with replies)"
            for p, n in sorted(self.connections.items())
        )
        owed = "; ".join(f"{n} on port {p} closed {how}" for (p, how), n in sorted(self.unanswered.items())) or "none"
        problems = "none" if self.clean else f"{len(self.problems)}, the first: {'; '.join(self.problems[:3])}"
        return f"{self.frames:,} frames; {ports}; requests left unanswered: {owed}; problems: {problems}"


ANSWERED = {t.ID for t in REQUESTS if t.DEF.answered}


def check(path: Path) -> Integrity:
    out = Integrity()
    conns: dict[int, _Conn] = {}
    with path.open(encoding="utf-8") as fh:
        next(fh, None)  # the header
        for n, line in enumerate(fh, 2):
            if line.strip():
                _line(n, line, conns, out)
    for number, c in conns.items():
        if not c.opened or not c.closed:
            out.problems.append(f"connection {number}: {'no open' if not c.opened else 'no close'}")
        if c.owed:
            out.unanswered[(c.port, c.closed.split(" (")[0] or "never")] += c.owed
    return out


def _line(n: int, line: str, conns: dict[int, _Conn], out: Integrity) -> None:
    try:
        rec = json.loads(line)
        kind, conn = rec["kind"], conns.setdefault(int(rec["conn"]), _Conn(int(rec["port"])))
    except (ValueError, KeyError, TypeError) as exc:
        out.problems.append(f"line {n}: {exc}")
        return
    if kind == "open":
        conn.opened = True
        out.connections[conn.port] += 1
    elif kind == "close":
        conn.closed = str(rec.get("detail", "?"))
    elif kind != "frame" or rec.get("error"):
        out.problems.append(f"line {n}: {kind} {rec.get('error') or ''}".strip())
    else:
        _frame(n, rec, conn, out)


def _frame(n: int, rec: dict[str, object], conn: _Conn, out: Integrity) -> None:
    out.frames += 1
    direction: Direction = "reply" if rec.get("direction") == "reply" else "request"
    try:
        telegram = decode_frame(bytes.fromhex(str(rec["hex"])), direction)
    except (errors.RemoteProtocolError, ValueError) as exc:
        out.problems.append(f"line {n}: does not decode again: {exc}")
        return
    named = rec.get("telegram")
    if isinstance(named, dict) and named.get("telegram") != telegram.NAME:
        out.problems.append(f"line {n}: names {named.get('telegram')}, the bytes are {telegram.NAME}")
    if direction == "request":
        conn.owed += telegram.ID in ANSWERED
    elif conn.owed == 0:
        out.problems.append(f"line {n}: a {telegram.NAME} reply on connection {rec.get('conn')} with no request owed")
    else:
        conn.owed -= 1
        if conn.replies == 0:
            out.answered_connections[conn.port] += 1
        conn.replies += 1
