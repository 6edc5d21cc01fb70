"""Windows of cases drawn ahead of the campaign, in a forked child process.

Rules:
- Windows come out in index order, so the stream is the one ``pltf.fuzz.schedule.Scheduler`` defines; what the
  target told us (``Knowledge``) goes to the child with each ``get`` and takes effect a few windows later.
- Drawing runs beside the campaign instead of taking the campaign's interpreter lock between its socket calls.
- The child writes each window itself, length-prefixed, into a pipe enlarged to ``PIPE_SIZE``: no feeder thread.
  (``multiprocessing.Queue`` pickles and writes from a thread that has to win the child's interpreter lock
  from the drawing loop for every 64 KiB chunk - at 5 ms a switch, a window of a few hundred KiB waited tens of
  milliseconds on the campaign's side, about 15 % of a run.)
- Knowledge goes the other way as changes only: the fields of ``Knowledge.light`` that differ from what was sent
  last, and the documents that changed, one message per window taken (empty when nothing changed). While its
  window waits for room in the pipe, the child reads knowledge, so neither side can block the other for good.
- The child draws at most ``AHEAD`` windows the campaign has not taken (each message is a window taken): a pipe
  of 1 MiB held up to a dozen windows of small cases, drawn and never served when the target is slow or the run
  ends - against a target serving a few hundred cases a second, more CPU than the cases served.
- The child is forked before the campaign opens its connections and closes every socket it inherited anyway, so
  that a connection the campaign closes is closed. Where fork is not available the windows are drawn in a thread.
- Where the compiled core draws (``Scheduler.compiled``, ``pltf.fuzz.draw``) there is no child: a window is drawn
  when it is taken, in the campaign's process (~3 us a case; pickling a window through the pipe and back cost
  ~2.4 us a case and the child's own wake-ups more), with what was learnt up to then.
"""

from __future__ import annotations

import contextlib
import fcntl
import multiprocessing
import os
import pickle
import queue
import select
import stat
import struct
import threading
import time
import traceback
from typing import Any

from pltf.fuzz.case import Case
from pltf.fuzz.schedule import Scheduler

PIPE_SIZE = 1 << 20  # bytes (Linux's default /proc/sys/fs/pipe-max-size): a typical window fits whole
GET_TIMEOUT = 30.0  # s the campaign waits for a window before it gives up
AHEAD = 2  # windows drawn and not yet taken, at most (a window takes ~10 ms to draw, a campaign ~0.1-1 s to run)
_LENGTH = struct.Struct(">Q")


def _enlarge(fd: int) -> None:
    with contextlib.suppress(OSError, AttributeError):
        fcntl.fcntl(fd, fcntl.F_SETPIPE_SZ, PIPE_SIZE)


class Prefetcher:
    def __init__(self, sched: Scheduler, start: int, window: int, ahead: int = AHEAD) -> None:
        self.sched, self.next_index, self.window = sched, start, window
        self.sent_light: dict[str, Any] = {}
        self.sent_documents: dict[str, bytes] = {}
        self.sent_version = -1
        self.proc: Any = None
        self.thread: threading.Thread | None = None
        self.stopped = threading.Event()
        self.windows: queue.Queue[tuple[int, Any, int]] = queue.Queue(maxsize=ahead)
        self.inline = bool(getattr(sched, "compiled", False))
        if self.inline:
            return
        if "fork" in multiprocessing.get_all_start_methods():
            self.win_r, win_w = os.pipe()
            kb_r, self.kb_w = os.pipe()
            for fd in (win_w, self.kb_w):
                _enlarge(fd)
            ctx = multiprocessing.get_context("fork")
            ends = (win_w, kb_r, self.win_r, self.kb_w)  # the child keeps the first two, closes the parent's
            args = (sched, start, window, ends, ahead)
            self.proc = ctx.Process(target=_child, args=args, name="fuzz-prefetch", daemon=True)
            self.proc.start()
            os.close(win_w)
            os.close(kb_r)
        else:
            self.thread = threading.Thread(target=self._run_thread, name="fuzz-prefetch", daemon=True)
            self.thread.start()

    def _run_thread(self) -> None:
        i = self.next_index
        while not self.stopped.is_set():
            cases = [self.sched.case(i + k) for k in range(self.window)]
            while not self.stopped.is_set():
                try:
                    self.windows.put((i, cases, self.sched.dropped), timeout=0.1)
                    break
                except queue.Full:
                    continue
            i += self.window

    def _send_knowledge(self) -> None:
        """A window was taken: the knowledge that changed since the last message (none: an empty one)."""
        kb = self.sched.kb
        light: dict[str, Any] = {}
        documents: dict[str, bytes] = {}
        if kb.version != self.sent_version:
            light = {k: v for k, v in kb.light().items() if k not in self.sent_light or self.sent_light[k] != v}
            documents = {k: v for k, v in kb.documents.items() if self.sent_documents.get(k) is not v}
            self.sent_version = kb.version
            self.sent_light.update({k: v.copy() if isinstance(v, list | dict) else v for k, v in light.items()})
            self.sent_documents = dict(kb.documents)
        with contextlib.suppress(BrokenPipeError):  # the child is gone: the next ``get`` says so
            _write_all(self.kb_w, _EMPTY if not light and not documents else _message((light, documents)))

    def get(self) -> tuple[int, list[Case]]:
        """(index of the first case, the cases) of the next window."""
        if self.inline:
            first = self.next_index
            self.next_index += self.window
            return first, self.sched.window(first, self.window)
        if self.proc is None:
            try:
                first, cases, dropped = self.windows.get(timeout=GET_TIMEOUT)
            except queue.Empty:
                raise RuntimeError(f"the case generator produced nothing for {GET_TIMEOUT:g} s") from None
        else:
            first, cases, dropped = pickle.loads(_read_message(self.win_r, time.monotonic() + GET_TIMEOUT))
            self._send_knowledge()  # after the read: the child may be waiting for room (or leave) to draw the next
        if isinstance(cases, str):
            raise RuntimeError(f"the case generator failed:\n{cases}")
        self.sched.dropped = dropped
        return first, cases

    def close(self) -> None:
        self.stopped.set()
        if self.thread is not None:
            self.thread.join(timeout=5)
        if self.proc is not None:
            self.proc.terminate()
            self.proc.join(timeout=5)
            for fd in (self.win_r, self.kb_w):
                with contextlib.suppress(OSError):
                    os.close(fd)
            self.proc = None


def _message(obj: object) -> bytes:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    return _LENGTH.pack(len(data)) + data


_EMPTY = _message(({}, {}))


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]


def _read_exactly(fd: int, n: int, deadline: float) -> bytes:
    buf = bytearray()
    while len(buf) < n:
        wait = deadline - time.monotonic()
        if wait <= 0 or not select.select([fd], [], [], wait)[0]:
            raise RuntimeError(f"the case generator produced nothing for {GET_TIMEOUT:g} s")
        chunk = os.read(fd, n - len(buf))
        if not chunk:
            raise RuntimeError("the case generator exited")
        buf += chunk
    return bytes(buf)


def _read_message(fd: int, deadline: float) -> bytes:
    (n,) = _LENGTH.unpack(_read_exactly(fd, _LENGTH.size, deadline))
    return _read_exactly(fd, n, deadline)


# ---------------------------------------------------------------------------------------------- the child


def _child(sched: Scheduler, i: int, window: int, ends: tuple[int, int, int, int], ahead: int = AHEAD) -> None:
    """Windows of cases into ``out`` for ever (the parent terminates it), at most ``ahead`` of them not taken;
    knowledge from ``kb_in``. The parent's ends of both pipes are closed here, so that each side sees the other
    one go."""
    out, kb_in, *parents = ends
    for fd in parents:
        os.close(fd)
    _close_inherited_sockets()
    os.set_blocking(out, False)
    os.set_blocking(kb_in, False)
    inbox = _Inbox(kb_in, sched)
    written = 0
    try:
        while True:
            inbox.drain()
            while written - inbox.taken >= ahead:  # wait until the campaign takes one
                select.select([inbox.fd], [], [])
                inbox.drain()
            try:
                cases: Any = [sched.case(i + k) for k in range(window)]
            except Exception:
                cases = traceback.format_exc()
            _put(out, inbox, _message((i, cases, sched.dropped)))
            written += 1
            if isinstance(cases, str):
                return
            i += window
    except (EOFError, OSError):  # the parent is gone
        return


def _put(out: int, inbox: _Inbox, data: bytes) -> None:
    """Write ``data`` whole; while the pipe is full, take the knowledge the parent sends."""
    view = memoryview(data)
    while view:
        readable, writable, _ = select.select([inbox.fd], [out], [])
        if readable:
            inbox.drain()
        if writable:
            with contextlib.suppress(BlockingIOError):
                view = view[os.write(out, view) :]


class _Inbox:
    """Knowledge messages as they arrive on a non-blocking pipe (length-prefixed pickles)."""

    def __init__(self, fd: int, sched: Scheduler) -> None:
        self.fd, self.sched, self.buf = fd, sched, bytearray()
        self.taken = 0  # messages read: windows the campaign took

    def drain(self) -> None:
        while True:
            try:
                chunk = os.read(self.fd, 1 << 20)
            except BlockingIOError:
                break
            if not chunk:
                raise EOFError
            self.buf += chunk
        while len(self.buf) >= _LENGTH.size:
            (n,) = _LENGTH.unpack_from(self.buf)
            if len(self.buf) < _LENGTH.size + n:
                break
            light, documents = pickle.loads(self.buf[_LENGTH.size : _LENGTH.size + n])
            del self.buf[: _LENGTH.size + n]
            self.taken += 1
            if light or documents:
                self.sched.kb.update(light, documents)


def _close_inherited_sockets() -> None:
    """Close the sockets the fork gave us (ours are pipes): a connection the parent closes must close."""
    try:
        fds = [int(fd) for fd in os.listdir("/proc/self/fd")]
    except OSError:
        return
    for fd in fds:
        with contextlib.suppress(OSError):
            if stat.S_ISSOCK(os.fstat(fd).st_mode):
                os.close(fd)
