"""A recording served to the GUI without a platform: ``pltf gui --session FILE`` (issue 35, time travel).

Rules:
- A session file (proxy/session.py: JSON lines, ``hex`` is the truth) is never sent whole: an hour of 20 Hz
  GET_STATUS with scans is ~1.5 GB. The gateway reads it once at start (``SessionIndex.build``: each frame's
  time, direction, telegram name and byte offset, ~40 bytes a frame kept) and answers two questions from that
  index, reading only the lines the answer needs:
  ``GET /api/recording/state?t=T``: the last reply of each telegram name at or before T (status, position, map,
  roadmap, debug data, CAN messages, parameters, ...): what the panels of a live GUI would show at T; with
  ``&since=S&limit=N`` also the last N frames (both directions) in (S, T] for the wire inspector, in the same
  answer (one round trip a seek: ``{"state": [...], "wire": [...]}``);
  ``GET /api/recording/records?from=A&to=B&limit=N``: the last N frames in (A, B] alone;
  ``GET /api/recording/history?t=T&span=S&points=N``: the plotted replies (PLOTTED: GET_STATUS, GET_POSITION) in
  (T - S, T], at most N of each name spread evenly over them: the plots' window up to a scrubbed time.
  Per name, a sorted array of times and a bisection stand in for keyframes: the same answer as per-second
  keyframes (the last offset of each name), without a second's rounding.
- An MCAP file (``pltf export --mcap``, ``pltf proxy --mcap``) is served as it is, with HTTP range requests
  (``GET /recording.mcap``): the browser reads it with @mcap/core's McapIndexedReader, as Foxglove does. The
  gateway only checks that it is an MCAP file with the raw telegrams' channel (``/pltf/telegrams``).
- ``GET /api/recording`` says which: ``{"kind": "session"|"mcap", "file", "start", "end", "events", "frames"}``
  (an MCAP's times and events are the browser's to read). Events are the requests the application sent that are
  not GETs (guide 6.3: the commands), as ``{"t", "name"}``.
- Nothing is sent anywhere: a gateway serving a recording has no /ws and holds no connection.
- A file that is not a recording: ``RecordingError``, one line naming the file and what is wrong.
"""

from __future__ import annotations

import bisect
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from aiohttp import web

from pltf.proxy.session import SessionError, open_session
from pltf.spec.codec import FRAME_OVERHEAD, telegram_set

MCAP_MAGIC = b"\x89MCAP0\r\n"
TELEGRAMS = "/pltf/telegrams"  # proxy/mcap_export.py: the raw telegrams' channel
RECORDS_LIMIT = 500  # frames one records answer holds at most
PLOTTED = ("CMD_GET_STATUS", "CMD_GET_POSITION")  # the replies panels/plots.ts draws over time
# the start of a line as proxy/session.py's SessionWriter writes a frame: time, kind, direction, the id's byte
_FRAME = re.compile(
    rb'\{"time": ([-0-9.e+]+), "conn": \d+, "port": \d+, "kind": "(frame|raw|open|close)"'
    rb'(?:, "direction": "(request|reply)", "hex": "([0-9a-f]{0,%d}))?' % (2 * FRAME_OVERHEAD + 2)
)


_HEX = re.compile(rb'"hex": "([0-9a-f]*)"')


class RecordingError(Exception):
    """The file is not a recording the GUI can show (one line of explanation)."""


def telegram_name(direction: str, hex_head: str) -> str | None:
    """The telegram's name from its frame's first bytes (the identifier follows the header and the length, guide
    6.2), or None when they are not a frame of a known telegram."""
    if len(hex_head) < 2 * FRAME_OVERHEAD + 2:
        return None
    cls = telegram_set(direction).by_id.get(int(hex_head[2 * FRAME_OVERHEAD : 2 * FRAME_OVERHEAD + 2], 16))  # type: ignore[arg-type]
    return None if cls is None else str(cls.NAME)


def is_command(name: str) -> bool:
    """A request that is an event on the timeline: every one but the GETs (guide 6.3)."""
    return not name.startswith("CMD_GET_")


@dataclass
class _Series:
    times: list[float] = field(default_factory=list)
    offsets: list[int] = field(default_factory=list)


@dataclass
class SessionIndex:
    """Where each frame of a session file is, by telegram name: built once, a line read per answer."""

    path: Path
    start: float = 0.0
    end: float = 0.0
    frames: int = 0
    replies: dict[str, _Series] = field(default_factory=dict)
    times: list[float] = field(default_factory=list)  # every frame, in time order
    offsets: list[int] = field(default_factory=list)
    events: list[tuple[float, str]] = field(default_factory=list)
    _fh: IO[bytes] | None = None

    @classmethod
    def build(cls, path: Path) -> SessionIndex:
        try:
            session = open_session(path)
        except SessionError as exc:
            raise RecordingError(str(exc)) from None
        index = cls(path, start=session.started)
        rows: list[tuple[float, int, str, str]] = []
        with path.open("rb") as fh:
            offset = 0
            for n, raw in enumerate(fh, 1):
                at, offset = offset, offset + len(raw)
                if n > session.header_line and raw.strip():
                    row = _row(path, n, raw)
                    if row is not None:
                        rows.append((row[0], at, row[1], row[2]))
        rows.sort(key=lambda r: r[0])  # a close is written late; frames are in time order already
        for t, at, direction, name in rows:
            index.add(t, at, direction, name)
        if rows:  # the recording's times are its frames' (the header's start is when the proxy started listening)
            index.start, index.end = rows[0][0], rows[-1][0]
        else:
            index.end = index.start
        return index

    def add(self, t: float, offset: int, direction: str, name: str) -> None:
        self.frames += 1
        self.times.append(t)
        self.offsets.append(offset)
        if direction == "reply":
            series = self.replies.setdefault(name, _Series())
            series.times.append(t)
            series.offsets.append(offset)
        elif is_command(name):
            self.events.append((t, name))

    def info(self) -> dict[str, Any]:
        return {
            "kind": "session",
            "file": self.path.name,
            "start": self.start,
            "end": self.end,
            "frames": self.frames,
            "events": [{"t": t, "name": name} for t, name in self.events],
        }

    def state_at(self, t: float) -> list[dict[str, Any]]:
        """The last reply of each name at or before ``t``, oldest first."""
        found = []
        for series in self.replies.values():
            i = bisect.bisect_right(series.times, t) - 1
            if i >= 0:
                found.append(series.offsets[i])
        return sorted((self._frame(at) for at in found), key=lambda f: f["t"])

    def records_in(self, a: float, b: float, limit: int = RECORDS_LIMIT) -> list[dict[str, Any]]:
        """The last ``limit`` frames with a < time <= b, in time order."""
        lo, hi = bisect.bisect_right(self.times, a), bisect.bisect_right(self.times, b)
        return [self._frame(at) for at in self.offsets[max(lo, hi - limit) : hi]]

    def history(self, t: float, span: float, points: int) -> list[dict[str, Any]]:
        """The PLOTTED replies with t - span < time <= t, at most ``points`` of each name (evenly spread, the last
        one always), in time order."""
        found = []
        for name in PLOTTED:
            series = self.replies.get(name)
            if series is not None:
                lo, hi = bisect.bisect_right(series.times, t - span), bisect.bisect_right(series.times, t)
                found += [series.offsets[i] for i in spread(lo, hi, points)]
        return sorted((self._frame(at) for at in found), key=lambda f: f["t"])

    def _frame(self, offset: int) -> dict[str, Any]:
        """The frame of the line at ``offset``: its fields found in SessionWriter's layout (a line is ~10 KB of
        decoded telegram beside the hex: not parsed), else in the JSON."""
        if self._fh is None:
            self._fh = self.path.open("rb")
        self._fh.seek(offset)
        line = self._fh.readline()
        m, h = _FRAME.match(line), _HEX.search(line)
        if m is not None and m[3] is not None and h is not None:
            return {"t": float(m[1]), "dir": m[3].decode(), "hex": h[1].decode()}
        obj = json.loads(line)
        return {"t": float(obj["time"]), "dir": obj["direction"], "hex": obj["hex"]}

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None


def spread(lo: int, hi: int, n: int) -> list[int]:
    """At most ``n`` indices of [lo, hi), evenly spread, ``hi - 1`` among them."""
    count = hi - lo
    if count <= n:
        return list(range(lo, hi))
    return sorted({hi - 1 - (k * (count - 1)) // max(1, n - 1) for k in range(n)})


def _row(path: Path, n: int, raw: bytes) -> tuple[float, str, str] | None:
    """(time, direction, name) of one line, or None for a connection event or marked bytes."""
    m = _FRAME.match(raw)
    if m is not None:
        if m[2] != b"frame":
            return None
        t, direction, head = float(m[1]), m[3].decode(), m[4].decode()
    else:  # another writer's layout: the JSON itself
        try:
            obj = json.loads(raw)
            if obj.get("kind") != "frame":
                return None
            t, direction, head = float(obj["time"]), str(obj["direction"]), str(obj["hex"])
        except (ValueError, KeyError, TypeError, AttributeError):
            raise RecordingError(f"{path}:{n}: not a record of a pltf-session file") from None
    if direction not in ("request", "reply"):
        raise RecordingError(f"{path}:{n}: direction {direction!r} is not request or reply")
    name = telegram_name(direction, head)
    return None if name is None else (t, direction, name)


@dataclass
class McapFile:
    """An MCAP recording: served as bytes; the browser reads it (McapIndexedReader over range requests)."""

    path: Path

    @classmethod
    def check(cls, path: Path) -> McapFile:
        from mcap.exceptions import McapError
        from mcap.reader import make_reader

        try:
            with path.open("rb") as fh:
                summary = make_reader(fh).get_summary()
        except (McapError, ValueError, EOFError, OSError) as exc:  # the reader's words for a cut or garbled file
            raise RecordingError(f"{path}: not a readable MCAP file ({exc or type(exc).__name__})") from None
        if summary is None:
            raise RecordingError(f"{path}: an MCAP file without a summary section (the GUI seeks by its indexes)")
        if not any(c.topic == TELEGRAMS for c in summary.channels.values()):
            raise RecordingError(f"{path}: an MCAP file without the {TELEGRAMS} channel (pltf export --mcap writes it)")
        return cls(path)

    def info(self) -> dict[str, Any]:
        return {"kind": "mcap", "file": self.path.name, "url": "recording.mcap"}

    def close(self) -> None:
        pass


Recording = SessionIndex | McapFile


def open_recording(path: Path) -> Recording:
    """The recording of ``path``: an MCAP file by its magic, else a session file; RecordingError otherwise."""
    try:
        with path.open("rb") as fh:
            head = fh.read(len(MCAP_MAGIC))
    except OSError as exc:
        raise RecordingError(f"{path}: {exc.strerror or exc}") from None
    if head == MCAP_MAGIC:
        return McapFile.check(path)
    if head and not head.lstrip().startswith(b"{"):
        raise RecordingError(f"{path}: neither a pltf-session file (pltf proxy --record) nor an MCAP file")
    return SessionIndex.build(path)


RECORDING = web.AppKey("recording", object)


def _number(request: web.Request, name: str, default: float | None = None) -> float:
    text = request.query.get(name)
    if text is None and default is not None:
        return default
    try:
        return float(text or "")
    except ValueError:
        raise web.HTTPBadRequest(text=f"{name}: expected a time in seconds, got {text!r}") from None


def _session(request: web.Request) -> SessionIndex:
    rec = request.app[RECORDING]
    if not isinstance(rec, SessionIndex):
        raise web.HTTPNotFound(text="an MCAP recording is read by the browser (GET /recording.mcap)")
    return rec


async def info(request: web.Request) -> web.Response:
    rec = request.app[RECORDING]
    assert isinstance(rec, SessionIndex | McapFile)
    return web.json_response(rec.info())


async def state(request: web.Request) -> web.Response:
    rec, t = _session(request), _number(request, "t")
    answer: dict[str, Any] = {"state": rec.state_at(t)}
    if "since" in request.query:
        limit = int(min(RECORDS_LIMIT, max(1, _number(request, "limit", RECORDS_LIMIT))))
        answer["wire"] = rec.records_in(_number(request, "since"), t, limit)
    return web.json_response(answer)


async def records(request: web.Request) -> web.Response:
    limit = int(min(RECORDS_LIMIT, max(1, _number(request, "limit", RECORDS_LIMIT))))
    frames = _session(request).records_in(_number(request, "from"), _number(request, "to"), limit)
    return web.json_response({"frames": frames})


async def history(request: web.Request) -> web.Response:
    points = int(min(RECORDS_LIMIT, max(1, _number(request, "points", RECORDS_LIMIT))))
    frames = _session(request).history(_number(request, "t"), max(0.0, _number(request, "span")), points)
    return web.json_response({"frames": frames})


async def mcap(request: web.Request) -> web.StreamResponse:
    rec = request.app[RECORDING]
    if not isinstance(rec, McapFile):
        raise web.HTTPNotFound(text="the recording is a session file (GET /api/recording/state)")
    return web.FileResponse(rec.path)  # answers Range requests (206) as McapIndexedReader asks


async def _close(app: web.Application) -> None:
    rec = app[RECORDING]
    assert isinstance(rec, SessionIndex | McapFile)
    rec.close()


def add_routes(app: web.Application, recording: Recording) -> None:
    app[RECORDING] = recording
    app.router.add_get("/api/recording", info)
    app.router.add_get("/api/recording/state", state)
    app.router.add_get("/api/recording/records", records)
    app.router.add_get("/api/recording/history", history)
    app.router.add_get("/recording.mcap", mcap)
    app.on_cleanup.append(_close)
