"""The replay of a recorded session: what to send when (``plan``), and how the replies compare (``judge``).
Sans-IO: replay_io.py does the sending and hands back an ``Outcome`` per connection.

Rules:
- A connection is replayed on the route it was recorded on (the order of the session header's routes), as a
  client of its own. It opens at its recorded time (scaled), but never before the connections that had closed
  before it opened in the recording have closed in the replay: on its own port because the target takes one
  client per port (guide 6.1), on the other because both ports drive the same platform (what the one did, the
  other saw). On its own port it also waits for every connection opened before it, unless it was turned away
  while that one was there (``turned_away``): the stamps of two proxy threads do not order them.
- Requests are sent as recorded, byte for byte (malformed ones too), each frame whole. A request waits for the
  replies that had arrived before it in the recording, then for its recorded gap after the later of those
  replies and the previous request, divided by the time scale: a client that waited for a reply still does.
- Replies answer requests by identifier, oldest first (guide 6.1: "returns data only on request").
- A wait is a run of the same request, sent again and again on one connection (a client polling until
  something changes). How many polls see each state depends on timing, so a wait is judged by where it ended:
  its final reply is compared, the polls before it are counted. The replay polls at the recorded pace until a
  reply matches the recorded final one (possibly before the recorded number of polls) or, past the recorded
  number, until twice the wait's recorded duration plus ``WAIT_GRACE`` has passed.
- Every other reply is compared field by field (compare.py, spec/volatile.yaml). A missing reply, an extra
  one, and a connection the target closes where it did not in the recording (or keeps open where it closed
  it) are differences too.
"""

from __future__ import annotations

import itertools
import statistics
from dataclasses import dataclass, field

from pltf.proxy.compare import diff_telegrams
from pltf.proxy.session import Session
from pltf.proxy.tap import CLOSE, FRAME, OPEN, RAW, Record
from pltf.proxy.view import format_fields
from pltf.spec.codec import FRAME_OVERHEAD
from pltf.spec.jsonio import telegram_to_json

WAIT_GRACE = 2.0  # s (wall, unscaled) a wait may poll beyond twice its recorded duration
MIN_WAIT_POLLS = 2  # a run of this many identical requests is a wait


@dataclass
class Step:
    """One recorded request: what to send, when, and what came back."""

    raw: bytes
    request: Record
    gap: float  # recorded seconds after the later of the previous request and the replies below
    after_replies: int  # replies this connection had received when it was sent
    answered: bool  # a reply is due (guide 6.1: only requests with a reply table are answered)
    reply: Record | None = None  # the recorded reply
    wait: int | None = None  # the wait it is a poll of
    ident: int = -1  # the telegram identifier (-1: no frame)
    at: float = 0.0  # recorded seconds since the session began

    @property
    def label(self) -> str:
        t = self.request.telegram
        if t is None:
            return f"malformed request ({len(self.raw)} bytes)"
        fields = format_fields(telegram_to_json(t))
        return f"{t.NAME} {fields}".strip() if len(fields) < 80 else f"{t.NAME} {fields[:77]}..."


@dataclass
class Wait:
    id: int
    steps: list[int]  # indices of its polls in the script
    interval: float  # recorded seconds between polls (median)
    duration: float  # recorded seconds from the first poll to the last reply

    @property
    def final(self) -> int:
        return self.steps[-1]


@dataclass
class Script:
    """One recorded connection, ready to replay."""

    conn: int
    route: int  # index of the session's route (0: first port, 1: second)
    port: int  # the recorded target port
    start: float  # recorded seconds since the session began
    after_closes: list[int] = field(default_factory=list)  # connections (either port) that must be closed first
    steps: list[Step] = field(default_factory=list)
    waits: dict[int, Wait] = field(default_factory=dict)
    unsolicited: list[Record] = field(default_factory=list)  # recorded replies no request asked for
    closed_by: str = "client"  # who ended it in the recording: client, target (or proxy: as client)
    closed: bool = False  # the recording has its close
    close_gap: float = 0.0  # recorded seconds from its last request or reply to the close
    last_time: float = 0.0
    last_data: float = 0.0  # recorded seconds of its last request or reply (its start when it had none)

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
    extra: list[Record] = field(default_factory=list)  # replies no request asked for, malformed bytes
    sent: int = 0  # steps sent
    closed_by_target_after: int | None = None  # steps sent when the target closed (None: it did not)
    error: str | None = None  # the connection could not be made


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


def _script(conn: int, records: list[Record], route: int, t0: float) -> Script:
    first = records[0]
    script = Script(conn, route, first.port, first.time - t0, last_data=first.time - t0)
    pending: dict[int, list[int]] = {}
    replies_seen, last_reply_time, last_request_time = 0, first.time, first.time
    for rec in records:
        if rec.kind in (FRAME, RAW):
            script.last_data = rec.time - t0
        if rec.kind in (FRAME, RAW) and rec.direction == "request":
            ident = _ident(rec.raw)
            ref = max(last_reply_time, last_request_time)
            step = Step(rec.raw, rec, rec.time - ref, replies_seen, _answered(rec), ident=ident, at=rec.time - t0)
            if step.answered:
                pending.setdefault(ident, []).append(len(script.steps))
            script.steps.append(step)
            last_request_time = rec.time
        elif rec.kind in (FRAME, RAW) and rec.direction == "reply":
            replies_seen += 1
            last_reply_time = rec.time
            waiting = pending.get(_ident(rec.raw))
            if waiting:
                script.steps[waiting.pop(0)].reply = rec
            else:
                script.unsolicited.append(rec)
        elif rec.kind == CLOSE:
            script.closed, script.closed_by = True, _closer(rec.detail)
            script.close_gap = max(0.0, rec.time - max(last_reply_time, last_request_time))
        script.last_time = rec.time - t0
    _find_waits(script)
    return script


def _find_waits(script: Script) -> None:
    steps, k = script.steps, 0
    while k < len(steps):
        end = k
        while end + 1 < len(steps) and steps[end + 1].raw == steps[k].raw:
            end += 1
        run = list(range(k, end + 1))
        if len(run) >= MIN_WAIT_POLLS and steps[k].answered:
            wid = len(script.waits)
            times = [steps[i].request.time for i in run]
            last = steps[run[-1]].reply
            duration = (last.time if last is not None else times[-1]) - times[0]
            gaps = [b - a for a, b in itertools.pairwise(times)]
            script.waits[wid] = Wait(wid, run, statistics.median(gaps), duration)
            for i in run:
                steps[i].wait = wid
        k = end + 1


def plan(session: Session) -> list[Script]:
    """The session's connections as scripts, in the order they opened."""
    by_conn: dict[int, list[Record]] = {}
    for rec in session.records:
        by_conn.setdefault(rec.conn, []).append(rec)
    route_of = {p: i for i, p in enumerate(session.ports)}
    t0 = min((r.time for r in session.records), default=session.started)
    scripts = []
    for conn, records in by_conn.items():
        if records[0].kind != OPEN:
            continue  # a connection cut short at the start of the file: nothing to replay it from
        scripts.append(_script(conn, records, route_of.get(records[0].port, 0), t0))
    scripts.sort(key=lambda s: s.start)
    for s in scripts:
        s.after_closes = [o.conn for o in scripts if o is not s and _closes_before(o, s)]
    return scripts


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
    unanswered = not newcomer.unsolicited and all(step.reply is None for step in newcomer.steps)
    closed_by_target = newcomer.closed and newcomer.closed_by == "target"
    return closed_by_target and unanswered and holder.last_data > newcomer.last_time


def final_matches(step: Step, reply: Record) -> bool:
    """Does a replayed poll's reply match the reply the recorded wait ended on (within the volatile table)?"""
    rec = step.reply
    if rec is None or rec.telegram is None or reply.telegram is None:
        return False
    return not diff_telegrams(rec.telegram, reply.telegram)


# ---------------------------------------------------------------------------------------------- judgement


def _describe(rec: Record | None) -> str:
    if rec is None:
        return "no reply"
    if rec.telegram is None:
        return f"malformed: {rec.error}"
    return rec.telegram.NAME


def _compare(script: Script, step: Step, got: Record | None, note: str = "") -> list[Difference]:
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
    return [d(f.path, f.recorded, f.replayed) for f in diff_telegrams(rec.telegram, got.telegram)]


def judge(scripts: list[Script], outcomes: dict[int, Outcome]) -> list[Difference]:
    out: list[Difference] = []
    for s in scripts:
        o = outcomes.get(s.conn, Outcome(s.conn))
        at = s.start

        def conn_diff(path: str, a: str, b: str, script: Script = s, when: float = at) -> Difference:
            return Difference("(connection)", script.conn, script.port, when, f"connection #{script.conn}", path, a, b)

        if o.error is not None:
            out.append(conn_diff("connect", "connected", o.error))
            continue
        for i, step in enumerate(s.steps[: o.sent]):
            wait = s.wait_of(i)
            if wait is not None:
                if i == wait.final:
                    polls = o.polls.get(wait.id, 0)
                    out += _compare(
                        s,
                        step,
                        o.wait_final.get(wait.id),
                        f" (a wait: {len(wait.steps)} polls recorded, {polls} replayed; its final reply)",
                    )
                continue
            if step.answered or step.reply is not None or i in o.replies:
                out += _compare(s, step, o.replies.get(i))
        if o.sent < len(s.steps):
            step = s.steps[o.sent]
            out.append(
                conn_diff(
                    "requests",
                    f"{len(s.steps)} sent",
                    f"{o.sent} sent: the target closed the connection before {step.label}",
                    when=step.at,
                )
            )
        if len(o.extra) != len(s.unsolicited) or any(
            _describe(a) != _describe(b) for a, b in zip(s.unsolicited, o.extra, strict=False)
        ):
            out.append(
                conn_diff(
                    "replies nobody asked for",
                    ", ".join(map(_describe, s.unsolicited)) or "none",
                    ", ".join(map(_describe, o.extra)) or "none",
                )
            )
        target_closed = o.closed_by_target_after is not None
        if s.closed_by == "target" and not target_closed:
            out.append(conn_diff("end", "closed by the target", "kept open by the target", when=s.last_time))
        elif s.closed_by != "target" and target_closed and o.sent == len(s.steps):
            out.append(conn_diff("end", f"closed by the {s.closed_by}", "closed by the target", when=s.last_time))
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
        "requests": sum(len(s.steps) for s in scripts),
        "sent": sent,
        "replies compared": compared,
        "waits": sum(len(s.waits) for s in scripts),
    }
