"""One sample a minute: every process's RSS, descriptors and threads, the recording's size and telegram count.

Rules:
- A sample is a plain dict (written as one JSON line as it is taken, so a run cut short keeps what it saw):
  ``t`` (seconds since the start), ``load`` (1-minute load average), ``procs`` ({pid: {name, rss_mb, fds,
  threads}}), ``recording`` ({bytes, telegrams}), ``dead`` (parts that ended).
- The telegram count is read from the session file as it grows (frames are its ``"kind": "frame"`` lines), up to
  its last complete line, so a minute costs reading that minute's bytes once.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from benchmarks.soak.procs import usage

FRAME = b'"kind": "frame"'


class RecordingMeter:
    """Bytes of the recording (session file and pcapng) and the telegrams in its session file so far."""

    def __init__(self, session: Path) -> None:
        self.session = session
        self.pcapng = session.with_suffix(".pcapng")
        self.offset = 0
        self.telegrams = 0

    def read(self) -> dict[str, int]:
        try:
            with self.session.open("rb") as fh:
                fh.seek(self.offset)
                chunk = fh.read()
        except OSError:
            chunk = b""
        complete = chunk[: chunk.rfind(b"\n") + 1]
        self.telegrams += complete.count(FRAME)
        self.offset += len(complete)
        return {"bytes": _size(self.session) + _size(self.pcapng), "telegrams": self.telegrams}


def _size(path: Path) -> int:
    try:
        return path.stat().st_size
    except OSError:
        return 0


def take(t: float, processes: dict[int, str], meter: RecordingMeter, dead: list[str]) -> dict[str, Any]:
    procs = {}
    for pid, name in processes.items():
        u = usage(pid)
        if u is not None:
            procs[str(pid)] = {"name": name, "rss_mb": round(u.rss_mb, 3), "fds": u.fds, "threads": u.threads}
    return {"t": round(t, 1), "load": os.getloadavg()[0], "procs": procs, "recording": meter.read(), "dead": dead}


def append(path: Path, sample: dict[str, Any]) -> None:
    with path.open("a", encoding="utf-8") as fh:
        fh.write(json.dumps(sample) + "\n")


def series(samples: list[dict[str, Any]]) -> dict[str, tuple[str, dict[str, list[tuple[float, float]]]]]:
    """Per pid: its name and, per quantity, ``[(t, value), ...]``."""
    out: dict[str, tuple[str, dict[str, list[tuple[float, float]]]]] = {}
    for s in samples:
        for pid, p in s["procs"].items():
            _, by = out.setdefault(pid, (p["name"], {"rss_mb": [], "fds": [], "threads": []}))
            for q, points in by.items():
                points.append((s["t"], float(p[q])))
    return out
