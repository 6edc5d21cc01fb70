"""From a failure to a finding on disk: reproduce on a fresh target, delta-debug, deduplicate, write.

Rules:
- ``handle`` gets the failure's kind, the units it covers (the suspicious unit, or the units sent last before a
  death) and whether the campaign believes it (replays on the live target, or a target no port serves). Only
  a believed failure is a finding; the rest is written under ``unconfirmed/`` and never sets the exit status.
- With ``--launch`` a believed failure is reproduced on fresh instances: each unit alone after the full state
  prelude of its target (the last first), then the units together, then what both lanes sent lately in the
  order it was written (``pltf.fuzz.sent``: the last ``RECENT_SENT`` sessions, then all ``pltf.fuzz.lanes.LOG``
  flights), each behind the full prelude of the plan's state: units in flight at a death among them;
  for a death none of those causes (a leak: the target dies of what piles up), the units are repeated until the
  instance dies (``REPEAT_MAX`` rounds, ``REPEAT_SECONDS``): all of them, then the biggest and the busiest alone. ddmin
  (``pltf.fuzz.minimize``) then removes frames across sessions, the lead of each kept: it tells a
  newcomer turned away from one served (``pltf.fuzz.verdict``); every replay waits for the port as the lanes do.
- The writer reads no campaign: a ``FindingContext`` (frozen) holds what stays for the campaign's life (the options
  it reads, the launcher of fresh instances), and ``handle`` gets an ``AtFailure`` with where the campaign stands
  at the failure (case index, state, elapsed time, the target's port and profile), which moves on between calls.
- The signature (kind and the ids of the minimal frames) deduplicates findings within a run and, through the
  corpus, across resumed runs; a failure whose culprit was seen before is not reproduced again.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pltf.fuzz import preludes
from pltf.fuzz.case import WHOLE
from pltf.fuzz.minimize import ddmin, shortest_failing_prefix
from pltf.fuzz.report import slug, write_finding
from pltf.fuzz.target import LEAD, Outcome, Session, play_admitted, session_reply_ids
from pltf.fuzz.unit import Unit
from pltf.fuzz.verdict import BAD_REPLY, DROPPED, OK, TIMED_OUT, judge, patient
from pltf.spec.codec import REQUESTS

if TYPE_CHECKING:
    from pltf.fuzz.options import Options
    from pltf.fuzz.profile import Profile
    from pltf.harness.launch import Launcher

REPEAT_MAX = 2000  # rounds of a repeated candidate at most
REPEAT_SECONDS = 30.0  # s a repeated candidate may take
GONE = ("dead", "hang", "deaf")
INCONCLUSIVE = "inconclusive"  # a replay the machine did not let run
FRESH_TRIES = 3  # fresh instances a replay gets at most while it is inconclusive
RECENT_SENT = 128  # sessions of what was sent last, in send order: the first such candidate (then all of them)


def led(s: Session) -> Session:
    """A session a fresh connection can replay: opened by the lead, our write side shut at the end."""
    if s.led:
        return s
    answered = None if s.answered is None else [LEAD[8], *s.answered]
    return replace(s, frames=[LEAD, *s.frames], half_close=True, led=True, answered=answered)


def prelude_session(target: preludes.Target) -> Session:
    return Session([LEAD, *preludes.full(target)], sync=True, half_close=True, led=True)


@dataclass(frozen=True)
class FindingContext:
    """What a FindingWriter reads of its campaign for the campaign's whole life."""

    host: str
    deadline: float  # s: the campaign's reply deadline (``--deadline``); replays wait ``patient(deadline)``
    out: Path = Path("findings")
    minimize_seconds: float = 60.0
    command: str = "pltf fuzz"  # the command line the description records
    seed: int = 0
    launcher: Launcher | None = None  # fresh instances (``--launch``); None: no reproduction, no minimisation

    @classmethod
    def of(cls, o: Options, launcher: Launcher | None) -> FindingContext:
        return cls(o.host, o.deadline, o.out, o.minimize_seconds, o.command, o.seed, launcher)


@dataclass(frozen=True)
class AtFailure:
    """Where the campaign stands when a failure is handled (it moves on between failures)."""

    index: int  # the case index before the failure
    state: preludes.Target  # the state plan's current target: the prelude of units that name none
    operation_state: int | None  # as the campaign last knew them (``pltf.fuzz.knowledge``)
    motion_mode: int | None
    elapsed: float  # s since the campaign started
    port: int  # the target's first port now (a restart of a --launch target changes it)
    profile: Profile | None = None  # what the opening phase learnt: replays adapt their sessions to it
    learnt: dict[str, Any] | None = None  # the same as the statistics record it, for the description


class FindingWriter:
    def __init__(self, context: FindingContext, known: set[str]) -> None:
        self.ctx = context
        self.profile: Profile | None = None  # the target's, as ``handle`` last got it (``AtFailure.profile``)
        self.signatures: set[str] = set(known)
        self.culprits: set[str] = set()
        self.count = 0
        self.rounds = 1
        self.used_launcher = False  # the last ``handle`` started fresh targets (the campaign's is gone)

    def adapt(self, session: Session) -> Session:
        """A session as the campaign's target needs it (``pltf.fuzz.profile``)."""
        return self.profile.adapt(session) if self.profile is not None else session

    # ------------------------------------------------------------------ replay against a fresh target
    def reproduce(
        self, sessions: list[Session], record: bool = False, repeat: int = 1, seconds: float | None = None
    ) -> tuple[str | None, list[Outcome]]:
        """Start a fresh target, replay ``sessions`` (``repeat`` rounds, until it dies), name the failure. A replay
        the machine left inconclusive (the fresh instance did not serve the probe port before anything was sent)
        runs again on another fresh instance, ``FRESH_TRIES`` times at most: it is not "not reproduced"."""
        verdict: str | None = INCONCLUSIVE
        outcomes: list[Outcome] = []
        for _ in range(FRESH_TRIES):
            verdict, outcomes = self._replay(sessions, record, repeat, seconds)
            if verdict != INCONCLUSIVE:
                return verdict, outcomes
        return None, outcomes

    def _replay(
        self, sessions: list[Session], record: bool, repeat: int, seconds: float | None
    ) -> tuple[str | None, list[Outcome]]:
        """One fresh instance. Every wait is the campaign's: the patient deadline of its stall replays
        (``pltf.fuzz.verdict.patient``) and, for the probe port, the patience of its liveness: a fresh instance on a
        loaded machine that answers late is slow, not stalled or hung."""
        launcher, o = self.ctx.launcher, self.ctx
        assert launcher is not None
        port, second = launcher.start()
        deadline, patience = patient(o.deadline), max(1.0, 2 * o.deadline)
        outcomes: list[Outcome] = []
        status = self.adapt(Session([LEAD], half_close=True, led=True))
        if not play_admitted(o.host, second, status, deadline, patience)[1]:
            return INCONCLUSIVE, outcomes
        end = time.monotonic() + (seconds or REPEAT_SECONDS)
        for self.rounds in range(1, repeat + 1):
            for s in map(self.adapt, sessions):
                out, served = play_admitted(o.host, port, s, deadline, patience, record, launcher.alive)
                outcomes.append(out)
                if not served:  # the other port still serves: this one is stuck
                    return self._gone(second, patience) or "stall", outcomes
                expected = len(session_reply_ids(s)) + s.sync
                v = judge(out, expected if s.sync else int(s.led), s.led, s.sync)
                if v.kind == BAD_REPLY:
                    return BAD_REPLY, outcomes
                if v.kind in (DROPPED, TIMED_OUT):
                    time.sleep(0.02)
                    gone = self._gone(second, patience)
                    return (gone or ("stall" if v.kind == TIMED_OUT else DROPPED)), outcomes
            if repeat > 1 and (not launcher.alive() or time.monotonic() > end):
                break
        time.sleep(0.02)
        return self._gone(second, patience) or ("dead" if not launcher.alive() else None), outcomes

    def _gone(self, second: int, patience: float) -> str | None:
        """None when the probe port still serves us; else dead, hang or deaf."""
        launcher, o = self.ctx.launcher, self.ctx
        assert launcher is not None
        if not launcher.alive():
            return "dead"
        probe = self.adapt(Session([LEAD], half_close=True, led=True))
        out, served = play_admitted(o.host, second, probe, patient(o.deadline), patience)
        if served and out.replies:
            return None
        if not launcher.alive() or out.refused:
            return "dead"
        return "hang" if out.timed_out else "deaf"

    def _minimize(self, kind: str, sessions: list[Session]) -> tuple[list[Session], int]:
        flat = [(k, j) for k, s in enumerate(sessions) for j in range(int(s.led), len(s.frames))]
        tests = 0

        def rebuild(items: list[tuple[int, int]]) -> list[Session]:
            keep: dict[int, list[bytes]] = {}
            for k, j in items:
                keep.setdefault(k, sessions[k].frames[:1] if sessions[k].led else []).append(sessions[k].frames[j])
            return [
                replace(sessions[k].with_frames(fr), gate=sessions[k].gate and len(fr) > 1)
                for k, fr in sorted(keep.items())
            ]

        end = time.monotonic() + self.ctx.minimize_seconds

        def test(items: list[tuple[int, int]]) -> bool:
            nonlocal tests
            if time.monotonic() > end:  # out of budget: the smallest failing sequence so far stays
                return False
            tests += 1
            return self.reproduce(rebuild(items))[0] == kind

        best = shortest_failing_prefix(flat, test)
        prelude = [i for i in best if i[0] == 0 and sessions[0].led and len(sessions) > 1]
        if len(best) > 1 and test(best[-1:]):  # the frame that tipped it over, alone
            best = best[-1:]
        elif len(prelude) + 1 < len(best) and test([*prelude, best[-1]]):  # ... behind the state prelude
            best = [*prelude, best[-1]]
        best = ddmin(best, test, max_tests=120, max_seconds=max(0.0, end - time.monotonic()))
        result = rebuild(best)
        simpler = [replace(s, delivery=WHOLE, gate=False) for s in result]
        if any(s.delivery != WHOLE or s.gate for s in result) and self.reproduce(simpler)[0] == kind:
            result = simpler
        return result, tests

    def _fresh(self, kind: str, units: list[Unit], history: list[Session], state: preludes.Target) -> dict[str, Any]:
        """Reproduce on fresh instances and minimise; what was found out (``state``: the plan's current target)."""
        sessions_of = [(prelude_session(u.target or state), u.session()) for u in units]
        candidates = [list(pair) for pair in reversed(sessions_of[-4:])]
        if len(units) > 1:
            candidates.append([sessions_of[-1][0], *(s for _, s in sessions_of)])
        # what both lanes sent lately, in the order it was written (``pltf.fuzz.sent``): a state fed by every
        # connection (a platform has one) may have been reached by the lanes together, in no unit alone
        sent = [history[-RECENT_SENT:], history] if len(history) > RECENT_SENT else [history]
        candidates += [[prelude_session(state), *map(led, h)] for h in sent if h]
        got: dict[str, Any] = {"sessions": None, "repeat": 1, "minimized": False, "tests": 0}
        for candidate in candidates:
            if self.reproduce(candidate)[0] == kind:
                got["sessions"] = candidate
                break
        if got["sessions"] is None and kind in GONE:  # what piles up: the units repeated, all, then the biggest
            biggest = sorted(sessions_of, key=lambda p: -len(p[1].data))[:2]
            busiest = sorted(sessions_of, key=lambda p: -len(p[1].frames))[:2]
            every = [sessions_of[-1][0], *(s for _, s in sessions_of)]
            pairs = list({(id(p), id(s)): (p, s) for p, s in [*biggest, *busiest]}.values())  # sessions: no hash
            for candidate in [every, *([p, s] for p, s in pairs)]:
                if self.reproduce(candidate, repeat=REPEAT_MAX, seconds=REPEAT_SECONDS)[0] == kind:
                    got["sessions"], got["repeat"] = candidate, 2 * self.rounds  # a margin for a fresh instance
                    break
        if got["sessions"] is not None and got["repeat"] == 1:
            got["sessions"], got["tests"] = self._minimize(kind, got["sessions"])
            got["minimized"] = True
        if got["sessions"] is not None:
            verdict, got["outcomes"] = self.reproduce(
                got["sessions"], record=True, repeat=got["repeat"], seconds=4 * REPEAT_SECONDS
            )
            got["reproduced"] = verdict == kind
        return got

    # ------------------------------------------------------------------ a failure
    def handle(
        self,
        kind: str,
        reason: str,
        units: list[Unit],
        history: list[Session],
        believed: bool,
        evidence: dict[str, Any],
        at: AtFailure,
    ) -> dict[str, Any] | None:
        """Write the failure; None for a duplicate. ``believed``: a finding (replays confirmed it, or no port
        serves us any more); else it goes under ``unconfirmed/``. ``at``: where the campaign stands."""
        c, launcher = self.ctx, self.ctx.launcher
        self.used_launcher = False
        self.profile = at.profile
        found_after = round(at.elapsed, 1)
        culprit = units[-1].cases[-1] if units and units[-1].cases else None
        key = f"{kind}:{culprit.telegram if culprit else '-'}:{culprit.origin if culprit else '-'}"
        if believed and key in self.culprits:
            return None
        target = units[-1].target if units and units[-1].target else at.state
        sessions = [prelude_session(target), *(u.session() for u in units)]
        fresh: dict[str, Any] = {}
        if launcher is not None and believed:
            self.used_launcher = True
            launcher.spares = True  # each test of the minimisation on a fresh instance, the next one warming up
            try:
                fresh = self._fresh(kind, units, history, at.state)
            finally:
                launcher.no_spares()
            if fresh.get("sessions") is not None:
                sessions = fresh["sessions"]
            launcher.stop()
        ids = [f[8] for s in sessions for f in s.frames[int(s.led) :] if len(f) > 8]
        signature = f"{kind}:{','.join(map(str, ids[-8:]))}"
        if believed and signature in self.signatures:
            return None
        if believed:
            self.signatures.add(signature)
            self.culprits.add(key)
        self.count += 1
        last = next((f for s in reversed(sessions) for f in reversed(s.frames[int(s.led) :])), b"")
        called = _telegram(last) if fresh.get("sessions") else culprit.telegram if culprit else "batch"
        name = f"finding-{self.count:03d}-{kind}-{slug(called)}"
        tail = list(launcher.output)[-30:] if launcher is not None else []
        description = {
            "signature": signature,
            "command": c.command,
            "seed": c.seed,
            "case_index_before": at.index,
            "state": {"target": list(target), "operation_state": at.operation_state, "motion_mode": at.motion_mode},
            "culprit": culprit.to_json() | {"frames": len(culprit.frames)} if culprit else None,
            "confirmed": believed,
            "found_after_s": found_after,
            "evidence": evidence,
            "reproduced_on_fresh_target": fresh.get("reproduced", False),
            "repeat": fresh.get("repeat", 1),
            "minimized": fresh.get("minimized", False),
            "minimize_tests": fresh.get("tests", 0),
            "target_output_tail": tail,
            "target_profile": at.learnt or None,  # what the opening phase learnt
        }
        where = c.out if believed else c.out / "unconfirmed"
        directory = write_finding(
            where / name,
            kind,
            reason,
            [self.adapt(s) for s in sessions],
            description,
            fresh.get("outcomes", []),
            at.port,
            c.deadline,
            repeat=fresh.get("repeat", 1),
        )
        return {
            "kind": kind,
            "reason": reason,
            "dir": str(directory),
            "confirmed": believed,
            "signature": signature,
            "reproduced": fresh.get("reproduced", False),
            "evidence": evidence,
            "found_after_s": description["found_after_s"],
        }


def _telegram(frame: bytes) -> str:
    t = REQUESTS.by_id.get(frame[8]) if len(frame) > 8 else None
    return t.NAME if t is not None else f"id {frame[8]}" if len(frame) > 8 else "raw"


__all__ = ["OK", "AtFailure", "FindingContext", "FindingWriter", "led", "prelude_session"]
