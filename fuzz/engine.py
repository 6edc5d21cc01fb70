"""The network campaign: schedule cases, run them in batches or alone, judge each unit, report findings.

Rules:
- A *unit* is what one oracle verdict covers: a *batch* (the cases the strict codec accepts, pipelined on one
  connection and closed by a GET_STATUS ``sync`` whose reply proves all of them were processed; the
  server answers nothing else, erratum E-CMD-013) or a *single* (a case the server should refuse or that
  needs its own delivery: a fresh connection, our write side shut, read until the peer closes).
- Units run in two lanes, one per port (``run_lanes``); behind a small unit already sent, up to three more
  wait connected (pipelining), when the target takes clients back to back (checked at the start and watched
  all along: a unit it turned away runs again alone). ``--lanes 1`` runs one unit at a time, batches on a
  kept connection.
- The oracle after every unit: the unit's own outcome (connect refused = dead, no reply and no close within
  the deadline = hang or stall, replies that do not decode strictly or answer the wrong request = bad reply)
  and the liveness probe, GET_STATUS on the OTHER port within the deadline.
- Before fuzzing in a state, its prelude (``pltf.fuzz.schedule.StatePlan``) drives the target there; the probe's
  status shows whether it got there. Values from every reply go to ``pltf.fuzz.knowledge``.
- A finding is confirmed and delta-debugged against fresh instances when we launch the target
  (``--launch``); against a target we cannot restart it is written as found and the campaign stops when the
  target is gone.
"""

from __future__ import annotations

import collections
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pltf.fuzz import safety
from pltf.fuzz.case import Case
from pltf.fuzz.corpus import Corpus
from pltf.fuzz.findings import FindingWriter
from pltf.fuzz.flight import Flight, fly, step_flights
from pltf.fuzz.knowledge import Knowledge
from pltf.fuzz.launch import Launcher
from pltf.fuzz.prefetch import Prefetcher
from pltf.fuzz.schedule import BIG_CASE, BIG_SHARE, DOCUMENT_RESET, HARVEST, Scheduler, StatePlan
from pltf.fuzz.target import CUT, GET_STATUS, Conn, Outcome, Prober, Session, play, play_on, session_reply_ids
from pltf.fuzz.wire import KEEP
from pltf.spec.codec import REQUESTS

WINDOW = 256  # cases drawn at a time, then run batch-first
BATCH_CASES = 128
BATCH_BYTES = 1 << 18
PIPELINE_BYTES = 1 << 14  # units up to this size may be pipelined on a port (read whole by one recv)
GET_STATUS_ID = REQUESTS.CMD_GET_STATUS.ID
PIPELINE_DEPTH = 4  # units in flight per port: the one the target serves and up to three waiting behind it
BACK_TO_BACK_TRIES = 8  # pairs per port of the start-up check that a target takes clients back to back
RETRY_FLOOR = 50  # pipelined units retried before their share is looked at
WINDOWS_PER_STATE = 4  # windows fuzzed in one (state, mode) before the plan moves on
# Where the case generator runs in a thread (no fork), the main thread, back from a socket wait, can queue
# behind it for milliseconds per unit with the default 5 ms GIL switch interval; a short one keeps it low.
SWITCH_INTERVAL = 0.0002  # s
SAVE_EVERY = 30.0  # s between saves of the corpus progress (a killed run resumes from there)
HISTORY = 64  # sessions kept for a finding that needs more than its last unit
LEAD_IDS = {False: (), True: (GET_STATUS_ID,)}  # the answered ids of a session's lead


DROPPED = (
    "the target closed the connection before answering, after frames the strict codec accepts "
    "(erratum E-WIRE-006: only malformed input closes a connection): an internal error?"
)


class HarnessError(RuntimeError):
    """The fuzzer itself cannot go on (target unreachable at the start, launch failure): exit status 2."""


@dataclass
class Options:
    host: str
    port: int
    second_port: int
    duration: float
    seed: int
    out: Path
    corpus: Path | None = None
    allow_motion: bool = False
    launch: str | None = None
    max_cases: int | None = None
    max_findings: int | None = None
    deadline: float = 2.0
    minimize_seconds: float = 60.0
    probe_every: int = 4  # units between liveness probes (1: after every unit)
    lanes: int = 2  # 2: refused cases run in two lanes, one per port (fuzz.flight); 1: one at a time
    big_share: float = BIG_SHARE  # of the cases over 1 MiB drawn that are kept (fuzz.schedule; 1: natural mix)
    pipeline: bool = True  # a port's next small unit connects while its previous one is in flight (run_lanes)
    command: str = "pltf fuzz"


@dataclass
class Stats:
    started: float = field(default_factory=time.monotonic)
    cases: int = 0
    units: int = 0
    batches: int = 0
    singles: int = 0
    probes: int = 0
    restarts: int = 0
    unexpected_closes: int = 0
    cut_replies: int = 0
    dropped_unsafe: int = 0
    pipelined: int = 0  # lane units connected behind their port's previous unit
    retried: int = 0  # pipelined units run again alone (no reply: perhaps turned away)
    turn_aways: int = 0  # retries that then passed: the target turned a newcomer away (pipelining stopped)
    turned_away: list[str] = field(default_factory=list)  # the cases of the unit that showed it
    duplicates: int = 0
    origins: collections.Counter[str] = field(default_factory=collections.Counter)
    telegrams: set[str] = field(default_factory=set)
    states: set[tuple[str, int | None]] = field(default_factory=set)
    state_targets: int = 0
    findings: list[dict[str, Any]] = field(default_factory=list)
    unconfirmed: list[dict[str, Any]] = field(default_factory=list)

    @property
    def elapsed(self) -> float:
        return time.monotonic() - self.started

    @property
    def rate(self) -> float:
        return self.cases / self.elapsed if self.elapsed > 0 else 0.0


class Campaign:
    def __init__(self, opts: Options, on_tick: Callable[[Stats], None] | None = None) -> None:
        self.o = opts
        self.on_tick = on_tick
        self.stats = Stats()
        self.kb = Knowledge()
        self.plan = StatePlan(opts.allow_motion)
        self.stats.state_targets = len(self.plan.targets)
        self.corpus = Corpus(opts.corpus)
        self.forbidden = safety.forbidden(opts.allow_motion)
        self.sched = Scheduler(opts.seed, self.forbidden, self.kb, self.corpus.load_cases(), opts.big_share)
        self.index = self.corpus.next_index(opts.seed)
        self.launcher = Launcher(opts.launch, opts.host, opts.port, opts.second_port) if opts.launch else None
        self.ports = (opts.port, opts.second_port)
        self.keeper: Conn | None = None
        self.prober: Prober | None = None
        self.history: collections.deque[Session] = collections.deque(maxlen=HISTORY)
        self.prev_unit: list[Session] = []
        self.unprobed: list[Session] = []
        self.units_since_probe = 0
        self.lane_units = 0  # sessions started by run_lanes
        self.lane_probed_at = [0, 0]  # lane_units when each port's last probe-led session started
        self.pipelining = opts.pipeline
        self.preludes = 0
        self.need_prelude = True
        self.prelude_tries = 0
        self.units_here = 0
        self.stop = False
        self.coverage: set[tuple[Any, ...]] = set()
        self.writer = FindingWriter(self, self.corpus.known_findings())
        self.prefetch: Prefetcher | None = None

    # ------------------------------------------------------------------ lifecycle
    def start_target(self) -> None:
        if self.launcher is not None:
            self.ports = self.launcher.start()
        self.prober = Prober(self.o.host, self.ports[1], self.o.deadline)
        verdict = self.prober.probe()
        if verdict is not None:
            raise HarnessError(f"the target does not answer GET_STATUS on {self.o.host}:{self.ports[1]}: {verdict}")
        self._learn_status()
        if self.pipelining and self.o.lanes > 1 and not self._takes_clients_back_to_back():
            self.pipelining = False
            self.stats.turn_aways += 1

    def _takes_clients_back_to_back(self) -> bool:
        """Before pipelining: on each port, a client right behind one that has sent GET_STATUS and left must be
        served too (``BACK_TO_BACK_TRIES`` pairs per port); a target that turns it away is not pipelined."""
        assert self.prober is not None
        if self.prober.release() is not None:
            return False
        for _ in range(BACK_TO_BACK_TRIES):
            for port in self.ports:
                pair = [Flight(self.o.host, port, Session([GET_STATUS], half_close=True), self.o.deadline)
                        for _ in range(2)]  # fmt: skip
                fly(pair)
                if any(len(f.out.replies) != 1 for f in pair):
                    return False
        return True

    def close(self) -> None:
        if self.prefetch is not None:
            self.prefetch.close()
            self.prefetch = None
        self.drop_keeper()
        if self.prober is not None:
            self.prober.close()
        if self.launcher is not None:
            self.launcher.cleanup()

    def run(self) -> int:
        switch = sys.getswitchinterval()
        sys.setswitchinterval(SWITCH_INTERVAL)
        try:
            return self._run()
        finally:
            sys.setswitchinterval(switch)

    def _run(self) -> int:
        if self.prefetch is None:  # forked before any connection of ours is open
            self.prefetch = Prefetcher(self.sched, self.index, WINDOW)
        self.start_target()
        self.stats.started = time.monotonic()  # the rate counts fuzzing, not the target's start-up
        end = time.monotonic() + self.o.duration
        last_tick = last_save = time.monotonic()
        try:
            while not self.stop and time.monotonic() < end:
                if self.o.max_cases is not None and self.stats.cases >= self.o.max_cases:
                    break
                self.step()
                now = time.monotonic()
                if now - last_save > SAVE_EVERY:
                    last_save = now
                    self.corpus.save(self.o.seed, self.index, self.writer.signatures)
                if self.on_tick is not None and now - last_tick > 0.25:
                    last_tick = now
                    self.on_tick(self.stats)
            self.final_probe()
        finally:
            self.stats.dropped_unsafe = self.sched.dropped
            self.corpus.save(self.o.seed, self.index, self.writer.signatures)
            self.close()
            if self.on_tick is not None:
                self.on_tick(self.stats)
        return 1 if self.stats.findings else 0

    # ------------------------------------------------------------------ one window of cases
    def step(self) -> None:
        if self.need_prelude:
            self.run_prelude()
            if self.stop:
                return
        if self.prefetch is None:
            self.prefetch = Prefetcher(self.sched, self.index, WINDOW)
        first, cases = self.prefetch.get()
        if self.o.max_cases is not None:
            cases = cases[: max(1, self.o.max_cases - self.stats.cases)]
        self.index = first + len(cases)
        batches: list[list[Case]] = [[]]
        size = 0
        singles: list[Case] = []
        for c in cases:
            if not _batchable(c):
                singles.append(c)
                continue
            if len(batches[-1]) >= BATCH_CASES or size + c.size > BATCH_BYTES:
                batches.append([])
                size = 0
            batches[-1].append(c)
            size += c.size
        batches = [b for b in batches if b]
        if self.o.lanes > 1:
            self.run_lanes(_interleave(batches, [[c] for c in singles]))
        else:
            for batch in batches:
                if self.stop or self.need_prelude:
                    return
                self.run_batch(batch)
            for c in singles:
                if self.stop or self.need_prelude:
                    return
                self.run_single(c)
        if self.stop or self.need_prelude:
            return
        self.units_here += 1
        if any(c.size > BIG_CASE for c in cases):
            self.need_prelude = True  # its document reset keeps a huge saved document from slowing every LOAD_*
        if self.units_here >= WINDOWS_PER_STATE:
            self.units_here = 0
            self.plan.advance()
            self.need_prelude = True

    def run_prelude(self) -> None:
        target = self.plan.current
        self.preludes += 1
        harvest = HARVEST if self.preludes % 4 == 1 else []  # the GET_* replies change slowly; they are dear
        frames = DOCUMENT_RESET + self.plan.prelude(target) + harvest
        session = Session(frames, sync=True)
        out = self._on_keeper(session)
        if out is None:
            return
        self.need_prelude = False
        status = out.replies[-1] if out.replies else None
        if (
            status is not None
            and status.NAME == "CMD_GET_STATUS"
            and self.plan.matches(target, status.operation_state, status.motion_mode)  # type: ignore[attr-defined]
        ):
            self.plan.reached.add(target)
            self.stats.states.add(target)
            self.prelude_tries = 0
            self.history.clear()
            self.history.append(session)
            return
        self.prelude_tries += 1
        if self.prelude_tries >= 3:
            self.plan.unreachable.add(target)
            self.prelude_tries = 0
            self.plan.advance()
        self.need_prelude = True
        time.sleep(0.01)

    # ------------------------------------------------------------------ units
    def _on_keeper(self, session: Session) -> Outcome | None:
        """Run a sync'ed session on the kept connection; None when a failure was handled."""
        out = Outcome()
        if self.keeper is None:
            try:
                self.keeper = Conn(self.o.host, self.ports[0], self.o.deadline)
            except ConnectionRefusedError:
                self.failure("dead", "connection refused on the fuzzed port", [session], [])
                return None
            except OSError:
                out.closed = True
                self.stats.unexpected_closes += 1
                return out if self._probe_ok([session], []) else None
            self.stats.units += 0
        play_on(self.keeper, session, self.o.deadline, out)
        self.stats.units += 1
        for r in out.replies:
            self.kb.learn(r)
        if out.bad_reply is not None:
            self.drop_keeper()
            self.failure("bad-reply", out.bad_reply, [session], [])
            return None
        if out.timed_out:
            self.drop_keeper()
            self._timed_out([session], [], "no reply to the sync GET_STATUS of a batch")
            return None
        if out.closed:
            self.stats.unexpected_closes += 1
            self.drop_keeper()
            self._dropped([session], [])
            return None
        return out if self._probe_ok([session], []) else None

    def run_batch(self, cases: list[Case]) -> None:
        known = all(c.answered is not None for c in cases)  # batched cases decode whole: their ids concatenate
        answered = [i for c in cases for i in c.answered or ()] if known else None
        session = Session([f for c in cases for f in c.frames], sync=True, answered=answered)
        self.history.append(session)
        out = self._on_keeper(session)
        self.stats.batches += 1
        self._count(cases, "kept" if out is not None and not out.closed else "closed")

    def run_single(self, case: Case) -> None:
        self.drop_keeper()
        answered = list(case.answered) if case.answered is not None else None
        session = Session(
            list(case.frames), case.delivery, half_close=True, sync=case.expect == KEEP, answered=answered
        )
        self.history.append(session)
        out = play(self.o.host, self.ports[0], session, self.o.deadline)
        self.stats.units += 1
        self.stats.singles += 1
        self._count([case], "closed" if out.closed else "open")
        for r in out.replies:
            self.kb.learn(r)
        if out.refused:
            self.failure("dead", "connection refused on the fuzzed port", [session], [case])
        elif out.bad_reply is not None and not self._cut_by_refusal(case, out):
            self.failure("bad-reply", out.bad_reply, [session], [case])
        elif out.timed_out:
            self._timed_out([session], [case], "the connection neither answered nor closed after our end-of-stream")
        elif case.expect == KEEP and len(out.replies) < len(session_reply_ids(session)) + 1:
            self._dropped([session], [case])
        else:
            self._probe_ok([session], [case])

    def run_lanes(self, units: list[list[Case]]) -> None:
        """Units in flight on both ports at once (``pltf.fuzz.flight``). A unit is a single case or a batch (its own
        connection, closed by a GET_STATUS ``sync``; while the target works through it the other port carries
        on). Every ``probe_every`` units a port's next session opens with a GET_STATUS: its reply is the liveness
        probe, on that port, of the units the other port carried before it.

        Pipelining: behind a small unit that is fully sent, its write side shut and that owes no reply but a
        status, the port's next small unit connects at once instead of after the target's close, so the
        target has it waiting the moment it is done (it reads what the previous client sent before it judges
        a newcomer, erratum E-WIRE-007). A target that turns such a newcomer away closes it unread (a reset)
        or leaves a reply owed unanswered: that unit runs again alone, and when it then passes the target
        does not take clients back to back and pipelining stops for the campaign (``turn_aways``)."""
        self.drop_keeper()
        assert self.prober is not None
        verdict = self.prober.release()
        if verdict is not None:
            self.failure(verdict.partition(":")[0], f"liveness probe: {verdict}", self.prev_unit + self.unprobed, [])
            return
        todo: collections.deque[tuple[list[Case], bool]] = collections.deque((u, False) for u in units)
        lanes: list[collections.deque[_InFlight]] = [collections.deque(), collections.deque()]
        probed = [False, False]  # a probe-led session answered on this port since the last rotation
        while True:
            for k in (0, 1):
                while todo and not (self.stop or self.need_prelude) and self._may_start(lanes[k], *todo[0]):
                    unit, alone = todo.popleft()
                    lanes[k].append(self._start(k, lanes[k], unit, alone))
            if not any(lanes):
                return
            if not any(q and q[0].flight.done for q in lanes):
                step_flights([e.flight for q in lanes for e in q if not e.flight.done])
            for k in (0, 1):
                q = lanes[k]
                while q and q[0].flight.done:
                    e = q.popleft()
                    _restart_clocks(q)
                    if e.behind and self._turned_away(e):
                        self.stats.retried += 1
                        todo.appendleft((e.unit, True))
                        if self.stats.retried > RETRY_FLOOR and self.stats.retried * 20 > self.stats.pipelined:
                            self.pipelining = False  # more than 5 % retried: back to back costs more than it saves
                        continue
                    if not self._judge_flight(e.flight, e.unit, e.probe, k, lanes):
                        return
                    if e.alone and self.pipelining and e.owed:
                        self.pipelining = False  # it passed alone: the target turned the newcomer away
                        self.stats.turn_aways += 1
                        # or it failed once, pipelined, and not again alone: shown so that a user can tell
                        self.stats.turned_away = [f"{c.telegram} ({c.origin}{': ' + c.note if c.note else ''})"
                                                  for c in e.unit[:3]]  # fmt: skip
                    if e.probe:
                        probed[k] = True
                        if all(probed):
                            probed = [False, False]
                            self.stats.probes += 2
                            self.prev_unit, self.unprobed = self.unprobed, []

    def _may_start(self, q: collections.deque[_InFlight], unit: list[Case], alone: bool) -> bool:
        """Whether the port of ``q`` takes ``unit`` now: when it is free, or pipelined behind its flights (not a
        slow delivery: waiting behind another, its pieces would reach the target in one)."""
        if not q:
            return True
        if not self.pipelining or alone or len(q) >= PIPELINE_DEPTH or not _whole(unit):
            return False
        f = q[-1].flight
        return (f.connected and not f.sending and f.session.half_close and len(f.data) <= PIPELINE_BYTES
                and all(i == GET_STATUS_ID for i in f.expected))  # fmt: skip

    def _start(self, k: int, q: collections.deque[_InFlight], unit: list[Case], alone: bool) -> _InFlight:
        """Connect and send ``unit`` on port ``k``, behind the flights of ``q``."""
        self.lane_units += 1
        probe = self.lane_units - self.lane_probed_at[k] >= self.o.probe_every and unit[0].delivery.mode == "whole"
        if probe:
            self.lane_probed_at[k] = self.lane_units
        flight = Flight(self.o.host, self.ports[k], _lane_session(unit, probe), self.o.deadline)
        behind = bool(q)
        if behind:
            flight.deadline = q[-1].flight.deadline + flight.budget  # its turn comes after the one before it
            self.stats.pipelined += 1
        self.history.append(flight.session)
        self.unprobed.append(flight.session)
        return _InFlight(flight, unit, probe, behind, alone, _owed(flight, unit, probe))

    def _turned_away(self, e: _InFlight) -> bool:
        """A pipelined unit that got no reply and was reset or owed one: perhaps the target never took it."""
        out = e.flight.out
        return not out.refused and not out.replies and (e.flight.reset or e.owed > 0)

    def _judge_flight(self, f: Flight, unit: list[Case], probe: bool, k: int,
                      lanes: list[collections.deque[_InFlight]]) -> bool:  # fmt: skip
        """The oracle of one finished flight; False when it failed (the port's other flights are run out
        first)."""
        self.stats.units += 1
        batch = _is_batch(unit)
        if batch:
            self.stats.batches += 1
        else:
            self.stats.singles += 1
        out = f.out
        c = unit[0]
        kind = None
        if out.refused:
            kind = "refused"
        elif out.bad_reply is not None and not (not batch and self._cut_by_refusal(c, out)):
            kind = "bad-reply"
        elif out.timed_out:
            kind = "timed-out"
        elif len(out.replies) < _owed(f, unit, probe):
            kind = "dropped"
        self._count(unit, ("kept" if kind is None else "closed") if batch else "closed" if out.closed else "open")
        for r in out.replies:
            self.kb.learn(r)
        if kind is None:
            return True
        others = [e for q in lanes for e in q]
        if others:  # the other flights run out: the probe and the replay need the ports free
            fly([e.flight for e in others])
            for e in others:
                self._count(e.unit, "closed" if e.flight.out.closed else "open")
            for q in lanes:
                q.clear()
        covered = self.prev_unit + self.unprobed
        port = self.ports[k]
        if kind == "refused":
            verdict = self._probe_other(port)
            self.failure((verdict or "dead:").partition(":")[0], "connection refused on a fuzzed port", covered, unit)
        elif kind == "bad-reply":
            self.failure("bad-reply", out.bad_reply or "", covered, unit)
        elif kind == "timed-out":
            what = "the connection neither answered nor closed after our end-of-stream"
            self._timed_out(covered, unit, what, port)
        else:
            self._dropped(covered, unit, port)
        return False

    def _cut_by_refusal(self, case: Case, out: Outcome) -> bool:
        """A reply cut short when the target closed on a malformed case with our input still unread: TCP resets
        such a connection and drops what was in flight. Counted, not a finding (the close itself is right)."""
        if case.expect != KEEP and (out.bad_reply or "").startswith(CUT):
            self.stats.cut_replies += 1
            return True
        return False

    def drop_keeper(self) -> None:
        """Release the kept connection in order: shut our side, wait for the peer's close (frees its slot)."""
        if self.keeper is None:
            return
        keeper, self.keeper = self.keeper, None
        keeper.shut_write()
        keeper.read_replies(None, time.monotonic() + self.o.deadline)
        keeper.close()

    # ------------------------------------------------------------------ oracle
    def _probe_ok(self, sessions: list[Session], cases: list[Case]) -> bool:
        """The liveness probe, pipelined: collect the answer to the probe sent before, send the next one (its
        round trip overlaps the next unit). It runs after every ``probe_every`` units; in between, each unit's
        own outcome is the oracle (a refused connect is a death, a missing close or reply a hang). A failed
        probe covers every unit since the probe before it."""
        assert self.prober is not None
        self.unprobed.extend(sessions)
        self.units_since_probe += 1
        if self.prober.pending:  # sent one unit ago
            verdict = self.prober.collect()
            if verdict is not None:
                kind, _, detail = verdict.partition(": ")
                reasons = {
                    "dead": "the liveness probe on the other port was refused: the target died",
                    "hang": "the liveness probe on the other port got no answer within the deadline",
                    "deaf": "the other port closes every connection without answering GET_STATUS",
                }
                self.failure(kind, reasons.get(kind, f"probe: {detail}"), self.prev_unit + self.unprobed, cases)
                return False
            self._learn_status()
            self.stats.probes += 1
        if self.units_since_probe >= self.o.probe_every:
            self.prev_unit, self.unprobed, self.units_since_probe = self.unprobed, [], 0
            self.prober.send()
        return True

    def final_probe(self) -> None:
        if self.prober is not None and not self.stop:
            self.units_since_probe = self.o.probe_every
            if self._probe_ok([], []) and self.prober.pending:
                self._probe_ok([], [])

    def _probe_other(self, port: int | None) -> str | None:
        """A liveness probe right now on the port other than ``port`` (the fuzzed port when None)."""
        assert self.prober is not None
        if port is None or port == self.ports[0]:
            return self.prober.probe()
        one_off = Prober(self.o.host, self.ports[0], self.o.deadline)
        try:
            return one_off.probe()
        finally:
            one_off.close()

    def _dropped(self, sessions: list[Session], cases: list[Case], port: int | None = None) -> None:
        """A connection closed early on valid input: a death, unless the other port answers right now."""
        verdict = self._probe_other(port)
        if verdict is None:
            self.failure("dropped", DROPPED, self.prev_unit + self.unprobed + sessions, cases)
        else:
            kind = verdict.partition(":")[0]
            self.failure(
                kind, f"{DROPPED}; then the liveness probe: {verdict}", self.prev_unit + self.unprobed + sessions, cases
            )

    def _timed_out(self, sessions: list[Session], cases: list[Case], what: str, port: int | None = None) -> None:
        verdict = self._probe_other(port)
        if verdict is None:
            self.failure("stall", f"{what} within {self.o.deadline} s; the other port still answers", sessions, cases)
        else:
            self.failure(verdict.partition(":")[0], f"{what}; then the liveness probe: {verdict}", sessions, cases)

    def _learn_status(self) -> None:
        if self.prober is not None and self.prober.last_status is not None:
            self.kb.learn(self.prober.last_status)

    def _count(self, cases: list[Case], outcome: str) -> None:
        st = self.stats
        st.cases += len(cases)
        target = self.plan.current
        for c in cases:
            st.origins[c.origin] += 1
            st.telegrams.add(c.telegram)
            key = (target, c.telegram, c.origin, outcome)
            if key not in self.coverage:
                self.coverage.add(key)
                self.corpus.add(c)

    # ------------------------------------------------------------------ findings
    def failure(self, kind: str, reason: str, sessions: list[Session], cases: list[Case]) -> None:
        self.drop_keeper_quietly()
        prelude = Session(self.plan.prelude(self.plan.current), sync=True)
        self.prev_unit, self.unprobed, self.units_since_probe = [], [], 0
        finding = self.writer.handle(kind, reason, prelude, sessions, list(self.history), cases)
        if finding is not None and (finding["confirmed"] or self.launcher is None):
            self.stats.findings.append(finding)
        elif finding is not None:
            self.stats.unconfirmed.append(finding)
        else:
            self.stats.duplicates += 1
        if self.o.max_findings is not None and len(self.stats.findings) >= self.o.max_findings:
            self.stop = True
            return
        if self.launcher is not None:
            self.stats.restarts += 1
            if self.prober is not None:
                self.prober.close()
            self.start_target()
            self.history.clear()
            self.need_prelude = True
        elif kind in ("dead", "hang", "deaf", "stall"):
            self.stop = True  # a target we cannot restart is gone (or its port is)

    def drop_keeper_quietly(self) -> None:
        if self.keeper is not None:
            self.keeper.close()
            self.keeper = None


@dataclass
class _InFlight:
    """A lane unit on its connection."""

    flight: Flight
    unit: list[Case]
    probe: bool  # it opens with the liveness probe's GET_STATUS
    behind: bool  # connected while the port's previous unit was still in flight (pipelined)
    alone: bool  # a retry of a pipelined unit that may have been turned away: never pipelined
    owed: int  # replies the target must send (E-WIRE-006)


def _restart_clocks(q: collections.deque[_InFlight]) -> None:
    """A port's flight is done: the deadline of each one waiting behind it runs from now, in its turn."""
    t = time.monotonic()
    for e in q:
        t += e.flight.budget
        e.flight.deadline = t


def _owed(f: Flight, unit: list[Case], probe: bool) -> int:
    """Replies owed by the target: all of a unit of accepted cases; otherwise only the lead GET_STATUS, even
    before a malformed frame - and past 16 KiB not even that: a close with unread input may reset the connection
    and lose replies in flight (TCP)."""
    if unit[0].expect == KEEP:
        return len(f.expected)
    return 1 if probe and unit[0].size < 1 << 14 else 0


def _whole(unit: list[Case]) -> bool:
    """A small unit written in one piece: one that may wait behind another (pipelining)."""
    return sum(c.size for c in unit) <= PIPELINE_BYTES and all(c.delivery.mode == "whole" for c in unit)


def _batchable(c: Case) -> bool:
    """A case the strict codec accepts, small and written whole: it goes into a batch."""
    return c.expect == KEEP and c.delivery.mode == "whole" and c.size < BATCH_BYTES // 4


def _is_batch(unit: list[Case]) -> bool:
    return len(unit) > 1 or _batchable(unit[0])


def _lane_session(unit: list[Case], probe: bool) -> Session:
    """The session of a lane unit: its frames (after a lead GET_STATUS when it carries the probe), our write
    side shut after them; a unit of accepted cases ends with the ``sync`` GET_STATUS."""
    lead = [GET_STATUS] if probe else []
    known = all(c.answered is not None for c in unit)
    answered = [*LEAD_IDS[probe], *(i for c in unit for i in c.answered or ())] if known else None
    frames = [*lead, *(f for c in unit for f in c.frames)]
    return Session(frames, unit[0].delivery, half_close=True, sync=unit[0].expect == KEEP, answered=answered)


def _interleave(batches: list[list[Case]], singles: list[list[Case]]) -> list[list[Case]]:
    """The batches spread evenly among the singles: while the target works through a batch on one port, the
    other port carries singles."""
    if not batches:
        return singles
    out: list[list[Case]] = []
    step = len(singles) / len(batches)
    for i, batch in enumerate(batches):
        out.extend(singles[round(i * step) : round((i + 1) * step)])
        out.append(batch)
    return out
