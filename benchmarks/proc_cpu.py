"""CPU seconds of a process group, read from /proc: what a benchmark's target spent while a subject drove it.

Rules:
- A target started by ``pltf.harness.launch`` runs in a process group of its own (a zoo member and the server behind
  it are two processes of one group), so the group is what "the target" costs.
- Only live processes count: read the group before the target is stopped. utime + stime of each, in clock ticks
  (``os.sysconf("SC_CLK_TCK")``), so a figure is good to 10 ms; compare readings seconds apart, not milliseconds.
- Where /proc is not there (not Linux), ``group_cpu`` returns None and the rows that need it are left out.
"""

from __future__ import annotations

import os
from pathlib import Path

PROC = Path("/proc")
TICK = float(os.sysconf("SC_CLK_TCK")) if hasattr(os, "sysconf") else 100.0


def _stat_fields(path: Path) -> list[str] | None:
    """The fields of /proc/PID/stat after the command (which may hold spaces and parentheses)."""
    try:
        text = (path / "stat").read_text()
    except OSError:  # the process ended between the listing and the read
        return None
    return text[text.rfind(")") + 2 :].split()


def _seconds(fields: list[str]) -> float:
    return (int(fields[11]) + int(fields[12])) / TICK  # utime, stime: fields 14 and 15 of the line (proc(5))


def stat_cpu(stat_dir: Path) -> float | None:
    """CPU seconds (user + system) of one process (``/proc/PID``) or thread (``/proc/PID/task/TID``); None when it
    is gone."""
    fields = _stat_fields(stat_dir)
    return None if fields is None else _seconds(fields)


def process_cpu(pid: int) -> float | None:
    return stat_cpu(PROC / str(pid))


def group_cpu(pgid: int) -> float | None:
    """CPU seconds (user + system) of the live processes of process group ``pgid``; None without /proc."""
    if not PROC.is_dir():
        return None
    total = 0.0
    for entry in PROC.iterdir():
        if not entry.name.isdigit():
            continue
        fields = _stat_fields(entry)
        # after the command: state ppid pgrp ...; a zombie (state Z: ended, not yet reaped - an orphan where PID 1
        # does not reap) is not the target any more
        if fields is not None and int(fields[2]) == pgid and fields[0] != "Z":
            total += _seconds(fields)
    return total


def pgid_of(pid: int) -> int | None:
    try:
        return os.getpgid(pid)
    except (ProcessLookupError, PermissionError):
        return None


__all__ = ["TICK", "group_cpu", "pgid_of", "process_cpu", "stat_cpu"]
