"""What a process holds, read from /proc: resident memory, open descriptors, threads; and a process's descendants.

Rules:
- ``peak_rss_mb``: the process's own high-water mark (VmHWM), which starts at its exec (the rusage of a child,
  wait4's ``ru_maxrss``, also counts the parent's pages it was forked with).
- One reading is ``Usage(rss_mb, fds, threads)`` from ``/proc/PID/status`` (VmRSS, Threads) and ``/proc/PID/fd``;
  None when the process is gone (or not ours to read).
- ``descendants`` walks the parent links of every live process once per call (a soak samples once a minute).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

PROC = Path("/proc")


@dataclass(frozen=True)
class Usage:
    rss_mb: float
    fds: int
    threads: int


def _status(pid: int) -> dict[str, str] | None:
    try:
        text = (PROC / str(pid) / "status").read_text()
    except OSError:
        return None
    return dict(line.split(":\t", 1) for line in text.splitlines() if ":\t" in line)


def usage(pid: int) -> Usage | None:
    """RSS (MB), open descriptors and threads of ``pid``; None when it is gone or a zombie."""
    status = _status(pid)
    if status is None or "VmRSS" not in status:  # a zombie has no memory lines
        return None
    try:
        fds = len(os.listdir(PROC / str(pid) / "fd"))
    except OSError:
        return None
    rss_kb = int(status["VmRSS"].split()[0])
    return Usage(rss_kb / 1024.0, fds, int(status["Threads"].strip()))


def peak_rss_mb(pid: int) -> float | None:
    """The high-water mark of ``pid``'s resident memory (VmHWM, MB) since it last exec'd; None when it is gone."""
    status = _status(pid)
    if status is None or "VmHWM" not in status:
        return None
    return int(status["VmHWM"].split()[0]) / 1024.0


def _parents() -> dict[int, int]:
    out = {}
    for entry in PROC.iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            out[int(entry.name)] = int(stat[stat.rfind(")") + 2 :].split()[1])
    return out


def descendants(root: int) -> list[int]:
    """Every live process below ``root`` (children, their children, ...), in pid order."""
    children: dict[int, list[int]] = {}
    for pid, ppid in _parents().items():
        children.setdefault(ppid, []).append(pid)
    out, todo = [], list(children.get(root, []))
    while todo:
        pid = todo.pop()
        out.append(pid)
        todo.extend(children.get(pid, []))
    return sorted(out)


def cmdline(pid: int) -> list[str]:
    try:
        raw = (PROC / str(pid) / "cmdline").read_bytes()
    except OSError:
        return []
    return [a.decode("utf-8", "replace") for a in raw.split(b"\0") if a]


def comm(pid: int) -> str:
    try:
        return (PROC / str(pid) / "comm").read_text().strip()
    except OSError:
        return ""
