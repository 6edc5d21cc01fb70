"""The sending side of ``pltf replay``: asyncio, and the only module of the replay with sockets and a clock.

Rules (the timing and the waits are replay.py's; this module carries them out):
- The session file is read as a stream: once for every connection's summary and where its open is (replay.py
  ``Survey``), then by each connection for itself during the replay, from its open on (the other connections'
  lines skipped unparsed), into its steps as they become ready (replay.py ``Builder``); a connection's reader
  stops while ``AHEAD`` of its steps are ready and not taken, unless the connection waits for one (a wait's
  final reply can lie ``WAIT_SPAN`` seconds ahead), and ends at its close. A reply is judged as soon as the
  replay has it and the recorded one is read, then dropped. So memory does not grow with the recording's
  length, nor when one connection's replay falls behind another's (a reader shared by all would have to
  keep what lies between them).
- Every recorded connection is a task with its own socket, started shortly before its recorded time; replies
  are decoded as they come (tap.py) and answer the oldest request of their identifier still open.
- Times are the loop's monotonic clock; recorded gaps are divided by the time scale. A request is never sent
  before its recorded time since its connection opened (scaled): a wait that ends sooner than recorded does not
  bring the connection's later requests forward, so the connections stay in step (the soak's patrol, whose
  waits ended early, closed its port seconds before the recording's end and the reconnecting client's last
  four connections were served instead of turned away). No wait is unbounded: a
  reply is waited for ``reply_timeout`` s at most, a connection's turn (the closes before it) ``connect_timeout``.
  A reply still missing ``LATE`` s after its request is judged missing (one that comes later is dropped).
- The replay's client ends a connection the way the recorded client did (FIN after the replies it was owed);
  where the recorded target ended it, the replay waits for the target to.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from pltf.proxy.replay import (
    WAIT_GRACE,
    Builder,
    Difference,
    Outcome,
    Script,
    Step,
    Survey,
    Wait,
    closes_first,
    final_matches,
    judge_end,
    judge_step,
    judge_wait,
)
from pltf.proxy.session import SessionFile
from pltf.proxy.tap import FRAME, Record, Tap

READ_SIZE = 65536
CLOSE_PAUSE_MAX = 1.0  # s: the recorded pause before a client's close, at most
AHEAD = 256  # steps of a connection ready and not yet taken before its reader pauses
BATCH = 256  # lines read between two turns of the event loop
EARLY = 1.0  # s before its recorded time (scaled) a connection's task starts
ARRIVALS_KEPT = 4096  # arrival times of replies kept per connection (the replay looks back a few)


@dataclass(frozen=True)
class Settings:
    host: str
    ports: list[int]  # per route of the session
    time_scale: float = 1.0
    reply_timeout: float = 3.0
    connect_timeout: float = 5.0

    @property
    def late(self) -> float:
        """Seconds after which a reply not come is judged missing."""
        return max(30.0, 4 * self.reply_timeout)


@dataclass
class Result:
    differences: list[Difference] = field(default_factory=list)
    counts: dict[str, int] = field(default_factory=dict)
    telegrams: list[str] = field(default_factory=list)  # the recorded reply telegrams, in order of appearance
    errors: list[str] = field(default_factory=list)  # connections that could not be made
    connected: int = 0  # connections made


class _Run:
    """What the connections of one replay share: their closes, the reader's pace, the findings."""

    def __init__(self, scripts: list[Script], settings: Settings) -> None:
        self.scripts, self.cfg = scripts, settings
        self.loop = asyncio.get_running_loop()
        self.t0 = self.loop.time()
        self.closed = {s.conn: asyncio.Event() for s in scripts}
        self.out = Result()
        self.names: dict[str, None] = {}

    def report(self, diffs: list[Difference]) -> None:
        self.out.differences += diffs


class _Arrivals:
    """The arrival times of a connection's replies: their count, and the last ``ARRIVALS_KEPT`` of them."""

    def __init__(self) -> None:
        self.count = 0
        self.times: deque[float] = deque(maxlen=ARRIVALS_KEPT)

    def add(self, t: float) -> None:
        self.count += 1
        self.times.append(t)

    def __len__(self) -> int:
        return self.count

    def at(self, index: int) -> float:
        """The time of reply ``index`` (0-based), or of the oldest kept."""
        return self.times[max(0, index - (self.count - len(self.times)))]


class _Conn:
    def __init__(self, script: Script, f: SessionFile, t0: float, run: _Run) -> None:
        self.s, self.f, self.run, self.cfg = script, f, run, run.cfg
        self.b = Builder(script, t0)
        self.starving = False  # waiting for a step its reader has not made ready yet
        self.loop = run.loop
        self.out = Outcome(script.conn)
        self.port = self.cfg.ports[script.route]
        self.tap = Tap("reply", script.conn, self.port)
        self.pending: dict[int, deque[Any]] = {}  # identifier -> keys of the requests it may answer
        self.got: dict[Any, Record] = {}  # key -> reply
        self.arrivals = _Arrivals()
        self.changed = asyncio.Event()
        self.eof = False
        self.closing = False
        self.skipped = 0  # replies the recording has and the replay will not (polls a wait did not need)
        self.extended = 0  # replies the replay has and the recording does not (polls past the recorded ones)
        self.last_send = 0.0
        self.opened = 0.0  # when the replay's connection was made
        self.unjudged: dict[int, tuple[Step, float]] = {}  # sent steps (no polls) -> (step, when sent)
        self.waits_open: dict[int, Wait] = {}  # waits sent, not judged
        self.dead: set[Any] = set()  # keys judged missing: a reply that comes for one later is dropped
        self.unsent: Step | None = None  # the first step not sent (the target closed first)

    # ------------------------------------------------------------------ steps from its reader
    async def _reader(self) -> None:
        """This connection's records, from its open on, into its builder; paused while ``AHEAD`` steps are ready
        and not taken (unless the connection waits for one), done at its close."""
        b = self.b
        for n, (_, rec) in enumerate(self.f.records_at(self.s.offset, self.s.conn)):
            before = len(b.ready)
            b.feed(rec)
            if len(b.ready) != before or b.ended:
                self._notify()
            if b.ended:
                break
            if n % BATCH == BATCH - 1:
                await asyncio.sleep(0)
            while len(b.ready) >= AHEAD and not self.starving:
                await self._until(lambda: len(b.ready) < AHEAD or self.starving, float("inf"))
        b.end()
        self._notify()
        for name in b.names:
            self.run.names.setdefault(name, None)
        self.run.out.counts["replies compared"] += b.compared
        self.run.out.counts["waits"] += b.waits

    async def _next(self) -> Step | None:
        """The next step to send, when the reader has it ready; None when the connection's steps are over."""
        if not self.b.ready and not self.b.ended:
            self.starving = True
            self._notify()
            try:
                await self._until(lambda: bool(self.b.ready) or self.b.ended, float("inf"))
            finally:
                self.starving = False
        if not self.b.ready:
            return None
        step = self.b.ready.popleft()
        self._notify()
        return step

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
            self.arrivals.add(rec.time)
            ident = rec.raw[8] if rec.kind == FRAME and len(rec.raw) > 8 else -1
            keys = self.pending.get(ident)
            if keys:
                key = keys.popleft()
                if key not in self.dead:
                    self.got[key] = rec
                self.dead.discard(key)
            else:
                self.out.add_extra(rec)
        if records:
            self._judge_ready()
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
                await asyncio.wait_for(self.changed.wait(), None if left == float("inf") else left)
        return True

    async def _sleep_until(self, when: float) -> None:
        await asyncio.sleep(max(0.0, when - self.loop.time()))

    # ------------------------------------------------------------------ judging as we go
    def _settled(self, step: Step) -> bool:
        """Is the recorded reply of ``step`` known (read, or known never to come)?"""
        return step.reply is not None or not step.answered or self.b.ended

    def _judge_ready(self, final: bool = False) -> None:
        now = self.loop.time()
        for index, (step, sent) in list(self.unjudged.items()):
            got = self.got.get(index)
            late = now - sent > self.cfg.late
            if final or (self._settled(step) and (got is not None or late or not step.answered)):
                if got is None and not final and index in self._pending_keys():
                    self.dead.add(index)
                del self.unjudged[index]
                self.got.pop(index, None)
                self.run.report(judge_step(self.s, step, got))

    def _pending_keys(self) -> set[Any]:
        return {k for keys in self.pending.values() for k in keys}

    def _judge_wait(self, wait: Wait) -> None:
        final = self.out.wait_final.get(wait.id)
        if final is None:
            polls = [("poll", wait.id, n) for n in range(self.out.polls.get(wait.id, 0), 0, -1)]
            final = next((self.got[k] for k in [*polls, *reversed(wait.steps)] if k in self.got), None)
        self.run.report(judge_wait(self.s, wait, final, self.out.polls.get(wait.id, 0)))
        for k in [*wait.steps, *(("poll", wait.id, n) for n in range(1, self.out.polls.get(wait.id, 0) + 1))]:
            if k in self.got:
                del self.got[k]
            elif any(k in keys for keys in self.pending.values()):
                self.dead.add(k)
        self.out.wait_final.pop(wait.id, None)
        self.out.polls.pop(wait.id, None)
        self.s.waits.pop(wait.id, None)
        self.waits_open.pop(wait.id, None)

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
        assert wait.last is not None
        if index > wait.steps[0] and prev is not None and final_matches(wait.last, prev):
            self.out.wait_final[wait.id] = prev
            return True
        return False

    async def _finish_wait(self, wait: Wait, writer: asyncio.StreamWriter, started: float) -> None:
        """After the last recorded poll: poll on at the recorded pace until the final reply comes or time is up."""
        final = wait.last
        assert final is not None
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
        while (step := await self._next()) is not None:
            i = step.index
            due = step.after_replies - self.skipped + self.extended
            await self._until(self._arrived(due), self.cfg.reply_timeout)
            ref = self.last_send
            if 0 < due <= len(self.arrivals):
                ref = max(ref, self.arrivals.at(due - 1))
            not_before = self.opened + (step.at - self.s.start) / scale  # never ahead of its recorded time
            await self._sleep_until(max(ref + step.gap / scale, not_before))
            if self.eof:
                self.unsent = step
                return
            wait = None if step.wait is None else self.s.waits[step.wait]
            if wait is not None and self._wait_done(wait, i):
                self.skipped += 1
                self.out.sent = i + 1
                if i == wait.final:
                    self._judge_wait(wait)
                continue
            if wait is not None:
                wait_started.setdefault(wait.id, self.loop.time())
                self.out.polls[wait.id] = self.out.polls.get(wait.id, 0) + 1
                self.waits_open[wait.id] = wait
            else:
                self.unjudged[i] = (step, self.loop.time())
            self._send(writer, step.raw, step.ident, i, step.answered)
            self.out.sent = i + 1
            if wait is not None and i == wait.final:
                await self._finish_wait(wait, writer, wait_started.pop(wait.id))
                if wait.id in self.out.wait_final:
                    self._judge_wait(wait)
            self._judge_ready()

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

    async def _drain(self) -> None:
        """Take the steps not sent (the target closed first, or no connection), so that the reader goes on."""
        while (step := await self._next()) is not None:
            if self.unsent is None:
                self.unsent = step

    def _finish(self) -> None:
        self._judge_ready(final=True)
        for wait in list(self.waits_open.values()):
            self._judge_wait(wait)
        nxt = self.unsent
        self.run.report(judge_end(self.s, self.out, nxt.label if nxt else "", nxt.at if nxt else 0.0))
        self.run.out.counts["sent"] += self.out.sent

    async def run_conn(self) -> None:
        reading = asyncio.create_task(self._reader())
        try:
            await self._run()
        finally:
            if not reading.done():
                reading.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reading
            self.run.closed[self.s.conn].set()

    async def _run(self) -> None:
        s, cfg = self.s, self.cfg
        for other in closes_first((o for o in self.run.scripts if not self.run.closed[o.conn].is_set()), s):
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self.run.closed[other].wait(), cfg.connect_timeout)
        await self._sleep_until(self.run.t0 + s.start / cfg.time_scale)
        try:
            reader, writer = await asyncio.wait_for(asyncio.open_connection(cfg.host, self.port), cfg.connect_timeout)
        except (OSError, TimeoutError) as exc:
            why = getattr(exc, "strerror", None) or str(exc) or f"no connection within {cfg.connect_timeout:g} s"
            self.out.error = f"cannot connect to {cfg.host}:{self.port}: {why}"
            self.run.out.errors.append(self.out.error)
            await self._drain()
            self.run.report(judge_end(s, self.out))
            return
        self.run.out.connected += 1
        self.last_send = self.opened = self.loop.time()
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
        await self._drain()
        self._finish()


def survey(f: SessionFile) -> tuple[list[Script], float]:
    """The first pass: every connection's summary (SessionError for a line that is not a record)."""
    sv = Survey(f.ports)
    for offset, rec in f.records_at():
        sv.feed(rec, offset)
    return sv.done(), sv.t0 or 0.0


async def replay(f: SessionFile, scripts: list[Script], t0: float, settings: Settings) -> Result:
    """Replay every connection of the session (concurrently, each on its schedule), judging as it goes. A
    connection's task starts ``EARLY`` s before its recorded time (scaled), so that few wait at once."""
    run = _Run(scripts, settings)
    run.out.counts = {"connections": len(scripts), "requests": sum(s.requests for s in scripts), "sent": 0}
    run.out.counts |= {"replies compared": 0, "waits": 0}
    tasks: list[asyncio.Task[None]] = []
    try:
        for s in scripts:  # in the order they opened
            await asyncio.sleep(max(0.0, run.t0 + s.start / settings.time_scale - EARLY - run.loop.time()))
            tasks.append(asyncio.create_task(_Conn(s, f, t0, run).run_conn()))
            if tasks[0].done():  # a connection that failed ends the replay at once (SessionError)
                tasks.pop(0).result()
        await asyncio.gather(*tasks)
    finally:
        for task in tasks:
            task.cancel()
    out = run.out
    out.telegrams = list(run.names)
    return out


def run(f: SessionFile, scripts: list[Script], t0: float, settings: Settings) -> tuple[Result, float]:
    """``replay`` in its own event loop; the result and the seconds it took."""
    start = time.monotonic()
    result = asyncio.run(replay(f, scripts, t0, settings))
    return result, time.monotonic() - start
