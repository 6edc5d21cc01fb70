"""From a failed unit to a finding on disk: confirm on a fresh target, delta-debug, deduplicate, write.

Rules:
- ``reproduce(sessions)`` starts a fresh target, replays, and names the failure it sees (``dead``, ``hang``,
  ``deaf``, ``stall``, ``bad-reply``, ``dropped``) or None. A candidate "still fails" when it fails the same way.
- Candidates, smallest first: the failed unit after the state prelude; then everything since the prelude.
  ddmin (``pltf.fuzz.minimize``) removes frames across sessions; a session left without frames is dropped.
- Without ``--launch`` nothing can be replayed: the finding is written as found (marked not minimized).
  With it, a failure that does not happen again on a fresh target (a load spike, state built up over a long
  run) is written under ``unconfirmed/`` and is not a finding (exit status 0).
- The signature (kind and the ids of the minimal frames) deduplicates findings within a run and, through
  the corpus, across resumed runs.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from pltf.fuzz.case import WHOLE, Case
from pltf.fuzz.minimize import ddmin, shortest_failing_prefix
from pltf.fuzz.report import slug, write_finding
from pltf.fuzz.target import Outcome, Prober, Session, expected_reply_ids, play

if TYPE_CHECKING:
    from pltf.fuzz.engine import Campaign


class FindingWriter:
    def __init__(self, campaign: Campaign, known: set[str]) -> None:
        self.c = campaign
        self.signatures: set[str] = set(known)
        self.count = 0

    # ------------------------------------------------------------------ replay against a fresh target
    def reproduce(self, sessions: list[Session], record: bool = False) -> tuple[str | None, list[Outcome]]:
        launcher, o = self.c.launcher, self.c.o
        assert launcher is not None
        port, second = launcher.start()
        prober = Prober(o.host, second, o.deadline)
        outcomes: list[Outcome] = []
        try:
            if prober.probe() is not None:
                return None, outcomes
            for s in sessions:
                out = play(o.host, port, s, o.deadline, record)
                outcomes.append(out)
                if out.refused:
                    return "dead", outcomes
                if out.bad_reply is not None:
                    return "bad-reply", outcomes
                if s.sync and out.closed and len(out.replies) < len(expected_reply_ids(s.data)) + 1:
                    verdict = prober.probe()
                    return (verdict.partition(":")[0] if verdict else "dropped"), outcomes
                if out.timed_out:
                    verdict = prober.probe()
                    return (verdict.partition(":")[0] if verdict else "stall"), outcomes
            time.sleep(0.02)
            verdict = prober.probe()
            if verdict is not None:
                return verdict.partition(":")[0], outcomes
            return ("dead" if not launcher.alive() else None), outcomes
        finally:
            prober.close()

    def _minimize(self, kind: str, sessions: list[Session]) -> tuple[list[Session], int]:
        flat = [(k, j) for k, s in enumerate(sessions) for j in range(len(s.frames))]
        tests = 0

        def rebuild(items: list[tuple[int, int]]) -> list[Session]:
            keep: dict[int, list[bytes]] = {}
            for k, j in items:
                keep.setdefault(k, []).append(sessions[k].frames[j])
            return [sessions[k].with_frames(fr) for k, fr in sorted(keep.items())]

        def test(items: list[tuple[int, int]]) -> bool:
            nonlocal tests
            tests += 1
            return self.reproduce(rebuild(items))[0] == kind

        best = shortest_failing_prefix(flat, test)
        if len(best) > 1 and test(best[-1:]):  # the frame that tipped it over, alone
            best = best[-1:]
        best = ddmin(best, test, max_tests=120, max_seconds=self.c.o.minimize_seconds)
        result = rebuild(best)
        simpler = [replace(s, delivery=WHOLE) for s in result]
        if any(s.delivery != WHOLE for s in result) and self.reproduce(simpler)[0] == kind:
            result = simpler
        return result, tests

    # ------------------------------------------------------------------ a failed unit
    def handle(
        self, kind: str, reason: str, prelude: Session, unit: list[Session], history: list[Session], cases: list[Case]
    ) -> dict[str, Any] | None:
        c = self.c
        sessions = [prelude, *unit]
        minimized, confirmed, tests = False, False, 0
        outcomes: list[Outcome] = []
        if c.launcher is not None:
            for candidate in ([prelude, *unit], [prelude, *[s for s in history if s is not prelude]]):
                if self.reproduce(candidate)[0] == kind:
                    sessions, confirmed = candidate, True
                    break
            if confirmed:
                sessions, tests = self._minimize(kind, sessions)
                minimized = True
            got, outcomes = self.reproduce(sessions, record=True)
            confirmed = confirmed and got == kind
            c.launcher.stop()
        ids = [f[8] for s in sessions for f in s.frames if len(f) > 8]
        signature = f"{kind}:{','.join(map(str, ids[-8:]))}"
        if signature in self.signatures:
            return None
        self.signatures.add(signature)
        self.count += 1
        culprit = cases[-1] if cases else None
        name = f"finding-{self.count:03d}-{kind}-{slug(culprit.telegram if culprit else 'batch')}"
        tail = list(c.launcher.output)[-30:] if c.launcher is not None else []
        description = {
            "signature": signature,
            "command": c.o.command,
            "seed": c.o.seed,
            "case_index_before": c.index,
            "state": {"target": list(c.plan.current), "operation_state": c.kb.operation_state,
                      "motion_mode": c.kb.motion_mode},
            "culprit": culprit.to_json() | {"frames": len(culprit.frames)} if culprit else None,
            "confirmed_on_fresh_target": confirmed,
            "minimized": minimized,
            "minimize_tests": tests,
            "target_output_tail": tail,
        }  # fmt: skip
        # with a launcher a finding must reproduce on a fresh target; one that does not is kept for inspection
        where = c.o.out if confirmed or c.launcher is None else c.o.out / "unconfirmed"
        directory = write_finding(where / name, kind, reason, sessions, description, outcomes, c.ports[0], c.o.deadline)
        return {"kind": kind, "reason": reason, "dir": str(directory), "confirmed": confirmed, "signature": signature}
