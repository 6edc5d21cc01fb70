"""A session file read for the MCAP export (issue 35): what ``read_records`` reads, at a fraction of its cost.

An hour of 20 Hz GET_STATUS is 1.5 GB of JSON lines; ``read_records`` parses every line whole (~100 us for a
status's line: the ``telegram`` member alone is 15 KB of JSON that no reader uses, session.py: "``hex`` is the
truth") and decodes every telegram whole (~90 us: a namedtuple per scan point). Here:

- A frame line of the layout ``SessionWriter`` writes (``{"time": T, "conn": C, "port": P, "kind": "frame",
  "direction": D, "hex": "...", "telegram": {...}}``) is read by its prefix and its ``hex``; the ``telegram``
  member is skipped unparsed, as the format says a reader does. Its object must close the line (``}}``): a
  marked frame's ``"error": "..."`` after it ends the line with ``"}`` and sends the line the slow way. (A
  search for ``"error"`` in the 15 KB of JSON cost 20 us a line.) Every other line (connection
  events, marked bytes, anything written by another hand) is parsed whole as ``read_records`` parses it.
- A short frame is decoded once (the last ``MEMO_FRAMES`` kept, as the proxy's tap does); a long one with its
  plain groups cut to the items the view shows and read as numpy columns (mcap_columns.py), the rest decoded
  and checked by the codec.

The entries carry what ``read_records``' records carry (the same times, connections, ports, kinds, directions,
bytes, errors and details: tested), and SessionError with ``path:line`` for the same bad lines, except that a
``telegram`` member of a frame line is not checked to be JSON (nothing reads it).
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pltf.proxy.mcap_columns import Column, split
from pltf.proxy.session import FORMAT, VERSION, SessionError, _decode, _record
from pltf.proxy.tap import FRAME, MEMO_BYTES, MEMO_FRAMES, Record
from pltf.proxy.view import ITEMS_SHOWN
from pltf.spec.codec import FRAME_OVERHEAD
from pltf.spec.model import Direction
from pltf.spec.telegram import Telegram


@dataclass(frozen=True, slots=True)
class Entry:
    """A record of the session as the export needs it: ``telegram`` whole, or (``columns`` not empty) with those
    groups cut to their first ITEMS_SHOWN items and given whole as columns."""

    time: float
    conn: int
    port: int
    kind: str
    direction: Direction | None = None
    raw: bytes = b""
    telegram: Telegram | None = None
    error: str | None = None
    detail: str = ""
    columns: tuple[Column, ...] = ()


def entry_of(rec: Record) -> Entry:
    """The entry of a record decoded already (the live sink): its telegram whole, its plain groups as columns."""
    decoded = rec.telegram is not None
    cut = split(rec.direction, rec.raw[FRAME_OVERHEAD:], ITEMS_SHOWN) if decoded and rec.direction else None
    columns = tuple(cut[1]) if cut is not None else ()
    return Entry(
        rec.time, rec.conn, rec.port, rec.kind, rec.direction, rec.raw, rec.telegram, rec.error, rec.detail, columns
    )


_NUMBER = rb"-?(?:0|[1-9][0-9]*)(?:\.[0-9]+)?(?:[eE][-+]?[0-9]+)?"
_INT = rb"(?:0|[1-9][0-9]*)"
_FRAME_LINE = re.compile(
    rb'\{"time": (' + _NUMBER + rb'), "conn": (' + _INT + rb'), "port": (' + _INT + rb'), "kind": "frame", '
    rb'"direction": "(request|reply)", "hex": "'
)
_TELEGRAM = b'", "telegram": {'


class _Decoder:
    """Frames to (telegram, columns); short frames memoized; None when the frame does not decode."""

    def __init__(self) -> None:
        self._memo: dict[tuple[str, bytes], tuple[Telegram, tuple[Column, ...]] | None] = {}

    def decode(self, direction: Direction, raw: bytes) -> tuple[Telegram, tuple[Column, ...]] | None:
        if len(raw) > MEMO_BYTES:
            return self._long(direction, raw)
        key = (direction, raw)
        if key not in self._memo:
            if len(self._memo) >= MEMO_FRAMES:
                self._memo.clear()
            t = _decode(direction, raw)
            self._memo[key] = None if t is None else (t, ())
        return self._memo[key]

    @staticmethod
    def _long(direction: Direction, raw: bytes) -> tuple[Telegram, tuple[Column, ...]] | None:
        cut = split(direction, raw[FRAME_OVERHEAD:], ITEMS_SHOWN)
        if cut is None:
            t = _decode(direction, raw)
            return None if t is None else (t, ())
        short = _decode(direction, raw[:FRAME_OVERHEAD] + cut[0])  # the header's length is not read again
        return None if short is None else (short, tuple(cut[1]))


def _fast(buf: Any, start: int, stop: int, decoder: _Decoder) -> Entry | None:
    """The entry of the frame line ``buf[start:stop]`` (its newline excluded) as SessionWriter writes it, or None
    (then the line is parsed whole). Nothing but the hex is copied out of ``buf``."""
    m = _FRAME_LINE.match(buf, start, stop)
    if m is None:
        return None
    end = buf.find(_TELEGRAM, m.end(), stop)
    if end < 0 or buf[stop - 2 : stop] != b"}}":  # the telegram object closes the line: no error member after it
        return None
    try:
        raw = bytes.fromhex(buf[m.end() : end].decode("ascii"))
    except ValueError:  # UnicodeDecodeError is one
        return None
    direction: Direction = "request" if m[4] == b"request" else "reply"
    decoded = decoder.decode(direction, raw)
    if decoded is None:
        raise ValueError("a frame without an error mark does not decode")
    return Entry(float(m[1]), int(m[2]), int(m[3]), FRAME, direction, raw, decoded[0], None, "", decoded[1])


def _slow(line: bytes, decoder: _Decoder) -> Entry:
    rec = _record(json.loads(line))  # read_records' own parser (it decodes the telegram whole)
    decoded = decoder.decode(rec.direction, rec.raw) if rec.kind == FRAME and rec.direction is not None else None
    t, columns = (rec.telegram, ()) if rec.telegram is None or decoded is None else decoded
    return Entry(rec.time, rec.conn, rec.port, rec.kind, rec.direction, rec.raw, t, rec.error, rec.detail, columns)


def _header(obj: Any) -> None:
    if not isinstance(obj, dict) or obj.get("format") != FORMAT:
        raise ValueError(f'not a {FORMAT} file (its first line has no "format": "{FORMAT}")')
    if obj.get("version") != VERSION:
        raise ValueError(f"version {obj.get('version')!r}, this pltf reads version {VERSION}")


BLOCK = 4 * 1024 * 1024  # bytes read at once


def _lines(fh: Any) -> Iterator[tuple[int, bytearray, int, int, bytes]]:
    """(line number, buffer, start, stop, newline) of each line of the binary file ``fh``: ``buf[start:stop]``
    without its line end (\\n, \\r\\n), ``newline`` b"\\n" when it had one (as text mode reads it). Read in
    blocks into one buffer (a line longer than a block grows it); a line's bytes are never copied on their own.
    The buffer is valid until the next line is asked for."""
    buf, have, n = bytearray(BLOCK), 0, 0
    while True:
        with memoryview(buf) as view:
            got = fh.readinto(view[have:])
        if not got:
            if have:
                yield n + 1, buf, 0, have - 1 if buf[have - 1] == 13 else have, b""
            return
        have += got
        pos = 0
        while (nl := buf.find(b"\n", pos, have)) >= 0:
            n += 1
            yield n, buf, pos, nl - 1 if nl > pos and buf[nl - 1] == 13 else nl, b"\n"
            pos = nl + 1
        buf[: have - pos] = buf[pos:have]
        have -= pos
        if have == len(buf):
            buf.extend(bytes(len(buf)))


def read_entries(path: Path) -> Iterator[Entry]:
    """The entries of a session file one by one (nothing kept), with ``read_records``' checks and one-line
    errors (SessionError ``path:line: ...``). A line's 15 KB of telegram JSON is never copied (``_lines``)."""
    decoder, header, n = _Decoder(), False, 0
    try:
        with path.open("rb") as fh:
            for n, buf, start, stop, newline in _lines(fh):  # noqa: B007  (n names the line of an error)
                if buf[start : start + 1] != b"{" and not buf[start:stop].strip():
                    continue
                if header and (entry := _fast(buf, start, stop, decoder)) is not None:
                    yield entry
                    continue
                line = bytes(buf[start:stop]) + newline  # as read_records' text mode reads it
                line.decode("utf-8")
                if header:
                    yield _slow(line, decoder)
                    continue
                _header(json.loads(line))
                header = True
    except OSError as exc:
        raise SessionError(f"{path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise SessionError(f"{path}: not a text file") from None
    except (ValueError, KeyError, TypeError) as exc:
        what = f"missing {exc}" if isinstance(exc, KeyError) else str(exc)
        raise SessionError(f"{path}:{n}: {what}") from None
    if not header:
        raise SessionError(f"{path}: empty, not a {FORMAT} file")
