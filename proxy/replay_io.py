"""The sending side of ``pltf replay``: asyncio, and the only module of the replay with sockets and a clock.

Rules (the timing and the waits are replay.py's; this module carries them out):
- Every recorded connection is a task with its own socket; replies are decoded as they come (tap.py) and
  answer the oldest request of their identifier still open.
- Times are the loop's monotonic clock; recorded gaps are divided by the time scale. No wait is unbounded: a
  reply is waited for ``reply_timeout`` s at most, a connection's turn (the closes before it) ``connect_timeout``.
- The replay's client ends a connection the way the recorded client did (FIN after the replies it was owed);
  where the recorded target ended it, the replay waits for the target to.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pltf.proxy.replay import WAIT_GRACE, Outcome, Script, Wait, final_matches
from pltf.proxy.tap import FRAME, Record, Tap

READ_SIZE = 65536
CLOSE_PAUSE_MAX = 1.0  # s: the recorded pause before a client's close, at most


@dataclass(frozen=True)
class Settings:
    host: str
    ports: list[int]  # per route of the session
    time_scale: float = 1.0
    reply_timeout: float = 3.0
    connect_timeout: float = 5.0


class _Conn:
    def __init__(self, script: Script, settings: Settings, t0: float, closed: dict[int, asyncio.Event]) -> None:
        self.s, self.cfg, self.t0, self.closed = script, settings, t0, closed
        self.loop = asyncio.get_running_loop()
        self.out = Outcome(script.conn)
        self.port = settings.ports[script.route]
        self.tap = Tap("reply", script.conn, self.port)
        self.pending: dict[int, deque[Any]] = {}  # identifier -> keys of the requests it may answer
        self.got: dict[Any, Record] = {}  # key -> reply
        self.arrivals: list[float] = []
        self.changed = asyncio.Event()
        self.eof = False
        self.closing = False
        self.skipped = 0  # replies the recording has and the replay will not (polls a wait did not need)
        self.extended = 0  # replies the replay has and the recording does not (polls past the recorded ones)
        self.last_send = 0.0

    # ------------------------------------------------------------------ reading
    async def _read(self, reader: asyncio.StreamReader) -> None:
        try:
            while data := await reader.read(READ_SIZE):
                self._take(self.tap.feed(data, self.loop.time()))
        except (ConnectionError, OSError):
            pass
        self._take(self.tap.end(self.loop.time()))
        if not self.closing and self.out.closed_by_target_after is None:
            self.out.closed_by_target_after = self.out.sent
        self.eof = True
        self._notify()

    def _take(self, records: list[Record]) -> None:
        for rec in records:
            self.arrivals.append(rec.time)
            ident = rec.raw[8] if rec.kind == FRAME and len(rec.raw) > 8 else -1
            keys = self.pending.get(ident)
            if keys:
                self.got[keys.popleft()] = rec
            else:
                self.out.extra.append(rec)
        if records:
            self._notify()

    def _answered(self, key: Any) -> Callable[[], bool]:
        return lambda: key in self.got or self.eof

    def _arrived(self, count: int) -> Callable[[], bool]:
        return lambda: len(self.arrivals) >= count or self.eof

    def _notify(self) -> None:
        self.changed.set()
        self.changed = asyncio.Event()

    async def _until(self, ok: Callable[[], bool], timeout: float) -> bool:
        deadline = self.loop.time() + timeout
        while not ok():
            left = deadline - self.loop.time()
            if left <= 0:
                return False
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self.changed.wait(), left)
        return True

    async def _sleep_until(self, when: float) -> None:
        await asyncio.sleep(max(0.0, when - self.loop.time()))

    # ------------------------------------------------------------------ sending
    def _send(self, writer: asyncio.StreamWriter, raw: bytes, ident: int, key: Any, answered: bool) -> None:
        writer.write(raw)
        self.last_send = self.loop.time()
        if answered:
            self.pending.setdefault(ident, deque()).append(key)

    def _wait_done(self, wait: Wait, index: int) -> bool:
        """Before poll ``index`` of a wait: did the poll before it already bring the wait's final reply?"""
        if wait.id in self.out.wait_final:
            return True
        prev = self.got.get(index - 1)
        if index > wait.steps[0] and prev is not None and final_matches(self.s.steps[wait.final], prev):
            self.out.wait_final[wait.id] = prev
            return True
        return False

    async def _finish_wait(self, wait: Wait, writer: asyncio.StreamWriter, started: float) -> None:
        """After the last recorded poll: poll on at the recorded pace until the final reply comes or time is up."""
        final = self.s.steps[wait.final]
        scale = self.cfg.time_scale
        deadline = started + 2 * wait.duration / scale + WAIT_GRACE
        key: Any = wait.final
        while True:
            await self._until(self._answered(key), self.cfg.reply_timeout)
            got = self.got.get(key)
            if got is not None:
                self.out.wait_final[wait.id] = got
            if got is None or final_matches(final, got) or self.eof or self.loop.time() >= deadline:
                return
            await asyncio.sleep(wait.interval / scale)
            n = self.out.polls[wait.id] = self.out.polls.get(wait.id, 0) + 1
            key = ("poll", wait.id, n)
            self.extended += 1
            self._send(writer, final.raw, final.ident, key, True)

    async def _steps(self, writer: asyncio.StreamWriter) -> None:
        scale = self.cfg.time_scale
        wait_started: dict[int, float] = {}
        for i, step in enumerate(self.s.steps):
            due = step.after_replies - self.skipped + self.extended
            await self._until(self._arrived(due), self.cfg.reply_timeout)
            ref = self.last_send
            if 0 < due <= len(self.arrivals):
                ref = max(ref, self.arrivals[due - 1])
            await self._sleep_until(ref + step.gap / scale)
            if self.eof:
                return
            wait = self.s.wait_of(i)
            if wait is not None and self._wait_done(wait, i):
                self.skipped += 1
                self.out.sent = i + 1
                continue
            if wait is not None:
                wait_started.setdefault(wait.id, self.loop.time())
                self.out.polls[wait.id] = self.out.polls.get(wait.id, 0) + 1
            self._send(writer, step.raw, step.ident, i, step.answered)
            self.out.sent = i + 1
            if wait is not None and i == wait.final:
                await self._finish_wait(wait, writer, wait_started[wait.id])

    async def _end(self, writer: asyncio.StreamWriter) -> None:
        if self.s.closed_by == "target":
            pause = max(2.0, 2 * self.s.close_gap / self.cfg.time_scale)
            await self._until(lambda: self.eof, pause + self.cfg.reply_timeout)
            return
        await self._until(lambda: self.eof or not any(self.pending.values()), self.cfg.reply_timeout)
        await asyncio.sleep(min(CLOSE_PAUSE_MAX, self.s.close_gap / self.cfg.time_scale))
        self.closing = True
        if not self.eof and writer.can_write_eof():
            with contextlib.suppress(OSError):
                writer.write_eof()
            await self._until(lambda: self.eof, self.cfg.reply_timeout)

    def _collect(self) -> None:
        """The replies by step; a wait whose final reply came only after its time ends on its last poll's reply."""
        for key, rec in self.got.items():
            if isinstance(key, int):
                self.out.replies[key] = rec
        for wait in self.s.waits.values():
            if wait.id not in self.out.wait_final:
                polls = [("poll", wait.id, n) for n in range(self.out.polls.get(wait.id, 0), 0, -1)]
                late = next((self.got[k] for k in [*polls, *reversed(wait.steps)] if k in self.got), None)
                if late is not None:
                    self.out.wait_final[wait.id] = late

    async def run(self) -> Outcome:
        s, cfg = self.s, self.cfg
        try:
            for other in s.after_closes:
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self.closed[other].wait(), cfg.connect_timeout)
            await self._sleep_until(self.t0 + s.start / cfg.time_scale)
            try:
                reader, writer = await asyncio.wait_for(
                    asyncio.open_connection(cfg.host, self.port), cfg.connect_timeout
                )
            except (OSError, TimeoutError) as exc:
                self.out.error = f"cannot connect to {cfg.host}:{self.port}: {getattr(exc, 'strerror', None) or exc}"
                return self.out
            self.last_send = self.loop.time()
            reading = asyncio.create_task(self._read(reader))
            try:
                await self._steps(writer)
                await self._end(writer)
            except (ConnectionError, OSError):
                pass
            finally:
                self.closing = True
                writer.close()
                with contextlib.suppress(ConnectionError, OSError):
                    await writer.wait_closed()
                reading.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await reading
            self._collect()
            return self.out
        finally:
            self.closed[s.conn].set()


async def replay(scripts: list[Script], settings: Settings) -> dict[int, Outcome]:
    """Replay every connection of the session (concurrently, each on its schedule); their outcomes by number."""
    t0 = asyncio.get_running_loop().time()
    closed = {s.conn: asyncio.Event() for s in scripts}
    outcomes = await asyncio.gather(*(_Conn(s, settings, t0, closed).run() for s in scripts))
    return {o.conn: o for o in outcomes}
