"""The replay of a recorded session: what to send when (``Survey``, ``Builder``), and how the replies compare
(``judge_step``, ``judge_wait``, ``judge_end``). Sans-IO: replay_io.py reads the session file, does the sending
and judges each reply as soon as both sides of it are known, so that nothing of a long recording is kept.

Rules:
- A connection is replayed on the route it was recorded on (the order of the session header's routes), as a
  client of its own. It opens at its recorded time (scaled), but never before the connections that had closed
  before it opened in the recording have closed in the replay: on its own port because the target takes one
  client per port (guide 6.1), on the other because both ports drive the same platform (what the one did, the
  other saw). On its own port it also waits for every connection opened before it, unless it was turned away
  while that one was there (``turned_away``): the stamps of two proxy threads do not order them.
- Requests are sent as recorded, byte for byte (malformed ones too), each frame whole. A request waits for the
  replies that had arrived before it in the recording, then for its recorded gap after the later of those
  replies and the previous request, divided by the time scale: a client that waited for a reply still does;
  and never before its recorded time since its connection opened (scaled).
- Replies answer requests by identifier, oldest first (guide 6.1: "returns data only on request").
- A wait is a run of the same request, sent again and again on one connection (a client polling until
  something changes). How many polls see each state depends on timing, so a wait is judged by where it ended:
  its final reply is compared, the polls before it are counted; its rates (velocities) within the most they
  moved between two of the recorded wait's polls (``phase_slack``, erratum E-REP-023), and the table's outcomes
  that changed at its last poll (``awaited``: what the client waited for, E-REP-024) exactly. The replay polls
  at the recorded pace until a reply matches the recorded final one (possibly before the recorded number of
  polls) or, past the recorded number, until twice the wait's recorded duration plus ``WAIT_GRACE`` has passed.
  A run longer than ``WAIT_SPAN`` recorded seconds or ``WAIT_POLLS`` polls is cut into waits of that size (each
  judged by its own final reply): the replay needs a wait's final reply before it sends its first poll, and a
  reader that looks that far ahead is what bounds the replay's memory.
- A watcher (``Script.reads_only``: every request a well-formed query, the telegrams the guide answers) has no
  waits: each poll is sent and judged on its own, and its replies whose values depend on when it asked are
  compared by kind (compare.py ``WATCHED``, erratum E-REP-022).
- Every other reply is compared field by field (compare.py, spec/volatile.yaml). A missing reply, an extra
  one, and a connection the target closes where it did not in the recording (or keeps open where it closed
  it) are differences too; a connection the target closed unanswered (turned away) is not cut short by a close
  that came before its requests went out, and a request still owed its reply when the recorded client closed
  (``Step.cut``) may have it in the replay.
- Memory: a connection's summary (``Survey``, a pass over the file before the replay) is kept for the whole
  replay (a few hundred bytes a connection); steps, replies and waits only until they are judged.
"""

from __future__ import annotations

import itertools
import math
import statistics
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field

from pltf.proxy.compare import diff_telegrams, diff_watched
from pltf.proxy.session import Session
from pltf.proxy.tap import CLOSE, FRAME, OPEN, RAW, Record
from pltf.proxy.view import format_fields
from pltf.spec.codec import FRAME_OVERHEAD
from pltf.spec.jsonio import telegram_to_json
from pltf.spec.volatile import outcomes, rates

WAIT_GRACE = 2.0  # s (wall, unscaled) a wait may poll beyond twice its recorded duration
MIN_WAIT_POLLS = 2  # a run of this many identical requests is a wait
WAIT_SPAN = 30.0  # recorded s: a longer run of polls is cut into waits of this span
WAIT_POLLS = 2000  # ... or of this many polls
KEPT = 50  # replies nobody asked for kept (beyond it they are counted)


@dataclass(eq=False)
class Step:
    """One recorded request: what to send, when, and what came back."""

    raw: bytes
    request: Record
    gap: float  # recorded seconds after the later of the previous request and the replies below
    after_replies: int  # replies this connection had received when it was sent
    answered: bool  # a reply is due (guide 6.1: only requests with a reply table are answered)
    reply: Record | None = None  # the recorded reply (dropped for a poll that is not its wait's final one)
    before: Record | None = None  # a poll's: the recorded reply of the poll before it (kept for the final one)
    slack: dict[str, float] = field(default_factory=dict)  # a poll's: the rates' largest change so far (E-REP-023)
    wait: int | None = None  # the wait it is a poll of
    ident: int = -1  # the telegram identifier (-1: no frame)
    at: float = 0.0  # recorded seconds since the session began
    index: int = 0  # its place among the connection's requests
    superseded: bool = False  # a poll followed by another of its run: its reply is not kept
    cut: bool = False  # still owed its reply when the client (or the recording's end) closed the connection

    @property
    def label(self) -> str:
        t = self.request.telegram
        if t is None:
            return f"malformed request ({len(self.raw)} bytes)"
        fields = format_fields(telegram_to_json(t))
        return f"{t.NAME} {fields}".strip() if len(fields) < 80 else f"{t.NAME} {fields[:77]}..."


@dataclass(eq=False)
class Wait:
    id: int
    steps: list[int]  # indices of its polls in the script
    interval: float  # recorded seconds between polls (median)
    duration: float  # recorded seconds from the first poll to the last reply
    last: Step | None = None  # the final poll
    complete: bool = True  # its final reply is known (or known never to come)

    @property
    def final(self) -> int:
        return self.steps[-1]


@dataclass(eq=False)
class Script:
    """One recorded connection, ready to replay: its summary, and (``plan``) its steps."""

    conn: int
    route: int  # index of the session's route (0: first port, 1: second)
    port: int  # the recorded target port
    start: float  # recorded seconds since the session began
    after_closes: list[int] = field(default_factory=list)  # connections (either port) that must be closed first
    steps: list[Step] = field(default_factory=list)  # plan() only: the replay streams them (Builder)
    waits: dict[int, Wait] = field(default_factory=dict)  # the waits not judged yet
    unsolicited: list[Record] = field(default_factory=list)  # recorded replies no request asked for (KEPT)
    unsolicited_count: int = 0
    closed_by: str = "client"  # who ended it in the recording: client, target (or proxy: as client)
    closed: bool = False  # the recording has its close
    close_gap: float = 0.0  # recorded seconds from its last request or reply to the close
    last_time: float = 0.0
    last_data: float = 0.0  # recorded seconds of its last request or reply (its start when it had none)
    requests: int = 0  # recorded requests
    replied: bool = False  # the recording has a reply on it
    reads_only: bool = True  # every request a well-formed query (a watcher)
    offset: int = 0  # where its open is in the session file (bytes)

    def wait_of(self, index: int) -> Wait | None:
        w = self.steps[index].wait
        return None if w is None else self.waits[w]


@dataclass
class Outcome:
    """What one replayed connection saw (filled in by replay_io)."""

    conn: int
    replies: dict[int, Record] = field(default_factory=dict)  # step index -> its reply
    wait_final: dict[int, Record] = field(default_factory=dict)  # wait id -> the reply the wait ended on
    polls: dict[int, int] = field(default_factory=dict)  # wait id -> polls sent
    extra: list[Record] = field(default_factory=list)  # replies no request asked for, malformed bytes (KEPT)
    extra_count: int = 0
    sent: int = 0  # steps sent
    closed_by_target_after: int | None = None  # steps sent when the target closed (None: it did not)
    error: str | None = None  # the connection could not be made

    def add_extra(self, rec: Record) -> None:
        self.extra_count += 1
        if len(self.extra) < KEPT:
            self.extra.append(rec)


@dataclass(frozen=True)
class Difference:
    telegram: str  # the reply telegram, or "(connection)"
    conn: int
    port: int
    at: float  # recorded seconds since the session began
    request: str
    path: str
    recorded: str
    replayed: str


def _ident(raw: bytes) -> int:
    return raw[FRAME_OVERHEAD] if len(raw) > FRAME_OVERHEAD and raw[:4] == b"\xff\x01\xfe\x02" else -1


def _answered(rec: Record) -> bool:
    return rec.telegram is not None and rec.telegram.DEF.answered


def _closer(detail: str) -> str:
    words = detail.split()
    return "target" if len(words) > 1 and words[1] == "target" else "client"


def _is_data(rec: Record) -> bool:
    return rec.kind in (FRAME, RAW)


# ---------------------------------------------------------------------------------------------- the survey


@dataclass
class _Clock:
    first: float
    last_reply: float
    last_request: float


class Survey:
    """A pass over the session's records: every connection's summary (``Script`` without steps), in the order
    they opened, and the session's first time. What the order of connections needs (when each closed, who closed
    it, whether it was answered) lies in the future of a streamed replay, so it is read first."""

    def __init__(self, ports: list[int]) -> None:
        self.route_of = {p: i for i, p in enumerate(ports)}
        self.scripts: dict[int, Script] = {}
        self.skipped: set[int] = set()  # connections cut short at the start of the file: nothing to replay
        self._clocks: dict[int, _Clock] = {}
        self.t0: float | None = None

    def feed(self, rec: Record, offset: int = 0) -> None:
        """One record; ``offset``: where its line starts in the session file."""
        self.t0 = rec.time if self.t0 is None else min(self.t0, rec.time)
        s = self.scripts.get(rec.conn)
        if s is None:
            if rec.conn in self.skipped or rec.kind != OPEN:
                self.skipped.add(rec.conn)
                return
            s = self.scripts[rec.conn] = Script(rec.conn, self.route_of.get(rec.port, 0), rec.port, rec.time)
            s.offset = offset
            s.last_data = rec.time
            self._clocks[rec.conn] = _Clock(rec.time, rec.time, rec.time)
        clock = self._clocks[rec.conn]
        if _is_data(rec):
            s.last_data = rec.time
            if rec.direction == "request":
                s.requests += 1
                s.reads_only = s.reads_only and _answered(rec)
                clock.last_request = rec.time
            else:
                s.replied = True
                clock.last_reply = rec.time
        elif rec.kind == CLOSE:
            s.closed, s.closed_by = True, _closer(rec.detail)
            s.close_gap = max(0.0, rec.time - max(clock.last_reply, clock.last_request))
        s.last_time = rec.time

    def done(self) -> list[Script]:
        """The scripts with their times relative to the session's first record, in the order they opened."""
        t0 = self.t0 or 0.0
        for s in self.scripts.values():
            s.start, s.last_time, s.last_data = s.start - t0, s.last_time - t0, s.last_data - t0
        self._clocks.clear()
        return sorted(self.scripts.values(), key=lambda s: s.start)


def survey(records: Iterable[Record], ports: list[int]) -> tuple[list[Script], float]:
    sv = Survey(ports)
    for rec in records:
        sv.feed(rec)
    return sv.done(), sv.t0 or 0.0


def closes_first(scripts: Iterable[Script], s: Script) -> list[int]:
    """The connections that must be closed in the replay before ``s`` opens."""
    return [o.conn for o in scripts if o is not s and _closes_before(o, s)]


def _closes_before(o: Script, s: Script) -> bool:
    """Whether ``o`` must be closed in the replay before ``s`` opens: it had closed before ``s`` opened in the
    recording; or it opened first on the same port and ``s`` was not turned away while it was there
    (``turned_away``). The target takes one client per port (guide 6.1: "For each port one client is able to
    connect"), so on one port the connections it served came one after the other, whatever the stamps say: the
    proxy stamps an open on the thread that accepts it and a connection's traffic and close on the thread that
    forwards it, which may wait milliseconds for the interpreter, so a client that closed one connection and
    opened the next at once can find the next one's open stamped first."""
    if o.last_time <= s.start:
        return True
    return o.route == s.route and o.start < s.start and not turned_away(newcomer=s, holder=o)


def turned_away(newcomer: Script, holder: Script) -> bool:
    """``newcomer`` was turned away while ``holder`` had the port (E-WIRE-007): the target closed it unanswered,
    and ``holder`` still talked after that."""
    closed_by_target = newcomer.closed and newcomer.closed_by == "target"
    return closed_by_target and not newcomer.replied and holder.last_data > newcomer.last_time


# ---------------------------------------------------------------------------------------------- the steps


class Builder:
    """One connection's records in (``feed``, ``end``), its steps out in order as each becomes ready to send
    (``ready``): a step when the next request shows it starts no run, a wait when its run is over and its final
    reply is known. ``keep`` also keeps every step and wait in the script (``plan``)."""

    def __init__(self, script: Script, t0: float, keep: bool = False) -> None:
        self.s, self.t0, self.keep = script, t0, keep
        start = script.start + t0
        self.last_reply, self.last_request = start, start
        self.pending: dict[int, deque[Step]] = {}
        self.replies_seen = 0
        self.run: list[Step] = []
        self.closed: deque[Step] = deque()  # steps whose run is over, not yet ready (behind an incomplete wait)
        self.ready: deque[Step] = deque()
        self.ended = False
        self.count = 0
        self.waits = 0  # waits formed
        self.compared = 0  # replies that will be compared (answered steps that are not polls, wait finals)
        self.names: dict[str, None] = {}  # the recorded reply telegrams

    def feed(self, rec: Record) -> None:
        if self.ended:
            return
        if _is_data(rec) and rec.direction == "request":
            self._request(rec)
        elif _is_data(rec):
            self._reply(rec)
        elif rec.kind == CLOSE:
            self.end()

    def _request(self, rec: Record) -> None:
        ref = max(self.last_reply, self.last_request)
        step = Step(rec.raw, rec, rec.time - ref, self.replies_seen, _answered(rec), ident=_ident(rec.raw))
        step.at, step.index = rec.time - self.t0, self.count
        self.count += 1
        self.last_request = rec.time
        if step.answered:
            self.pending.setdefault(step.ident, deque()).append(step)
        if self.keep:
            self.s.steps.append(step)
        if self._joins_run(step):
            prev = self.run[-1]
            prev.superseded = True
            step.slack = _widest(prev.slack, _moved(prev.before, prev.reply))
            step.before, prev.reply, prev.before, prev.slack = prev.reply, None, None, {}
            self.run.append(step)
            return
        self._close_run()
        self.run = [step]

    def _joins_run(self, step: Step) -> bool:
        if self.s.reads_only or not self.run or not step.answered or step.raw != self.run[0].raw:
            return False
        return len(self.run) < WAIT_POLLS and step.request.time - self.run[0].request.time <= WAIT_SPAN

    def _reply(self, rec: Record) -> None:
        self.replies_seen += 1
        self.last_reply = rec.time
        waiting = self.pending.get(_ident(rec.raw))
        if not waiting:
            self.s.unsolicited_count += 1
            if len(self.s.unsolicited) < KEPT:
                self.s.unsolicited.append(rec)
            return
        step = waiting.popleft()
        if rec.telegram is not None:
            self.names[rec.telegram.NAME] = None
        if not step.superseded:
            step.reply = rec
        self._release()

    def _close_run(self) -> None:
        run, self.run = self.run, []
        if len(run) >= MIN_WAIT_POLLS and run[0].answered:
            times = [st.request.time for st in run]
            wait = Wait(
                self.waits,
                [st.index for st in run],
                statistics.median([b - a for a, b in itertools.pairwise(times)]),
                0.0,
                last=run[-1],
                complete=False,
            )
            self.waits += 1
            self.s.waits[wait.id] = wait
            for st in run:
                st.wait = wait.id
            self.compared += 1
        else:
            self.compared += sum(st.answered for st in run)
        self.closed.extend(run)
        self._release()

    def _release(self) -> None:
        while self.closed:
            head = self.closed[0]
            wait = None if head.wait is None else self.s.waits.get(head.wait)
            if wait is not None and not wait.complete:
                last = wait.last
                assert last is not None
                if last.reply is None and not self.ended:
                    return
                end = last.reply.time if last.reply is not None else last.request.time
                wait.duration = end - self.closed[0].request.time
                wait.complete = True
            self.ready.append(self.closed.popleft())

    def end(self) -> None:
        """The connection's close (or the end of the file): what is left is ready."""
        if self.ended:
            return
        self._close_run()
        self.ended = True
        self._release()
        if self.s.closed_by != "target":
            for waiting in self.pending.values():
                for step in waiting:
                    step.cut = True
        self.pending.clear()


def plan(session: Session) -> list[Script]:
    """The session's connections as scripts with all their steps, in the order they opened (in memory: for
    tests and short sessions; ``pltf replay`` streams, replay_io.py)."""
    scripts, t0 = survey(session.records, session.ports)
    builders = {s.conn: Builder(s, t0, keep=True) for s in scripts}
    for rec in session.records:
        b = builders.get(rec.conn)
        if b is not None:
            b.feed(rec)
    for b in builders.values():
        b.end()
    for s in scripts:
        s.after_closes = closes_first(scripts, s)
    return scripts


def phase_slack(step: Step) -> dict[str, float]:
    """A wait's final poll: the largest change of each rate field (spec/volatile.yaml ``rates``: velocities)
    between two consecutive polls of the recorded wait. A replayed poll falls elsewhere in the platform's motion
    than the recorded one did (up to a poll's period earlier or later), so at the wait's end a velocity may be
    off by what one period can change it (erratum E-REP-023: the soak's patrol reports its target reached while
    still turning at 48-49 mrad/s, one 50 ms poll later at rest; a poll before, at 15 or 519)."""
    return _widest(step.slack, _moved(step.before, step.reply))


def awaited(step: Step) -> frozenset[str]:
    """A wait's final poll: the table's ``outcomes`` (ignored fields that say how a command ended) that changed
    from the recorded poll before it to the final one - what the client waited for (target_reached going to 1,
    erratum E-REP-024). The replayed wait ends only when they match, and its final reply is judged on them."""
    a, b = step.before, step.reply
    if a is None or b is None or a.telegram is None or b.telegram is None or a.telegram.NAME != b.telegram.NAME:
        return frozenset()
    fa, fb = telegram_to_json(a.telegram)["fields"], telegram_to_json(b.telegram)["fields"]
    return frozenset(f for f in outcomes(b.telegram.NAME) if fa.get(f) != fb.get(f))


def _moved(a: Record | None, b: Record | None) -> dict[str, float]:
    """How far each rate field moved from reply ``a`` to reply ``b`` (empty: not two replies of one kind)."""
    if a is None or b is None or a.telegram is None or b.telegram is None or a.telegram.NAME != b.telegram.NAME:
        return {}
    fa, fb = telegram_to_json(a.telegram)["fields"], telegram_to_json(b.telegram)["fields"]
    return {f: abs(float(fb[f]) - float(fa[f])) for f in rates(b.telegram.NAME) if _numbers(fa.get(f), fb.get(f))}


def _widest(x: dict[str, float], y: dict[str, float]) -> dict[str, float]:
    return {k: max(x.get(k, 0.0), y.get(k, 0.0)) for k in x.keys() | y.keys()}


def _numbers(*xs: object) -> bool:
    return all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in xs)


def final_matches(step: Step, reply: Record) -> bool:
    """Does a replayed poll's reply match the reply the recorded wait ended on (within the volatile table, the
    rates within their ``phase_slack``)?"""
    rec = step.reply
    if rec is None or rec.telegram is None or reply.telegram is None:
        return False
    return not diff_telegrams(rec.telegram, reply.telegram, widen=phase_slack(step), exact=awaited(step))


# ---------------------------------------------------------------------------------------------- judgement


def _describe(rec: Record | None) -> str:
    if rec is None:
        return "no reply"
    if rec.telegram is None:
        return f"malformed: {rec.error}"
    return rec.telegram.NAME


def _compare(
    script: Script,
    step: Step,
    got: Record | None,
    note: str = "",
    watched: bool = False,
    widen: dict[str, float] | None = None,
    exact: frozenset[str] = frozenset(),
) -> list[Difference]:
    rec = step.reply
    name = (
        rec.telegram.NAME
        if rec is not None and rec.telegram is not None
        else (step.request.telegram.NAME if step.request.telegram is not None else "(malformed)")
    )

    def d(path: str, a: str, b: str) -> Difference:
        return Difference(name, script.conn, script.port, step.at, step.label + note, path, a, b)

    if rec is None and got is None:
        return []
    if rec is None or got is None or rec.telegram is None or got.telegram is None:
        if rec is not None and got is not None and rec.telegram is None and got.telegram is None:
            same = (rec.error or "").split(":")[0] == (got.error or "").split(":")[0]
            return [] if same else [d("(reply)", _describe(rec), _describe(got))]
        return [d("(reply)", _describe(rec), _describe(got))]
    if script.reads_only or watched:
        found = diff_watched(rec.telegram, got.telegram)
    else:
        found = diff_telegrams(rec.telegram, got.telegram, widen=widen, exact=exact)
    return [d(f.path, f.recorded, f.replayed) for f in found]


def judge_step(script: Script, step: Step, got: Record | None) -> list[Difference]:
    """A sent request that is no poll of a wait, against the reply the replay got for it (None: none). A request
    the recording has no reply for because its client closed first (``Step.cut``) may have one in the replay
    (whose client reads what it is owed before it closes): judged by its kind."""
    if step.cut and step.reply is None and (got is None or got.name == step.request.name):
        return []
    if step.answered or step.reply is not None or got is not None:
        return _compare(script, step, got)
    return []


def judge_wait(script: Script, wait: Wait, final: Record | None, polls: int) -> list[Difference]:
    """A wait by the reply it ended on in the replay; a wait the client's end cut (``cut_by_end``), and one whose
    final poll was still owed its reply when the recording (or its client) ended, by kind."""
    assert wait.last is not None
    last = wait.last
    if last.cut and last.reply is None and (final is None or final.name == last.request.name):
        return []  # the recording ended (or its client closed) before the final poll's reply: as judge_step
    cut = cut_by_end(script, wait)
    what = "the connection's end cut it with the platform moving" if cut else "its final reply"
    note = f" (a wait: {len(wait.steps)} polls recorded, {polls} replayed; {what})"
    return _compare(script, last, final, note, watched=cut, widen=phase_slack(last), exact=awaited(last))


MOTION = ("vel_trans", "vel_rot")  # fields of a reply that say the platform is moving


def cut_by_end(script: Script, wait: Wait) -> bool:
    """Was ``wait`` cut by its client's end rather than ended by a state reached? It is the connection's last
    request and its final recorded reply shows the platform moving (a velocity not 0): the client stopped while
    the platform drove (the soak stops its patrol mid-drive), so where the platform was then is a matter of
    timing; judged like a watcher's reply (compare.py ``WATCHED``). A wait that ends with the platform at rest,
    or that more requests follow, is judged field by field."""
    rec = None if wait.last is None else wait.last.reply
    if wait.final != script.requests - 1 or rec is None or rec.telegram is None:
        return False
    values = telegram_to_json(rec.telegram)["fields"]
    return any(values.get(name) not in (None, 0, 0.0) for name in MOTION)


def _conn_diff(s: Script, path: str, a: str, b: str, when: float | None = None) -> Difference:
    return Difference("(connection)", s.conn, s.port, s.start if when is None else when, f"connection #{s.conn}",
                      path, a, b)  # fmt: skip


def judge_end(script: Script, o: Outcome, next_label: str = "", next_at: float = 0.0) -> list[Difference]:
    """How the connection went as a whole: cut short, replies nobody asked for, who ended it. ``next_label`` and
    ``next_at``: the first request not sent (when the target closed before all were)."""
    s, out = script, []
    if o.error is not None:
        return [_conn_diff(s, "connect", "connected", o.error)]
    if o.sent < s.requests and not (_turned_away(s) and o.closed_by_target_after is not None):
        what = f"{o.sent} sent: the target closed the connection before {next_label}"
        out.append(_conn_diff(s, "requests", f"{s.requests} sent", what, when=next_at))
    if o.extra_count != s.unsolicited_count or any(
        _describe(a) != _describe(b) for a, b in zip(s.unsolicited, o.extra, strict=False)
    ):
        out.append(
            _conn_diff(
                s,
                "replies nobody asked for",
                _list(s.unsolicited, s.unsolicited_count),
                _list(o.extra, o.extra_count),
            )
        )
    target_closed = o.closed_by_target_after is not None
    if s.closed_by == "target" and not target_closed:
        out.append(_conn_diff(s, "end", "closed by the target", "kept open by the target", when=s.last_time))
    elif s.closed_by != "target" and target_closed and o.sent == s.requests:
        out.append(_conn_diff(s, "end", f"closed by the {s.closed_by}", "closed by the target", when=s.last_time))
    return out


def _turned_away(s: Script) -> bool:
    """Closed by the target with no reply in the recording (a newcomer turned away, E-WIRE-007): it is judged by
    being closed by the target unanswered again, not by how many of its requests went out before the close (a
    race between the client's first send and the target's close)."""
    return s.closed and s.closed_by == "target" and not s.replied


def _list(records: list[Record], count: int) -> str:
    shown = ", ".join(map(_describe, records)) or "none"
    return shown if count <= len(records) else f"{shown} and {count - len(records)} more"


def judge(scripts: list[Script], outcomes: dict[int, Outcome]) -> list[Difference]:
    """Every difference of the planned scripts (``plan``) against the outcomes, at once."""
    out: list[Difference] = []
    for s in scripts:
        o = outcomes.get(s.conn, Outcome(s.conn))
        if o.error is not None:
            out += judge_end(s, o)
            continue
        for i, step in enumerate(s.steps[: o.sent]):
            wait = s.wait_of(i)
            if wait is None:
                out += judge_step(s, step, o.replies.get(i))
            elif i == wait.final:
                out += judge_wait(s, wait, o.wait_final.get(wait.id), o.polls.get(wait.id, 0))
        nxt = s.steps[o.sent] if o.sent < len(s.steps) else None
        out += judge_end(s, o, nxt.label if nxt else "", nxt.at if nxt else 0.0)
    return out


def group(differences: list[Difference]) -> dict[str, list[Difference]]:
    """Differences by telegram, telegrams in the order their first difference happened."""
    out: dict[str, list[Difference]] = {}
    for d in sorted(differences, key=lambda d: d.at):
        out.setdefault(d.telegram, []).append(d)
    return out


def counts(scripts: list[Script], outcomes: dict[int, Outcome]) -> dict[str, int]:
    """How much was replayed: connections, requests sent, replies compared, waits."""
    sent = sum(outcomes[s.conn].sent for s in scripts if s.conn in outcomes)
    compared = sum(
        1
        for s in scripts
        for i, st in enumerate(s.steps)
        if st.answered and (st.wait is None or i == s.waits[st.wait].final)
    )
    return {
        "connections": len(scripts),
        "requests": sum(s.requests for s in scripts),
        "sent": sent,
        "replies compared": compared,
        "waits": sum(len(s.waits) for s in scripts),
    }
