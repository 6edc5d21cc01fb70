"""The recorder in a process of its own, so that decoding, the view and the files never delay a forwarded byte.

Rules:
- ``RecorderPipe`` stands where the network module expects a recorder, and may be called from any thread (the
  forwarding threads call it directly, ``threadsafe``): each call packs one message (a fixed header and the
  bytes) and appends it to a queue, nothing more. ``flush`` (the network module's event loop, every few
  milliseconds) writes what is queued to the pipe without blocking: one write, and one wakeup of the recorder
  process, for many messages. What the pipe does not take at once waits for the next ``flush``.
- The child runs at a lower priority (``NICE``; on Linux also in the SCHED_IDLE class, which runs only on a CPU
  nothing else wants - added with the C loop of network.py, whose spin yields its CPU to the client or the
  target, not to the recorder; its effect alone was not measured): when the machine is busy, forwarding comes
  first and the recording catches up when there is time (what it has not taken waits in the pipe and in the
  buffer).
- The child (forked before the event loop starts, so it inherits no loop and no socket) builds the recorder
  with ``make`` and replays the messages into it in order; at the end of the pipe it closes the recorder
  (files flushed) and prints the summary.
- Should the child die, the next write fails: recording stops, forwarding goes on (reported once).
"""

from __future__ import annotations

import collections
import contextlib
import fcntl
import json
import os
import select
import signal
import struct
import sys
from collections.abc import Callable
from typing import Any

from pltf.proxy.recorder import Recorder

_HEAD = struct.Struct("<BIBdI")  # kind, connection, c2s, time, payload length
START, OPENED, DATA, HALF, CLOSED = range(5)
_PIPE_SIZE = 1 << 20
NICE = 10  # added to the recorder process's niceness
IDLE_FLUSH = 0.25  # s without messages after which the child flushes its files


class RecorderPipe:
    threadsafe = True  # the network module may call it from its forwarding threads

    def __init__(self, make: Callable[[], Recorder], summary: Callable[[Recorder], str]) -> None:
        self.make, self.summary = make, summary
        self.pid = 0
        self.fd = -1
        self._queue: collections.deque[bytes] = collections.deque()  # messages (appended from any thread)
        self._buf = bytearray()  # what the pipe has not taken yet (``flush``'s thread only)
        self.broken = False

    def start(self) -> None:
        r, w = os.pipe()
        with contextlib.suppress(OSError):  # a bigger pipe: fewer stalls when the child falls behind
            fcntl.fcntl(w, getattr(fcntl, "F_SETPIPE_SZ", 1031), _PIPE_SIZE)
        pid = os.fork()
        if pid == 0:  # the child: Ctrl-C and SIGTERM (to the group too) are the parent's to act on (it ends the pipe)
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            signal.signal(signal.SIGTERM, signal.SIG_IGN)  # a group's SIGTERM lost the recording's tail (issue 32)
            os.close(w)
            with contextlib.suppress(OSError):
                os.nice(NICE)
            with contextlib.suppress(OSError, AttributeError):  # Linux: run only on a CPU nothing else wants
                os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))
            code = 0
            try:
                _child(r, self.make, self.summary)
            except BaseException:
                import traceback

                traceback.print_exc()
                code = 1
            finally:
                sys.stdout.flush()
                sys.stderr.flush()
                os._exit(code)
        os.close(r)
        os.set_blocking(w, False)
        self.pid, self.fd = pid, w

    # ------------------------------------------------------------------ what the network module calls
    def _send(self, kind: int, conn: int, c2s: bool, now: float, payload: bytes = b"") -> None:
        if not self.broken:
            self._queue.append(_HEAD.pack(kind, conn, c2s, now, len(payload)) + payload)

    def _write(self) -> None:
        try:
            n = os.write(self.fd, self._buf)
        except BlockingIOError:
            return
        except OSError as exc:
            self.broken = True
            self._buf.clear()
            raise RuntimeError(f"the recorder process is gone ({exc.strerror})") from None
        del self._buf[:n]

    def session_start(self, routes: list[tuple[str, str]], started: float) -> None:
        self._send(START, 0, False, started, json.dumps(routes).encode())

    def opened(self, conn: int, now: float, port: int, client: tuple[str, int], target: tuple[str, int]) -> None:
        self._send(OPENED, conn, False, now, json.dumps([port, list(client), list(target)]).encode())

    def data(self, conn: int, now: float, c2s: bool, chunk: bytes) -> None:
        self._send(DATA, conn, c2s, now, chunk)

    def half_closed(self, conn: int, now: float, c2s: bool) -> None:
        self._send(HALF, conn, c2s, now)

    def closed(self, conn: int, now: float, detail: str, ended_at: float | None = None) -> None:
        self._send(CLOSED, conn, False, now, json.dumps([detail, ended_at]).encode())

    def _take(self) -> None:
        queue, buf = self._queue, self._buf
        while queue:
            buf += queue.popleft()

    def flush(self) -> None:
        """Write what is queued (from one thread at a time: the network module's loop)."""
        if self.broken:
            return
        self._take()
        if self._buf:
            self._write()

    def close(self, now: float) -> None:
        """Hand over what is left, end the pipe and wait for the child to finish its files."""
        if self.fd < 0:
            return
        if not self.broken:
            self._take()
            os.set_blocking(self.fd, True)
            with contextlib.suppress(OSError):
                while self._buf:
                    del self._buf[: os.write(self.fd, self._buf)]
        os.close(self.fd)
        self.fd = -1
        with contextlib.suppress(ChildProcessError):
            os.waitpid(self.pid, 0)


def _child(fd: int, make: Callable[[], Recorder], summary: Callable[[Recorder], str]) -> None:
    recorder = make()
    buf = bytearray()
    last = 0.0
    while True:
        ready, _, _ = select.select([fd], [], [], IDLE_FLUSH)
        if not ready:
            recorder.flush()
            continue
        chunk = os.read(fd, 1 << 20)
        if not chunk:
            break
        buf += chunk
        pos = 0
        while len(buf) - pos >= _HEAD.size:
            kind, conn, c2s, now, n = _HEAD.unpack_from(buf, pos)
            if len(buf) - pos - _HEAD.size < n:
                break
            payload = bytes(buf[pos + _HEAD.size : pos + _HEAD.size + n])
            pos += _HEAD.size + n
            _apply(recorder, kind, conn, bool(c2s), now, payload)
            last = now
        del buf[:pos]
    recorder.close(last)
    print(summary(recorder), file=sys.stderr, flush=True)


def _apply(recorder: Recorder, kind: int, conn: int, c2s: bool, now: float, payload: bytes) -> None:
    args: Any
    if kind == DATA:
        recorder.data(conn, now, c2s, payload)
    elif kind == START:
        routes = json.loads(payload)
        if recorder.session is not None:
            from pltf.proxy.session import Route

            recorder.session.start([Route(a, b) for a, b in routes], now)
    elif kind == OPENED:
        args = json.loads(payload)
        recorder.opened(conn, now, args[0], tuple(args[1]), tuple(args[2]))
    elif kind == HALF:
        recorder.half_closed(conn, now, c2s)
    elif kind == CLOSED:
        detail, ended_at = json.loads(payload)
        recorder.closed(conn, now, detail, ended_at)
