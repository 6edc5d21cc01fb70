"""A pltf proxy recording as MCAP (issue 35): for Foxglove, Lichtblick and the ROS 2 tools.

Sans-IO apart from the files it is given: records in (proxy/tap.py), MCAP out through mcap_writer.py (the ``mcap``
library's writer: chunked, with a summary section and its indexes; each chunk compressed with lz4 by default, or
zstd, or not at all: ``--compression``). Used by ``pltf export
SESSION --mcap OUT`` (a session file read line by line, put in time order) and, live, by ``pltf proxy --mcap
OUT`` (a sink of the recorder).

Channels (topic: schema, from what):
- ``/pltf/telegrams``: pltf.Telegram, every frame and every run of marked bytes, both directions, with its
  connection, port, direction and bytes (hex): the recording itself, nothing dropped.
- ``/pltf/wire``: foxglove.Log, one line per telegram as ``pltf proxy`` shows it (decoded, enums by name), and per
  connection event; malformed bytes at level WARNING.
- ``/pose``: foxglove.PoseInFrame and ``/tf``: foxglove.FrameTransform (map -> base_link), from each
  CMD_GET_POSITION reply (guide 6.4: x, y mm, angle rad).
- ``/scan``: foxglove.LaserScan in protobuf (mcap_proto.py: packed doubles, not 541 floats as JSON text), from the
  ``scan`` of each CMD_GET_STATUS reply (guide 6.4: points x, y in mm in the platform's frame, base_link).
  LaserScan holds ranges at equally spaced bearings, the protocol sends points: each point goes into the 0.5
  degree bin of its bearing seen from the platform's origin (the nearest point wins a bin; a bin without a point
  has range 0, Foxglove draws it at the origin), from the first point's bin to the last's. A point is off by at
  most 0.25 degrees of bearing; its range is rounded to the mm.
- ``/map``: foxglove.SceneUpdate, from CMD_GET_MAP replies (entity ``map``: the lines of every layer, guide 6.5)
  and CMD_GET_ROADMAP replies (entity ``roadmap``: each station's name and heading), documents parsed and
  validated with pltf.spec.documents; a document that does not validate is a WARNING line on ``/pltf/wire``.

Every other channel is JSON (its schema a JSON schema, mcap_schemas.py). ``pltf export`` reads the session with
mcap_read.py (``read_entries``: the ``telegram`` members of the lines skipped, a status's scan as numpy columns);
a short frame's messages are made once and reused with new times (a poller's requests and unchanged replies).

Times: a message's log time and publish time are the record's time (ns). Within a channel log times never go
back: a record earlier than the channel's last message (a close, written when both sides are done, with the
time of the first end; live, or more than REORDER_S late in a session file) is logged at the channel's last
time; its publish time keeps the recorded one.
"""

from __future__ import annotations

import binascii
import contextlib
import heapq
import json
import math
import os
import tempfile
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import IO, Any, TypeVar

import numpy as np

from pltf.proxy import mcap_proto
from pltf.proxy.mcap_read import Entry, entry_of, read_entries
from pltf.proxy.mcap_schemas import schema_bytes, schema_encoding
from pltf.proxy.mcap_wire import fields_text
from pltf.proxy.mcap_writer import CHUNK_BYTES, COMPRESSIONS, McapWriter
from pltf.proxy.session import FORMAT, VERSION, SessionError, _lines, _record
from pltf.proxy.tap import CLOSE, MEMO_BYTES, MEMO_FRAMES, OPEN, Record
from pltf.proxy.view import ARROW, format_record
from pltf.spec.documents import DocumentError, DocumentKind, validate_document

NS = 1_000_000_000
_json_string: Callable[[str], str] = json.encoder.encode_basestring_ascii  # json.dumps' own string escaping
MM = 1000  # mm per metre, Foxglove's unit (division: the nearest float to the exact value)
SCAN_STEP = math.radians(0.5)
REORDER_S = 10.0  # how late a record may come and still be put in its place (in_time_order)
INFO, WARNING = 2, 3  # foxglove.LogLevel
MAP_FRAME, PLATFORM_FRAME = "map", "base_link"
CHANNELS = {  # topic: schema
    "/pltf/telegrams": "pltf.Telegram",
    "/pltf/wire": "foxglove.Log",
    "/pose": "foxglove.PoseInFrame",
    "/tf": "foxglove.FrameTransform",
    "/scan": "foxglove.LaserScan",
    "/map": "foxglove.SceneUpdate",
}
PROTOBUF = ("/scan",)  # channels whose messages are protobuf (mcap_proto.py); the others JSON
UNSTAMPED = ("/map",)  # foxglove.SceneUpdate has no timestamp of its own (its entities have)
DEFAULT_COMPRESSION = "lz4"  # within the hour's 10 s with the mcap library's writer; zstd: 0.58x the size (mcap.md)
COMPRESSION_NAMES = tuple(COMPRESSIONS)
Message = tuple[str, bytes]  # (topic, the message after its timestamp: see ``encode``)
Ordered = TypeVar("Ordered", Record, Entry, Record | Entry)


def stamp(t: float) -> dict[str, int]:
    ns = max(0, round(t * NS))
    return {"sec": ns // NS, "nsec": ns % NS}


def _vector(x: float = 0.0, y: float = 0.0) -> dict[str, float]:
    return {"x": x, "y": y, "z": 0.0}


def quaternion(angle: float) -> dict[str, float]:
    """A rotation by ``angle`` (rad) about z."""
    return {"x": 0.0, "y": 0.0, "z": math.sin(angle / 2), "w": math.cos(angle / 2)}


def _pose(x: float = 0.0, y: float = 0.0, angle: float = 0.0) -> dict[str, Any]:
    return {"position": _vector(x, y), "orientation": quaternion(angle)}


def _tail(message: dict[str, Any]) -> bytes:
    """The JSON of a message without its timestamp, after the opening brace (``encode`` puts the stamp first)."""
    return json.dumps(message, separators=(",", ":"), allow_nan=False)[1:].encode()


def encode(topic: str, ns: int, tail: bytes) -> bytes:
    """A message of ``topic`` stamped ``ns``: JSON ``{"timestamp":{"sec":S,"nsec":N},`` + tail, or protobuf (field
    1, google.protobuf.Timestamp, then tail); a /map message is whole already."""
    if topic in PROTOBUF:
        return mcap_proto.stamped(ns, tail)
    if topic in UNSTAMPED:
        return tail
    sec, nsec = divmod(ns, NS)
    return b'{"timestamp":{"sec":%d,"nsec":%d},%s' % (sec, nsec, tail)


# ------------------------------------------------------------------------------------- telegram -> messages


def _position(e: Entry, t: Any) -> list[Message]:
    # guide 6.4 CMD_GET_POSITION: x, y [mm] (erratum E-REP-012), angle [rad]
    pose = {"frame_id": MAP_FRAME, "pose": _pose(t.x / MM, t.y / MM, t.angle)}
    tf = {
        "parent_frame_id": MAP_FRAME,
        "child_frame_id": PLATFORM_FRAME,
        "translation": _vector(t.x / MM, t.y / MM),
        "rotation": quaternion(t.angle),
    }
    return [("/pose", _tail(pose)), ("/tf", _tail(tf))]


def scan_ranges(x: np.ndarray, y: np.ndarray) -> tuple[float, float, np.ndarray]:
    """(start_angle, end_angle, ranges in m to the mm) of scan points (x, y in mm), binned by bearing (SCAN_STEP)."""
    x, y = x.astype(float), y.astype(float)
    ranges = np.hypot(x, y) / MM
    bins = np.rint(np.arctan2(y, x) / SCAN_STEP).astype(np.intp)
    lo, hi = int(bins.min()), int(bins.max())
    at = bins - lo
    out = np.zeros(hi - lo + 1)
    if np.bincount(at).max() > 1:  # points share a bin: the nearest wins (farthest written first, nearest last)
        order = np.argsort(-ranges, kind="stable")
        at, ranges = at[order], ranges[order]
    out[at] = ranges
    return lo * SCAN_STEP, hi * SCAN_STEP, out.round(3)


def _scan_points(e: Entry, t: Any) -> tuple[np.ndarray, np.ndarray]:
    for c in e.columns:
        if c.name == "scan":
            return c.items["x"], c.items["y"]
    xy = np.array(t.scan, dtype=float).reshape(-1, 2)
    return xy[:, 0], xy[:, 1]


def _status(e: Entry, t: Any) -> list[Message]:
    # guide 6.4 CMD_GET_STATUS: "Observed scan (platform coordinates)", points x, y [mm]
    x, y = _scan_points(e, t)
    if not len(x):
        return []
    start, end, ranges = scan_ranges(x, y)
    return [("/scan", mcap_proto.laser_scan_tail(PLATFORM_FRAME, start, end, ranges.astype("<f8").tobytes()))]


def _entity(e: Entry, ident: str, lines: list[dict[str, Any]], texts: list[dict[str, Any]]) -> dict[str, Any]:
    return {
        "deletions": [],
        "entities": [
            {
                "timestamp": stamp(e.time),
                "frame_id": MAP_FRAME,
                "id": ident,
                "lifetime": {"sec": 0, "nsec": 0},
                "frame_locked": False,
                "metadata": [],
                **{k: [] for k in ("arrows", "cubes", "spheres", "cylinders", "triangles", "models")},
                "lines": lines,
                "texts": texts,
            }
        ],
    }


def _line_list(points: list[dict[str, float]], color: tuple[float, ...], thickness: float) -> dict[str, Any]:
    r, g, b = color
    return {
        "type": 2,  # LINE_LIST: each pair of points is a segment
        "pose": _pose(),
        "thickness": thickness,
        "scale_invariant": True,
        "points": points,
        "color": {"r": r, "g": g, "b": b, "a": 1.0},
        "colors": [],
        "indices": [],
    }


def _xy(el: Any) -> dict[str, float]:
    return _vector(float(el.get("x")) / MM, float(el.get("y")) / MM)


def map_scene(rec: Entry, xml: bytes) -> dict[str, Any]:
    """guide 6.5 map: <layer><line><point x y/><point x y/></line>...; the lines of every layer."""
    tree = validate_document(DocumentKind.MAP, xml)
    points = [_xy(p) for line in tree.iter("line") for p in line.findall("point")[:2]]
    return _entity(rec, "map", [_line_list(points, (0.2, 0.2, 0.2), 2.0)] if points else [], [])


def roadmap_scene(rec: Entry, xml: bytes) -> dict[str, Any]:
    """guide 6.5 roadmap: <station name angle><point x y/></station>; angle in degrees (erratum E-XML-007)."""
    tree = validate_document(DocumentKind.ROADMAP, xml)
    texts, heads = [], []
    for st in tree.iter("station"):
        pos, angle = _xy(st.find("point")), math.radians(float(st.get("angle", "0")))
        texts.append(
            {
                "pose": {"position": pos, "orientation": quaternion(0.0)},
                "billboard": True,
                "font_size": 12.0,
                "scale_invariant": True,
                "color": {"r": 0.1, "g": 0.3, "b": 0.8, "a": 1.0},
                "text": str(st.get("name", st.get("id", ""))),
            }
        )
        tip = _vector(pos["x"] + 0.5 * math.cos(angle), pos["y"] + 0.5 * math.sin(angle))
        heads += [pos, tip]
    return _entity(rec, "roadmap", [_line_list(heads, (0.1, 0.3, 0.8), 3.0)] if heads else [], texts)


def _document(scene: Callable[[Entry, bytes], dict[str, Any]]) -> Callable[[Entry, Any], list[Message]]:
    def convert(e: Entry, t: Any) -> list[Message]:
        try:
            whole = json.dumps(scene(e, t.xml.encode("utf-8")), separators=(",", ":"), allow_nan=False)
            return [("/map", whole.encode())]
        except (DocumentError, TypeError, ValueError) as exc:
            return [("/pltf/wire", _log(e, WARNING, f"{t.NAME} reply: the document is not shown: {exc}"))]

    return convert


REPLY_MESSAGES: dict[str, Callable[[Entry, Any], list[Message]]] = {  # telegram name: its messages
    "CMD_GET_POSITION": _position,
    "CMD_GET_STATUS": _status,
    "CMD_GET_MAP": _document(map_scene),
    "CMD_GET_ROADMAP": _document(roadmap_scene),
}


def _log(e: Entry, level: int, message: str) -> bytes:
    """foxglove.Log after its timestamp: the message is the one string that needs JSON's escaping."""
    text = _json_string(message).encode()
    return b'"level":%d,"message":%s,"name":"port %d","file":"","line":0}' % (level, text, e.port)


def _as_record(e: Entry) -> Record:
    return Record(e.time, e.conn, e.port, e.kind, e.direction, e.raw, e.telegram, e.error, e.detail)


def wire_line(rec: Record | Entry) -> str:
    """The line ``pltf proxy`` shows for the record, without its clock, its words written by mcap_wire.py's
    compiled formatter (a long group cut to the items the view shows; an entry's columns are cut already)."""
    e = entry_of(rec) if isinstance(rec, Record) else rec
    if e.telegram is None:
        return format_record(_as_record(e), t0=e.time)[1].lstrip().split(" ", 1)[1]
    words = fields_text(e.telegram, {c.name: len(c.items) for c in e.columns})
    return f"#{e.conn:<3} :{e.port:<5} {ARROW[e.direction or 'request']} {e.telegram.NAME} {words}".rstrip()


def telegram_message(e: Entry) -> bytes:
    """pltf.Telegram: conn, port, direction, kind, name, hex, error (the hex written in as it is: it needs no
    escaping, and json.dumps of 5 KB of it cost more than the rest of the message)."""
    strings = (_json_string(v) if v is not None else "null" for v in (e.direction, e.kind, _name(e), e.error))
    direction, kind, name, error = (v.encode() for v in strings)
    return b'"conn":%d,"port":%d,"direction":%s,"kind":%s,"name":%s,"hex":"%s","error":%s}' % (
        e.conn,
        e.port,
        direction,
        kind,
        name,
        binascii.hexlify(e.raw),
        error,
    )


def _name(e: Entry) -> str:
    if e.telegram is not None:
        return e.telegram.NAME
    return e.kind if e.kind in (OPEN, CLOSE) else "malformed"


def messages(e: Entry) -> list[Message]:
    """The MCAP messages of one record, each after its timestamp (``encode``)."""
    line = wire_line(e)
    if e.kind in (OPEN, CLOSE):
        return [("/pltf/wire", _log(e, INFO, line))]
    out: list[Message] = [
        ("/pltf/telegrams", telegram_message(e)),
        ("/pltf/wire", _log(e, INFO if e.error is None else WARNING, line)),
    ]
    t = e.telegram
    if t is not None and e.direction == "reply" and t.NAME in REPLY_MESSAGES:
        out += REPLY_MESSAGES[t.NAME](e, t)
    return out


# --------------------------------------------------------------------------------------------- the writer


class _Channel:
    """A channel's state in McapSink: its id, its last log time, its last sequence number (= its messages)."""

    __slots__ = ("ident", "json", "last", "sequence")

    def __init__(self, ident: int, topic: str) -> None:
        self.ident, self.json, self.last, self.sequence = ident, topic not in PROTOBUF + UNSTAMPED, 0, 0


class McapSink:
    """Writes records as MCAP to ``stream`` (binary, seekable or not); ``write`` is a recorder sink, ``write_entry``
    takes the entries of ``read_entries``; ``finish`` writes the summary section and the footer (the stream stays
    open). A short frame's messages are made once (the last MEMO_FRAMES kept) and only stamped again.
    ``compression``: zstd, lz4 or none (mcap_writer.COMPRESSIONS)."""

    def __init__(self, stream: IO[bytes], library: str = "pltf", compression: str = DEFAULT_COMPRESSION) -> None:
        self._writer = McapWriter(stream, compression, CHUNK_BYTES)
        self._writer.start(profile="", library=library)
        schema_ids: dict[str, int] = {}
        self._channels: dict[str, _Channel] = {}
        for topic, schema in CHANNELS.items():
            encoding = schema_encoding(schema)
            if schema not in schema_ids:
                schema_ids[schema] = self._writer.register_schema(schema, encoding, schema_bytes(schema))
            message_encoding = "protobuf" if topic in PROTOBUF else "json"
            ident = self._writer.register_channel(topic, message_encoding, schema_ids[schema])
            self._channels[topic] = _Channel(ident, topic)
        self._memo: dict[tuple[Any, ...], list[Message]] = {}

    @property
    def counts(self) -> dict[str, int]:
        """Messages written per topic."""
        return {topic: ch.sequence for topic, ch in self._channels.items()}

    def write(self, rec: Record) -> None:
        self.write_entry(entry_of(rec))

    def _messages(self, e: Entry) -> list[Message]:
        if e.kind in (OPEN, CLOSE) or len(e.raw) > MEMO_BYTES:
            return messages(e)
        key = (e.conn, e.port, e.kind, e.direction, e.raw, e.error)
        found = self._memo.get(key)
        if found is None:
            found = messages(e)
            if any(topic in UNSTAMPED for topic, _ in found):
                return found  # a scene's entities carry the time: made again each time
            if len(self._memo) >= MEMO_FRAMES:
                self._memo.clear()
            self._memo[key] = found
        return found

    def write_entry(self, e: Entry) -> None:
        publish = max(0, round(e.time * NS))
        head = b'{"timestamp":{"sec":%d,"nsec":%d},' % divmod(publish, NS)  # encode's JSON stamp, made once
        add = self._writer.add
        for topic, tail in self._messages(e):
            ch = self._channels[topic]
            log_time = publish if publish > ch.last else ch.last  # never back within a channel
            ch.last = log_time
            ch.sequence += 1
            add(ch.ident, log_time, head + tail if ch.json else encode(topic, publish, tail), publish, ch.sequence)

    def finish(self) -> None:
        self._writer.finish()


class McapFile:
    """An MCAP file written atomically: into a temporary file beside ``path``, renamed over it by ``close``
    (a reader never sees half a file; ``abort`` removes the temporary file). OSError when it cannot be made."""

    def __init__(self, path: Path, library: str = "pltf", compression: str = DEFAULT_COMPRESSION) -> None:
        self.path = path
        fd, self._tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        self._fh = os.fdopen(fd, "wb", buffering=1 << 20)
        self.sink = McapSink(self._fh, library, compression)

    def write(self, rec: Record) -> None:
        self.sink.write(rec)

    def write_entry(self, e: Entry) -> None:
        self.sink.write_entry(e)

    def close(self) -> None:
        try:
            self.sink.finish()
            self._fh.close()
            os.replace(self._tmp, self.path)
        except BaseException:
            self.abort()
            raise

    def abort(self) -> None:
        self._fh.close()
        with contextlib.suppress(OSError):
            os.unlink(self._tmp)


def read_records(path: Path) -> Iterator[Record]:
    """The records of a session file one by one, as ``read_session`` reads them (its header check, its line
    parser and its one-line errors, SessionError), without holding the session in memory: an hour of 20 Hz
    GET_STATUS with scans is about 5 GB as decoded records."""
    header = False
    for n, line in _lines(path):
        if not line.strip():
            continue
        try:
            obj = json.loads(line)
            if header:
                yield _record(obj)
                continue
            if not isinstance(obj, dict) or obj.get("format") != FORMAT:
                raise ValueError(f'not a {FORMAT} file (its first line has no "format": "{FORMAT}")')
            if obj.get("version") != VERSION:
                raise ValueError(f"version {obj.get('version')!r}, this pltf reads version {VERSION}")
            header = True
        except (ValueError, KeyError, TypeError) as exc:
            what = f"missing {exc}" if isinstance(exc, KeyError) else str(exc)
            raise SessionError(f"{path}:{n}: {what}") from None
    if not header:
        raise SessionError(f"{path}: empty, not a {FORMAT} file")


def in_time_order(records: Iterable[Ordered], window: float = REORDER_S) -> Iterator[Ordered]:
    """``records`` sorted by time, holding back only those of the last ``window`` seconds: a session is in
    order within a connection, and a close (written when both sides are done, with the time of the first end)
    comes at most seconds late. Records of one time keep their order; one later than the window is passed on
    as it comes (McapSink keeps its channel's log times monotonic)."""
    held: list[tuple[float, int, Ordered]] = []
    for seq, rec in enumerate(records):
        heapq.heappush(held, (rec.time, seq, rec))
        while held and held[0][0] < rec.time - window:
            yield heapq.heappop(held)[2]
    while held:
        yield heapq.heappop(held)[2]


def export(
    records: Iterable[Record | Entry], path: Path, library: str = "pltf", compression: str = DEFAULT_COMPRESSION
) -> dict[str, int]:
    """Write ``records`` (``read_records``' or, faster, ``read_entries``') to ``path`` as MCAP in time order
    (``in_time_order``); the message count of each channel. On any error (SessionError of a record read lazily,
    OSError) nothing is left at ``path``."""
    out = McapFile(path, library, compression)
    try:
        for rec in in_time_order(records):
            out.write_entry(entry_of(rec) if isinstance(rec, Record) else rec)
    except BaseException:
        out.abort()
        raise
    out.close()
    return out.sink.counts


def export_session(
    session: Path, path: Path, library: str = "pltf", compression: str = DEFAULT_COMPRESSION
) -> dict[str, int]:
    """``pltf export SESSION --mcap PATH``: the session file read by ``read_entries``, written by ``export``."""
    return export(read_entries(session), path, library, compression)
