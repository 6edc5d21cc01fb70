"""The network campaign: draw cases, group them into units, run them in the lanes, believe only what happens
again, report findings.

Rules:
- The parts, each with its own rules: ``pltf.fuzz.unit`` (what one verdict covers and the session carrying it),
  ``pltf.fuzz.preludes`` (the state a unit is fuzzed in), ``pltf.fuzz.lanes`` and ``pltf.fuzz.gate`` (ports,
  pipelining, newcomers turned away), ``pltf.fuzz.verdict`` (the oracle), ``pltf.fuzz.findings`` (fresh
  targets, minimisation, the files).
- A window of cases (``WINDOW``) becomes batches and singles; the first batch carries the state prelude, and so
  does one single in ``STATEFUL_EVERY`` about an operation or motion command. On a target whose connections are dear
  (``pltf.fuzz.gate``) the units of accepted cases run on a kept connection, and the cases a window brings that
  need a fresh connection (the target should close on them) beyond ``SINGLES_QUEUE`` waiting are skipped
  (counted, before units are built for them): fresh connections are what such a target has least of. Those kept
  are the ones whose telegram ran least so far (``pltf.fuzz.unit.rarest_cases``): every id comes round. Where the
  target turns nobody away the dear way is paced (its batches take turns with the singles, ``pltf.fuzz.pace``),
  tried against fresh connections and kept only when it is faster and gives up few singles (``pltf.fuzz.trial``).
- A suspicion (``pltf.fuzz.verdict``) stops the lanes; once the ports are free its unit is replayed alone: a
  finding when it fails again the same way, else reported apart as unconfirmed (``stats.unconfirmed``), which
  never sets the exit status. A unit that timed out is a stall when another port still serves us, else a hang;
  a stall is replayed once, on the port that serves, with ``pltf.fuzz.verdict.STALL_PATIENCE`` times the deadline.
- When no port serves us any more (``Lanes.gone``) the target is dead (or hung, or deaf): one finding names the
  units sent last; with ``--launch`` it is reproduced and minimised against fresh instances, the target
  restarted and the campaign goes on, without it the campaign stops.
"""

from __future__ import annotations

import collections
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pltf.fuzz import preludes, profile, safety
from pltf.fuzz.case import Case
from pltf.fuzz.corpus import Corpus
from pltf.fuzz.findings import AtFailure, FindingContext, FindingWriter
from pltf.fuzz.knowledge import Knowledge
from pltf.fuzz.lanes import DONE, STOPPED, InFlight, Lanes
from pltf.fuzz.options import Options, Stats
from pltf.fuzz.pace import Pace
from pltf.fuzz.prefetch import Prefetcher
from pltf.fuzz.preludes import STATEFUL, StatePlan
from pltf.fuzz.schedule import BIG_CASE, Scheduler
from pltf.fuzz.trial import Trial
from pltf.fuzz.unit import Unit, rarest_cases, window_units
from pltf.fuzz.verdict import HOW, NEEDED, REPLAYS, TIMED_OUT, Verdict, confirm, confirmed, patient
from pltf.fuzz.wire import KEEP
from pltf.harness.launch import Launcher

WINDOW = 256  # cases drawn at a time
MEASURE = 6  # status-only clients per port at the start: does it answer, what does a connection cost
SINGLES_QUEUE = 32  # singles waiting at most on a dear target (the rest of a window's are skipped)
STATEFUL_EVERY = 4  # one single about an operation or motion command in so many carries the state prelude
# Where the case generator runs in a thread (no fork), the main thread, back from a socket wait, can queue
# behind it for milliseconds per unit with the default 5 ms GIL switch interval; a short one keeps it low.
SWITCH_INTERVAL = 0.0002  # s
SAVE_EVERY = 30.0  # s between saves of the corpus progress (a killed run resumes from there)
TARGET_LINES = 6  # lines of a launched target's output in a message about its start
STOPS = ("dead", "hang", "deaf", "stall")  # without --launch, the campaign ends with such a finding


class HarnessError(RuntimeError):
    """The fuzzer itself cannot go on (target unreachable at the start, launch failure): exit status 2."""


@dataclass
class Suspicion:
    unit: Unit
    port: int
    verdict: Verdict
    exchange: dict[str, Any]  # what the campaign's connection carried (``exchange``): the replays cannot show it


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
        self.lanes: Lanes | None = None
        self.suspicions: list[Suspicion] = []
        self.not_admitted_before = 0  # connections not served by the targets before the last restart
        self.stateful = 0  # singles about an operation or motion command drawn so far
        self.single_telegrams: collections.Counter[str] = collections.Counter()  # singles queued on a dear target
        self.stop = False
        self.coverage: set[tuple[Any, ...]] = set()
        self.writer = FindingWriter(FindingContext.of(opts, self.launcher), self.corpus.known_findings())
        self.prefetch: Prefetcher | None = None
        self.trial = Trial()  # fresh connections or the dear way, measured (kept across restarts)
        self.profile: profile.Profile | None = None  # learnt at the first start (``pltf.fuzz.profile``)

    # ------------------------------------------------------------------ lifecycle
    def start_target(self) -> None:
        if self.launcher is not None:
            self.ports = self.launcher.start()
        if self.lanes is not None:
            self.not_admitted_before += sum(g.turn_aways for g in self.lanes.gates)
        pipelining = self.o.pipeline and self.o.lanes > 1
        self.lanes = lanes = Lanes(
            self.o.host, self.ports, self.o.deadline, pipelining, active=self.o.lanes, lead_every=self.o.probe_every
        )
        if self.profile is None:  # learnt once: a restarted instance is the same implementation
            try:
                self.profile = profile.learn(self.o.host, self.ports[0], self._flag(0), self.o.deadline)
            except profile.ProfileError as exc:
                raise HarnessError(f"{exc}{self._target_said()}") from None
            self.stats.profile = self.profile.to_json()
        lanes.adapt = self.profile.adapt
        lanes.fin_waits, lanes.frames_as_is = self.profile.fin_waits, not self.profile.silent_before_connect
        if self.profile.small_backlog:  # SYNs past the backlog are dropped: a pipelined connect would wait seconds
            for gate in lanes.gates:
                gate.pipelining = False
        status = Unit([], [])
        for k in range(len(self.ports)):
            for _ in range(MEASURE if k < self.o.lanes else 1):
                e = lanes.alone(k, status)
                if e is None or e.verdict is None or e.verdict.suspicious or not e.flight.out.replies:
                    raise HarnessError(self._unanswered(k, e) + self._target_said())
                self._learn(e.flight.out.replies)
        if self.o.lanes < 2 or self.profile.slow_setup or any(g.dear for g in lanes.gates[: self.o.lanes]):
            self.trial.settle(self.o.lanes > 1)  # one lane has no other port for the fresh connections
        lanes.dear = self.trial.way()
        lanes.pace = None if self.trial.settled else Pace()
        self._gate_stats()

    def _target_said(self) -> str:
        """The last lines a launched target wrote (for a message about its start), or nothing."""
        lines = list(self.launcher.output)[-TARGET_LINES:] if self.launcher is not None else []
        return f"; the target's last lines: {' | '.join(lines)}" if lines else ""

    def _flag(self, k: int) -> str:
        """The option that named port ``k`` (for messages)."""
        if self.launcher is not None:
            return f"the {'first' if k == 0 else 'second'} port --launch's target reported"
        return "--target" if k == 0 else "--second-port"

    def _unanswered(self, k: int, e: InFlight | None) -> str:
        """What the start saw on port ``k``: the port, the flag that named it, what the target did."""
        assert self.lanes is not None
        where = f"{self.o.host}:{self.ports[k]} ({self._flag(k)})"
        if e is not None and e.verdict is not None and e.verdict.reason:
            seen = e.verdict.reason
        elif e is not None:
            seen = "no reply"
        else:
            how = self.lanes.live.failing.get(k, "timed-out")
            if how == "refused":
                return f"nothing listening on {where}: connection refused each time for {self.lanes.patience:g} s"
            seen = f"{HOW[how]} each time for {self.lanes.patience:g} s"
        return f"the target does not answer on {where}: connected, sent CMD_GET_POSITION, {seen}"

    def _gate_stats(self) -> None:
        assert self.lanes is not None
        st, gates = self.stats, self.lanes.gates
        st.release_ms = [round(g.release * 1000, 3) for g in gates]
        st.dear = self.lanes.dear
        st.ways = {k: round(v, 1) for k, v in self.trial.rates.items()} if self.trial.seen else {}
        st.pipelined = sum(g.pipelined for g in gates)
        st.turn_aways = sum(1 for g in gates if not g.pipelining and g.pipelined)
        st.turned_away = self.lanes.turned_away
        st.not_admitted = sum(g.turn_aways for g in gates) + self.not_admitted_before

    def close(self) -> None:
        if self.prefetch is not None:
            self.prefetch.close()
            self.prefetch = None
        if self.lanes is not None:
            self.lanes.close()
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
            self.finish()
        finally:
            self.stats.dropped_unsafe = self.sched.dropped
            self.corpus.save(self.o.seed, self.index, self.writer.signatures)
            self.close()
            if self.on_tick is not None:
                self.on_tick(self.stats)
        return 1 if self.stats.findings else 0

    def finish(self) -> None:
        """The units in flight run out and are judged; what is still queued is not run."""
        if self.lanes is None or self.stop:
            return
        self.lanes.clear_queue()
        self._lanes_run(batches_only=False)

    # ------------------------------------------------------------------ one window of cases
    def step(self) -> None:
        assert self.lanes is not None and self.prefetch is not None
        first, cases = self.prefetch.get()
        if self.o.max_cases is not None:
            cases = cases[: max(1, self.o.max_cases - self.stats.cases)]
        self.index = first + len(cases)
        self.lanes.add(self.units(cases, self._choose_singles if self.lanes.dear else None))
        t0, served, singles, dear = time.monotonic(), self.stats.cases, self.stats.singles, self.lanes.dear
        self._lanes_run(batches_only=dear and self.trial.next_way())  # a trial's ways are not mixed
        if not self.stop:
            self.plan.window_done(any(c.size > BIG_CASE for c in cases))
            if self.o.lanes > 1 and any(g.dear for g in self.lanes.gates):
                self.trial.settle(True)  # turn-aways began late (a target that is slow to free a port)
                self.lanes.pace = None
            st = self.stats
            self.trial.record(dear, st.cases - served, time.monotonic() - t0, singles=st.singles - singles)
            self._way(self.trial.way())
        self._gate_stats()

    def _choose_singles(self, singles: list[Case], batches: list[list[Case]]) -> list[Case]:
        """On the dear way: the singles' cases that run, before units are built for them - those that need a fresh
        connection beyond the room left (``_singles_queue``) are skipped (counted), the rarest telegrams kept."""
        assert self.lanes is not None
        kept = [len(b) for b in batches] + [1 for c in singles if c.expect == KEEP]  # the kept connection's units
        room = max(0, self._singles_queue(kept) - self.lanes.fresh_waiting())
        fresh = [c for c in singles if c.expect != KEEP]
        chosen = rarest_cases(fresh, room, self.single_telegrams)
        if len(chosen) == len(fresh):
            return singles
        run = {id(c) for c in chosen}
        out = [c for c in singles if c.expect == KEEP or id(c) in run]
        self.stats.skipped += len(singles) - len(out)
        return out

    def _singles_queue(self, batches: list[int]) -> int:
        """Singles that may wait on the dear way: ``SINGLES_QUEUE``, or, paced, as many as the window's units of
        accepted cases (``batches``: their numbers of cases) owe the other port (``pltf.fuzz.pace``) when that is
        more."""
        pace = self.lanes.pace if self.lanes is not None else None
        if pace is None:
            return SINGLES_QUEUE
        return max(SINGLES_QUEUE, sum(pace.singles(n) for n in batches))

    def _way(self, dear: bool) -> None:
        """Run the next window the dear way or with fresh connections (``pltf.fuzz.trial``)."""
        assert self.lanes is not None
        if dear != self.lanes.dear:
            if not dear:
                self.lanes.release()  # the kept connection would hold port 0 (a target that admits one client)
            self.lanes.dear = dear

    def _lanes_run(self, batches_only: bool) -> None:
        assert self.lanes is not None
        while not self.stop:
            result = self.lanes.run(self.judge_unit, batches_only=batches_only, judge_clean=self.judge_clean)
            if result not in (DONE, STOPPED):  # no port serves us: what looked suspicious died with it
                culprit = self.suspicions[-1].unit if self.suspicions else None
                self.suspicions.clear()
                self.gone(result, culprit=culprit)
                return
            if self.suspicions:
                self.settle()
            if result == DONE:
                return

    def units(
        self, cases: list[Case], choose: Callable[[list[Case], list[list[Case]]], list[Case]] | None = None
    ) -> list[Unit]:
        """The window's units (``pltf.fuzz.unit.window_units``): the first batch behind the state prelude, and
        one single in ``STATEFUL_EVERY`` about an operation or motion command of those that run (``choose``)."""
        state, mode = self.kb.operation_state, self.kb.motion_mode
        target = self.plan.current

        def single_prelude(c: Case) -> list[bytes]:
            if c.telegram not in STATEFUL:
                return []
            self.stateful += 1
            if self.stateful % STATEFUL_EVERY:  # a prelude costs a target as much as a few cases
                return []
            return preludes.path(state, mode, target, self.forbidden)

        return window_units(
            cases, lambda: self.plan.prelude(state, mode, self.forbidden), target, single_prelude, choose
        )

    # ------------------------------------------------------------------ the oracle of an admitted unit
    def judge_unit(self, e: InFlight, v: Verdict) -> bool:
        """Count and learn from a unit the target served; False (stop the lanes) on a suspicion."""
        st, f, unit = self.stats, e.flight, e.unit
        st.units += 1
        st.probes += e.led  # its lead was answered: a liveness probe
        st.batches += unit.batch
        st.singles += not unit.batch
        st.cut_replies += v.cut
        self._learn(f.replies)
        if unit.target is not None:
            self._check(e, f.replies)
        if v.suspicious:
            self.suspicions.append(Suspicion(unit, e.port, v, exchange(e)))
            return False
        self._count(unit.cases, ("kept" if unit.batch else "closed") if f.closed or unit.batch else "open")
        return True

    def judge_clean(self, entries: list[InFlight]) -> None:
        """``judge_unit`` of plain singles the target served with a clean verdict (``pltf.fuzz.lanes``: they ran in
        C), in one loop: counted, their replies learnt."""
        st, learn, count = self.stats, self.kb.learn, self._count
        st.units += len(entries)
        st.singles += len(entries)
        for e in entries:
            f: Any = e.flight  # a ``pltf.fuzz.single.CSingle``
            unit = e.unit
            st.probes += e.led
            st.cut_replies += e.verdict.cut  # type: ignore[union-attr]
            if f.got:
                replies = f.replies
                for r in replies:
                    learn(r)
                if unit.target is not None:
                    self._check(e, replies)
            count(unit.cases, "closed" if f.closed else "open")

    def _check(self, e: InFlight, replies: list[Any]) -> None:
        """The unit's state prelude reached its target when its check's reply says so."""
        unit = e.unit
        at = None if unit.check_at is None else unit.check_at - (not e.led)
        if at is not None and unit.target is not None and len(replies) > at:
            check: Any = replies[at]  # a CMD_GET_STATUS reply (its fields are built from the spec at import)
            if check.NAME == "CMD_GET_STATUS" and self.plan.check(
                unit.target, check.operation_state, check.motion_mode
            ):
                self.stats.states.add(unit.target)

    def _learn(self, replies: list[Any]) -> None:
        for r in replies:
            self.kb.learn(r)

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

    # ------------------------------------------------------------------ suspicions
    def settle(self) -> None:
        """Replay each suspicion's unit alone once the ports are free: a finding when it fails again."""
        assert self.lanes is not None
        self.lanes.release()
        todo, self.suspicions = self.suspicions, []
        for s in todo:
            if self.stop:
                return
            self._settle(s)

    def _settle(self, s: Suspicion) -> None:
        assert self.lanes is not None
        kind, reason = s.verdict.kind, s.verdict.reason
        port = s.port
        if kind == TIMED_OUT:
            other = (port + 1) % len(self.ports)
            if self.lanes.alone(other, Unit([], []), patience=self.o.deadline) is None:
                self.gone("hang", f"{reason}; then no port served us within {self.o.deadline} s", s.unit)
                return
            kind, port = "stall", other  # the unit's port may still be held by the stalled connection
            reason = f"{reason} within the deadline; the other port still answers"

        patient_deadline = patient(self.o.deadline) if kind == "stall" else None

        def replay() -> str | None:
            self.stats.replays += 1
            again = Unit(s.unit.cases, s.unit.prelude, s.unit.target)
            e = self.lanes.alone(port, again, deadline=patient_deadline)  # type: ignore[union-attr]
            if e is None or e.verdict is None:
                return None
            self._learn(e.flight.out.replies)
            got = e.verdict.kind
            return "stall" if got == TIMED_OUT else got

        replays, needed = (1, 1) if kind == "stall" else (REPLAYS, NEEDED)  # a stall holds the port it stalls
        seen = confirm(kind, replay, replays, needed)
        if len(seen) < 2 and self.lanes.live.failing:  # a replay was not served: is the target still there?
            gone = self._cross_check()
            if gone is not None:
                self.gone(gone, culprit=s.unit)
                return
        ok = confirmed(kind, seen, needed)
        self.failure(kind, reason, [s.unit], ok, {"replays": seen, "port": self.ports[s.port], "exchange": s.exchange})
        if not ok:
            self._count(s.unit.cases, "closed")

    def _cross_check(self) -> str | None:
        """Every port once more; None when one serves us, else how the last attempts ended."""
        assert self.lanes is not None
        for k in range(len(self.ports)):
            if self.lanes.alone(k, Unit([], [])) is not None:
                return None
        return self.lanes.live.verdict(time.monotonic() + self.lanes.patience) or "dead"

    # ------------------------------------------------------------------ findings
    def gone(self, kind: str, reason: str | None = None, culprit: Unit | None = None) -> None:
        """No port serves us (or one is stuck): one finding naming the units sent last (``culprit``, the one that
        showed it, last of all)."""
        assert self.lanes is not None
        lanes = self.lanes
        if self.launcher is not None and kind in ("hang", "deaf"):  # a dying process may still hold its ports
            for _ in range(20):
                if not self.launcher.alive():
                    break
                time.sleep(0.05)
        if self.launcher is not None and not self.launcher.alive():
            kind = "dead"
        if culprit is None and kind == "stall":  # replayed first on a fresh instance, even if out of ``recent``
            culprit = lanes.left_unanswered(lanes.stuck)
        last = [u for u in dict.fromkeys(e.unit for e in lanes.recent) if u is not culprit and u.cases]
        last += [culprit] if culprit is not None else []
        lanes.drain()
        lanes.clear_queue()
        why = (
            reason
            or {
                "dead": "no port of the target takes a connection any more: it died",
                "hang": "the target takes connections but answers none within the deadline on any port: it hangs",
                "deaf": "the target closes every connection without answering on every port",
                "stall": f"port {self.ports[lanes.stuck or 0]} has not served a client for {lanes.patience:g} s "
                "while the other port still does",
            }[kind]
        )
        self.failure(kind, why, last, True, {"units_sent_last": [u.describe() for u in last[-8:]]})

    def at_failure(self) -> AtFailure:
        """Where the campaign stands, for the finding writer."""
        kb, learnt = self.kb, self.stats.profile
        return AtFailure(
            index=self.index,
            state=self.plan.current,
            operation_state=kb.operation_state,
            motion_mode=kb.motion_mode,
            elapsed=self.stats.elapsed,
            port=self.ports[0],
            profile=self.profile,
            learnt=learnt,
        )

    def failure(self, kind: str, reason: str, units: list[Unit], ok: bool, evidence: dict[str, Any]) -> None:
        assert self.lanes is not None
        finding = self.writer.handle(kind, reason, units, self.lanes.sent(), ok, evidence, self.at_failure())
        if finding is None:
            self.stats.duplicates += 1
        elif finding["confirmed"]:
            self.stats.findings.append(finding)
        else:
            self.stats.unconfirmed.append(finding)
            return
        if self.o.max_findings is not None and len(self.stats.findings) >= self.o.max_findings:
            self.stop = True
            return
        if self.launcher is not None and (kind in STOPS or self.writer.used_launcher):
            self.stats.restarts += 1
            self.lanes.close()
            self.start_target()
            self.plan.documents_due = True
        elif kind in STOPS:
            self.stop = True  # a target we cannot restart is gone (or its port is)


def exchange(e: InFlight) -> dict[str, Any]:
    """What a suspicious unit's connection carried in the campaign, for finding.json: the replies asked for, owed
    and received, the bytes each way, when our FIN went and when and how the connection ended (ms from the
    connect), and how it was connected (pipelined behind another unit, on the kept connection)."""
    f, out = e.flight, e.flight.out
    how = "deadline" if out.timed_out else "reset" if out.reset else "closed" if out.closed else "open"
    return {
        "asked": len(f.expected),
        "owed": e.unit.owed(f.session, len(f.expected)),
        "replies": [r.NAME for r in out.replies][:40],
        "bytes_sent": f.pos,
        "bytes_received": out.got,
        "our_fin_ms": out.fin_ms,
        "ended_ms": out.end_ms,
        "ended_by": how,
        "fin_waits": f.session.fin_waits,
        "pipelined": e.behind,
        "kept": e.kept,
        "led": e.led,
    }


__all__ = ["Campaign", "HarnessError", "Options", "Stats"]
