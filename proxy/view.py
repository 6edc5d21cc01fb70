"""The live view of ``pltf proxy``: one line per telegram (time, connection, port, direction, telegram, fields).

Rules: a view only reads records. ``--filter``/``--hide`` take telegram names or globs, with or without the
``CMD_`` prefix (``GET_STATUS``, ``CMD_MOVE_*``), case-insensitive; malformed bytes and connection events are
always shown. Enum values print as NAME(number), groups as their item count (the first items when few), long
strings cut short; a line never wraps past ``width``. Colour only on a terminal.
"""

from __future__ import annotations

import datetime
import fnmatch
from collections.abc import Sequence
from typing import Any, TextIO

from pltf.proxy.tap import CLOSE, OPEN, Record
from pltf.spec.jsonio import telegram_to_json

ARROW = {"request": "->", "reply": "<-"}
_COLOR = {"request": "\x1b[36m", "reply": "\x1b[32m", "malformed": "\x1b[1;31m", "event": "\x1b[2m"}
_RESET = "\x1b[0m"
STRING_CUT = 40
ITEMS_SHOWN = 3


def _pattern(p: str) -> str:
    p = p.strip().upper()
    return p if p.startswith(("CMD_", "*")) else f"CMD_{p}"


class Selection:
    """Which telegrams a view shows: any of ``keep`` (all when empty) and none of ``hide``."""

    def __init__(self, keep: Sequence[str] = (), hide: Sequence[str] = ()) -> None:
        self.keep = [_pattern(p) for p in keep if p.strip()]
        self.hide = [_pattern(p) for p in hide if p.strip()]

    def shows(self, rec: Record) -> bool:
        if rec.telegram is None:
            return True  # malformed bytes and events
        name = rec.telegram.NAME
        if self.keep and not any(fnmatch.fnmatchcase(name, p) for p in self.keep):
            return False
        return not any(fnmatch.fnmatchcase(name, p) for p in self.hide)


def _value(v: Any) -> str:
    if isinstance(v, str):
        return repr(v if len(v) <= STRING_CUT else v[:STRING_CUT] + "...")
    if isinstance(v, list):
        if v and isinstance(v[0], dict):
            head = ", ".join(
                "{" + " ".join(f"{k}={_value(x)}" for k, x in item.items()) + "}" for item in v[:ITEMS_SHOWN]
            )
            return f"[{len(v)}: {head}{', ...' if len(v) > ITEMS_SHOWN else ''}]"
        return "[" + ",".join(_value(x) for x in v) + "]"
    return repr(v)


def format_fields(shape: dict[str, Any]) -> str:
    """``fields`` of ``pltf decode``'s JSON as ``name=value`` words, enums as NAME(number)."""
    names = shape.get("names", {})
    words = []
    for k, v in shape["fields"].items():
        words.append(f"{k}={names[k]}({v})" if k in names else f"{k}={_value(v)}")
    return " ".join(words)


def format_record(rec: Record, t0: float | None = None) -> tuple[str, str]:
    """(style, line) of one record: style is request, reply, malformed or event."""
    if t0 is None:
        stamp = datetime.datetime.fromtimestamp(rec.time).strftime("%H:%M:%S.%f")[:-3]
    else:
        stamp = f"{rec.time - t0:10.3f}"
    head = f"{stamp} #{rec.conn:<3} :{rec.port:<5}"
    if rec.kind in (OPEN, CLOSE):
        return "event", f"{head}    {rec.kind} {rec.detail}"
    arrow = ARROW[rec.direction or "request"]
    if rec.telegram is not None:
        shape = telegram_to_json(rec.telegram)
        return rec.direction or "request", f"{head} {arrow} {rec.telegram.NAME} {format_fields(shape)}".rstrip()
    raw = rec.raw[:24].hex() + ("..." if len(rec.raw) > 24 else "")
    return "malformed", f"{head} {arrow} MALFORMED {rec.error} ({len(rec.raw)} bytes: {raw})"


class View:
    def __init__(
        self,
        out: TextIO,
        selection: Selection | None = None,
        *,
        color: bool = False,
        width: int = 160,
        t0: float | None = None,
    ) -> None:
        self.out, self.selection = out, selection or Selection()
        self.color, self.width, self.t0 = color, width, t0
        self.shown = 0

    def show(self, rec: Record) -> None:
        if not self.selection.shows(rec):
            return
        style, line = format_record(rec, self.t0)
        if len(line) > self.width:
            line = line[: self.width - 3] + "..."
        if self.color:
            line = f"{_COLOR[style]}{line}{_RESET}"
        self.out.write(line + "\n")
        self.shown += 1

    def flush(self) -> None:
        self.out.flush()
