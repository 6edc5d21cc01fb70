"""One epoll for the lanes' flights (``pltf.fuzz.lanes``): plain singles in C and Python flights side by side.

Rules:
- Each socket is registered once, for reading, and for writing only while its flight has something to send now;
  a closed socket leaves epoll by itself, a kept connection is taken out when its flight is done.
- Where ``_singles`` is built the epoll is its ``Pool``: the C singles (``pltf.fuzz.single.CSingle``) enrol
  themselves and are driven inside ``poll`` without a Python call; the Python flights get their ``(fd, events)``
  back as with ``select.epoll``.
- One round is ``pltf.fuzz.flight``'s ``select`` round: the flights past their deadline are finished first.
"""

from __future__ import annotations

import contextlib
import select
import time
from typing import Any

try:
    from pltf.fuzz import _singles
except ImportError:  # built without a compiler, or PLTF_NO_EXTENSIONS=1
    _singles = None  # type: ignore[assignment]

_IN = select.EPOLLIN
_OUT = select.EPOLLOUT


class Poller:
    """The lanes' flights on one epoll: registered once (reading; writing only while a flight has bytes due), a
    socket closed leaves it by itself; a kept connection is taken out when its flight is done."""

    def __init__(self) -> None:
        self.ep: Any = _singles.Pool() if _singles is not None else select.epoll()  # ``CSingle``s enrol themselves
        self.masks: dict[int, int] = {}
        self.by_fd: dict[int, Any] = {}

    def close(self) -> None:
        self.ep.close()

    def step(self, live: list[Any], until: float | None) -> None:
        """One round, as ``_step``: finish the flights past their deadline, else wait for the nearest deadline (or
        ``until``, or a slow delivery's next piece) and drive the ones ready."""
        now = time.monotonic()
        nearest = until if until is not None else now + 3600.0
        overdue = False
        masks, by_fd, ep = self.masks, self.by_fd, self.ep
        for f in live:
            if now >= f.deadline:
                f._finish(timed_out=True)
                overdue = True
                continue
            nearest = min(nearest, f.deadline)
            if f.native:
                continue
            if f.sending:
                if f.connected and f.next_at > now:
                    nearest = min(nearest, f.next_at)
                want = _IN | _OUT if not f.connected or f.due else _IN
            else:
                want = _IN
            fd = f.poll_fd if f.poll_fd >= 0 else f.fileno()
            if masks.get(fd) != want:
                self._arm(fd, want, f)
        if overdue:
            self.forget(live)
            return
        for fd, ev in ep.poll(max(0.0, nearest - now)):
            f = by_fd.get(fd)
            if f is None or f.done:
                continue
            if ev & _OUT:
                f.writable()
            if ev & ~_OUT and not f.done:
                f.readable()
        self.forget(live)

    def _arm(self, fd: int, want: int, f: Any) -> None:
        """Register ``fd`` for ``want`` (or change what it waits for). The number of a socket closed meanwhile
        (it left epoll by itself) may be a new socket's."""
        if f.poll_fd != fd:
            f.poll_fd = fd
            self.masks.pop(fd, None)
        try:
            if fd in self.masks:
                self.ep.modify(fd, want)
            else:
                self.ep.register(fd, want)
        except FileNotFoundError:  # closed and reused since
            self.ep.register(fd, want)
        except FileExistsError:
            self.ep.modify(fd, want)
        self.masks[fd] = want
        self.by_fd[fd] = f

    def forget(self, flights: list[Any]) -> None:
        """The flights done leave the poller: a closed socket has left epoll by itself, a kept one is taken out
        (between its flights a byte from the target would wake every wait)."""
        for f in flights:
            fd, kept = f.poll_fd, f.kept
            if f.done and fd >= 0:
                f.poll_fd = -1
                if self.by_fd.get(fd) is f:
                    del self.by_fd[fd], self.masks[fd]
                    if kept is not None:
                        with contextlib.suppress(OSError):
                            self.ep.unregister(fd)
