"""The session file: one JSON object per line (header, then frames and connection events as they happened).

Format (version 1):
- line 1, the header: ``{"format": "pltf-session", "version": 1, "started": T, "routes": [{"listen":
  "HOST:PORT", "target": "HOST:PORT"}, ...]}``; the routes in the order of the command line (first port, then
  ``--second``), which is how ``pltf replay`` maps them onto a new target.
- then one line per record: ``time`` (Unix seconds), ``conn`` (connection number), ``port`` (the target's
  port), ``kind`` ("frame", "raw", "open", "close"), and for frames and raw bytes ``direction`` ("request":
  client to target, "reply": target to client), ``hex`` (the bytes as they passed), ``telegram`` (what
  ``pltf decode`` prints for them, or null) and ``error`` ("<codec error class>: reason", when malformed);
  events carry ``detail`` (the client's address; who ended the connection first, and how: "by client (FIN)",
  "by target (reset: ...)", "by proxy (stopped)"); a close's ``time`` is when that first end happened.
- ``hex`` is the truth: a reader decodes it again and ignores ``telegram``, which is there for people and jq.
"""

from __future__ import annotations

import contextlib
import json
import math
import re
from collections.abc import Generator, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from pltf.proxy.tap import CLOSE, FRAME, MEMO_BYTES, MEMO_FRAMES, OPEN, RAW, Record
from pltf.spec import errors
from pltf.spec.codec import FRAME_OVERHEAD, telegram_set
from pltf.spec.jsonio import telegram_to_json

FORMAT, VERSION = "pltf-session", 1
KINDS = (FRAME, RAW, OPEN, CLOSE)


class SessionError(Exception):
    """The session file cannot be read (one line of explanation)."""


@dataclass(frozen=True)
class Route:
    listen: str  # HOST:PORT the proxy listened on
    target: str  # HOST:PORT it forwarded to

    @property
    def target_port(self) -> int:
        return int(self.target.rsplit(":", 1)[1])


@dataclass(frozen=True)
class Session:
    started: float
    routes: tuple[Route, ...]
    records: tuple[Record, ...]

    @property
    def ports(self) -> list[int]:
        """The target ports in route order."""
        return [r.target_port for r in self.routes]


def record_to_json(rec: Record) -> dict[str, Any]:
    out: dict[str, Any] = {"time": round(rec.time, 6), "conn": rec.conn, "port": rec.port, "kind": rec.kind}
    if rec.kind in (OPEN, CLOSE):
        out["detail"] = rec.detail
        return out
    out["direction"] = rec.direction
    out["hex"] = rec.raw.hex()
    out["telegram"] = None if rec.telegram is None else telegram_to_json(rec.telegram)
    if rec.error is not None:
        out["error"] = rec.error
    return out


class SessionWriter:
    """Opens the file at once (so that a bad path fails before anything listens), writes the header when the
    routes are known (``start``) and a line per record; ``flush`` hands the lines to the OS."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._fh: IO[str] = path.open("w", encoding="ascii")
        self.lines = 0
        self._memo: dict[tuple[str, str | None, bytes, str | None, bool], str] = {}

    def start(self, routes: list[Route], started: float) -> None:
        header = {
            "format": FORMAT,
            "version": VERSION,
            "started": round(started, 6),
            "routes": [{"listen": r.listen, "target": r.target} for r in routes],
        }
        self._fh.write(json.dumps(header) + "\n")

    def write(self, rec: Record) -> None:
        self._fh.write(self._line(rec) + "\n")
        self.lines += 1

    def _line(self, rec: Record) -> str:
        """``json.dumps(record_to_json(rec))``; the part after ``kind`` is kept for short frames (a poller's
        identical requests and unchanged replies are turned into JSON once)."""
        if rec.kind in (OPEN, CLOSE) or len(rec.raw) > MEMO_BYTES:
            return json.dumps(record_to_json(rec))
        key = (rec.kind, rec.direction, rec.raw, rec.error, rec.telegram is None)
        tail = self._memo.get(key)
        if tail is None:
            body = record_to_json(rec)
            for name in ("time", "conn", "port", "kind"):
                del body[name]
            tail = json.dumps(body)
            if len(self._memo) >= MEMO_FRAMES:
                self._memo.clear()
            self._memo[key] = tail
        t = round(rec.time, 6)
        stamp = repr(t) if math.isfinite(t) else json.dumps(t)  # what json.dumps writes for a number
        return f'{{"time": {stamp}, "conn": {int(rec.conn)}, "port": {int(rec.port)}, "kind": "{rec.kind}", {tail[1:]}'

    def flush(self) -> None:
        self._fh.flush()

    def close(self) -> None:
        self._fh.close()


# ---------------------------------------------------------------------------------------------- reading


def _decode(direction: Any, raw: bytes) -> Any:
    try:
        return telegram_set(direction).decode_data(raw[FRAME_OVERHEAD:])
    except errors.RemoteProtocolError:
        return None


def _record(obj: Any) -> Record:
    if not isinstance(obj, dict):
        raise ValueError("not a JSON object")
    kind = obj.get("kind")
    if kind not in KINDS:
        raise ValueError(f"kind {kind!r} is not one of {', '.join(KINDS)}")
    time, conn, port = float(obj["time"]), int(obj["conn"]), int(obj["port"])
    if kind in (OPEN, CLOSE):
        return Record(time, conn, port, kind, detail=str(obj.get("detail", "")))
    direction = obj.get("direction")
    if direction not in ("request", "reply"):
        raise ValueError(f"direction {direction!r} is not request or reply")
    raw = bytes.fromhex(obj["hex"])
    error = obj.get("error")
    telegram = _decode(direction, raw) if kind == FRAME and error is None else None
    if kind == FRAME and error is None and telegram is None:
        raise ValueError("a frame without an error mark does not decode")
    return Record(time, conn, port, kind, direction, raw, telegram, None if error is None else str(error))


def _lines(path: Path) -> Generator[tuple[int, str], None, None]:
    try:
        with path.open(encoding="utf-8") as fh:
            yield from enumerate(fh, 1)
    except OSError as exc:
        raise SessionError(f"{path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise SessionError(f"{path}: not a text file") from None


@dataclass(frozen=True)
class SessionFile:
    """A session file read as a stream: its header at once, its records one by one on each ``records()`` (the
    file read again each time, nothing kept: an hour of 20 Hz GET_STATUS with scans is gigabytes)."""

    path: Path
    started: float
    routes: tuple[Route, ...]
    header_line: int = 1

    @property
    def ports(self) -> list[int]:
        """The target ports in route order."""
        return [r.target_port for r in self.routes]

    def records(self) -> Iterator[Record]:
        """The records; SessionError names the first line that is not one."""
        for _, rec in self.records_at():
            yield rec

    def records_at(self, offset: int = 0, conn: int | None = None) -> Iterator[tuple[int, Record]]:
        """The records from byte ``offset`` on (the start of a line), each with the offset of its line; with
        ``conn``, only that connection's (the others' lines skipped unparsed where they have the layout
        SessionWriter writes)."""
        start, n = offset, 0
        try:
            with self.path.open("rb") as fh:
                fh.seek(start)
                for raw in fh:
                    at, offset, n = offset, offset + len(raw), n + 1
                    if (not start and n <= self.header_line) or not raw.strip():
                        continue
                    if conn is not None and (found := _CONN.match(raw)) is not None and int(found[1]) != conn:
                        continue
                    where = str(n) if not start else f"byte {at}"  # line numbers are counted from the start
                    rec = _parse(self.path, where, raw.decode("utf-8"), _record)
                    if conn is None or rec.conn == conn:
                        yield at, rec
        except OSError as exc:
            raise SessionError(f"{self.path}: {exc.strerror or exc}") from None
        except UnicodeDecodeError:
            raise SessionError(f"{self.path}: not a text file") from None


_CONN = re.compile(rb'\{"time": [-0-9.e+a-zA-Z]+, "conn": (\d+),')  # the start of a line SessionWriter wrote


def _parse(path: Path, n: int | str, line: str, make: Any) -> Any:
    try:
        return make(json.loads(line))
    except (ValueError, KeyError, TypeError) as exc:
        what = f"missing {exc}" if isinstance(exc, KeyError) else str(exc)
        raise SessionError(f"{path}:{n}: {what}") from None


def _header(obj: Any) -> dict[str, Any]:
    if not isinstance(obj, dict) or obj.get("format") != FORMAT:
        raise ValueError(f'not a {FORMAT} file (its first line has no "format": "{FORMAT}")')
    if obj.get("version") != VERSION:
        raise ValueError(f"version {obj.get('version')!r}, this pltf reads version {VERSION}")
    return obj


def open_session(path: Path) -> SessionFile:
    """The session file's header (its first line that is not blank); SessionError when it is not one. The
    records are read by ``SessionFile.records``."""
    with contextlib.closing(_lines(path)) as lines:
        first = next(((n, line) for n, line in lines if line.strip()), None)
    if first is None:
        raise SessionError(f"{path}: empty, not a {FORMAT} file")
    header = _parse(path, first[0], first[1], _header)
    try:
        routes = tuple(Route(str(r["listen"]), str(r["target"])) for r in header["routes"])
        _ = [r.target_port for r in routes]
    except (KeyError, TypeError, ValueError, IndexError):
        raise SessionError(
            f"{path}:{first[0]}: the header's routes are not a list of {{listen, target: HOST:PORT}}"
        ) from None
    return SessionFile(path, float(header.get("started", 0.0)), routes, first[0])


def read_session(path: Path) -> Session:
    """The session of ``path``, all in memory; SessionError names the first line that is not one."""
    f = open_session(path)
    return Session(f.started, f.routes, tuple(f.records()))
