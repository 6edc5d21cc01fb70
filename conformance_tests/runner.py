"""Run the selected cases against a target and turn what they raise into verdicts.

Rules:
- Before each group the target is put into the known state (Ready, MODE_MOTION_NO); each case then sets up
  what it needs itself, so a case selected alone with ``-k`` behaves as in a full run.
- The safety gate is checked here, not in the cases: ``moves_platform``/``switches_outputs`` cases run only
  with ``--allow-motion`` or ``--target-is-simulator``, ``destructive`` ones only with ``--allow-shutdown``;
  the others are SKIPPED with the reason.
- Re-runs: an INCONCLUSIVE attempt is re-run up to ``reruns`` times; a FAIL of a ``timing`` case is re-run
  too. Attempts that disagree (one PASS, one FAIL) make the case INCONCLUSIVE: a flake is reported, not hidden.
- After every ``abuse`` case the runner checks liveness: a new client is served on each port and the operation
  state and motion mode are what they were before the abuse.
- A case during which the target restarted (a port refused connections, then served again; or a lost connection
  after which the platform had lost its initialisation: erratum E-BEH-007, zoo matrix row 10) is INCONCLUSIVE with
  that reason and run again, whatever it saw meanwhile: a restart is an event of the platform, not a failure of
  its protocol. After an attempt that failed or lost its connection the runner looks: a port A that refuses now
  is waited out (``RESTART_WINDOW``; the wait and what was seen are named); a connection lost during a case that
  sent nothing that uninitialises the platform (``UNINITIALISING``) nor malformed input, after which a new one is
  served at once but the platform lost its initialisation, is a restart too. The re-run starts from scratch: the
  case's own set-up brings the fresh target to the state it needs (``CaseContext.ensure``), and a way to a state
  that the restart made the pipelined run abandon is taken for granted again. A re-run that a restart cuts again
  stays INCONCLUSIVE with that reason, never FAIL; a FAIL of a re-run that no restart cut is the case's verdict.
  The run's notes name each restart and the case in flight, and sum them up at the end.
- A SHOULD or MAY case during which the target stopped answering (a reply timeout, and then no new client
  served) is FAIL: whatever the case's level, a target must keep serving.
- Bounds (pace.py): the target's reply time is measured once before the first case and scales the waits; every
  case (and the reset before a group) runs within a budget; a run budget and the watch on a target that stopped
  answering leave the remaining cases INCONCLUSIVE "not run" with the reason, so a run always ends.
- Exit status (``RunResult.exit_code``): 2 when a harness error occurred, 1 when a case FAILed or a MUST case
  stayed INCONCLUSIVE (unless the baseline expects it) or a baseline entry is stale, else 0.
"""

from __future__ import annotations

import time
import traceback
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

from pltf.conformance_tests import pace
from pltf.conformance_tests.baseline import Baseline
from pltf.conformance_tests.catalogue import Case, Level, Verdict
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import (
    Absurd,
    BudgetSpent,
    ConnectionClosed,
    Deviation,
    Fail,
    Inconclusive,
    NoConnection,
    NotApplicable,
    ReplyTimeout,
    Unreachable,
    deviation_verdict,
    verdict_for_level,
    worst,
)
from pltf.conformance_tests.target import Config, Status, Target
from pltf.conformance_tests.wire import NullObserver, Session, WireEntry, WireLog


def first_line(text: str) -> str:
    return text.splitlines()[0] if text else ""


@dataclass
class Attempt:
    verdict: Verdict
    message: str
    duration: float
    wire: list[WireEntry]
    deviations: list[Deviation]
    notes: list[str]
    precondition: bool = False
    silent: bool = False  # the target did not answer at all (a reply timeout, no connection, a spent budget)
    final: bool = False  # not to be re-run (the case's budget ran out)


@dataclass
class CaseResult:
    case: Case
    verdict: Verdict
    message: str
    attempts: list[Attempt] = field(default_factory=list)
    expected_failure: bool = False  # listed in the baseline and still failing

    @property
    def duration(self) -> float:
        return sum(a.duration for a in self.attempts)

    @property
    def wire(self) -> list[WireEntry]:
        return self.attempts[-1].wire if self.attempts else []

    @property
    def deviations(self) -> list[Deviation]:
        return self.attempts[-1].deviations if self.attempts else []

    @property
    def notes(self) -> list[str]:
        return self.attempts[-1].notes if self.attempts else []

    @property
    def blocking(self) -> bool:
        """Does this result fail the run (exit status 1)?"""
        if self.expected_failure:
            return False
        return self.verdict is Verdict.FAIL or (self.verdict is Verdict.INCONCLUSIVE and self.case.level is Level.MUST)


@dataclass
class RunResult:
    config: Config
    results: list[CaseResult]
    target: Target
    started: float
    duration: float
    stale: list[str] = field(default_factory=list)
    harness_error: str | None = None
    notes: list[str] = field(default_factory=list)  # about the run as a whole (the target's pace, budgets)

    @property
    def exit_code(self) -> int:
        if self.harness_error or any(r.verdict is Verdict.ERROR for r in self.results):
            return 2
        if self.stale or any(r.blocking for r in self.results):
            return 1
        return 0

    def counts(self) -> dict[Verdict, int]:
        out = dict.fromkeys(Verdict, 0)
        for r in self.results:
            out[r.verdict] += 1
        return out


class Reporter(Protocol):
    def on_start(self, config: Config, cases: Sequence[Case], gate: list[str]) -> None: ...
    def on_case_start(self, case: Case) -> None: ...
    def on_case_end(self, result: CaseResult) -> None: ...
    def on_finish(self, run: RunResult) -> None: ...


def gate_notice(config: Config) -> list[str]:
    """What the safety gate lets through, in plain words (shown at start)."""
    lines = []
    if config.simulator:
        lines.append(
            "The target is declared a simulator (--target-is-simulator): cases that MOVE the platform "
            "and SWITCH outputs will run."
        )
    elif config.allow_motion:
        lines.append(
            "--allow-motion: cases will MOVE THE PLATFORM (up to 0.6 m from where it stands, turns on "
            "the spot) and SWITCH OUTPUTS (digital outputs, brakes, head drive, CAN frames). Keep the "
            "area clear and the emergency stop at hand."
        )
    else:
        lines.append(
            "Safety gate closed: cases that move the platform or switch outputs are SKIPPED "
            "(use --allow-motion on a real platform, or --target-is-simulator)."
        )
    if config.allow_shutdown:
        lines.append("--allow-shutdown: the last case sends CMD_EXIT; the target will stop.")
    lines.append(
        "The suite changes parameters, documents and the estimated pose and restores them after each "
        "case; CMD_SAVE_* cases rewrite the stored files with the content they had."
    )
    return lines


LAST_CASE_GRACE = 10.0  # wall s a case begun just before the run's budget is spent may still take


class Runner:
    def __init__(
        self,
        config: Config,
        cases: Sequence[Case],
        reporters: Sequence[Reporter] = (),
        baseline: Baseline | None = None,
    ) -> None:
        self.config = config
        self.cases = list(cases)
        self.reporters = list(reporters)
        self.baseline = baseline or Baseline()
        self.target = Target(config)
        self.watch = pace.Watch()
        self.notes: list[str] = []
        self._run_end: float | None = None  # when the run's budget is spent (monotonic), None: no budget

    def _emit(self, hook: str, *args: object) -> None:
        for r in self.reporters:
            getattr(r, hook)(*args)

    def run(self) -> RunResult:
        started = time.time()
        t0 = time.monotonic()
        self._emit("on_start", self.config, self.cases, gate_notice(self.config))
        results: list[CaseResult] = []
        harness_error = None
        try:
            # reachable = a TCP connection is accepted; a broken GET_STATUS is the cases' to report, not ours
            self.target.connect("A", WireLog(), NullObserver(), probe=False).close()
        except Unreachable as exc:
            harness_error = str(exc)
        if harness_error is None:
            self.prepare()
            group = None
            budget = self.config.run_budget
            self._run_end = None if budget is None else t0 + budget
            for c in self.cases:
                self._emit("on_case_start", c)
                if budget is not None and time.monotonic() - t0 > budget and not self._gate(c):
                    result = CaseResult(
                        c, Verdict.INCONCLUSIVE, f"not run: the run's budget of {budget:g} s is spent (--budget)"
                    )
                else:
                    if c.group != group:
                        group = c.group
                        self.reset(c)
                    result = self.run_case(c)
                results.append(result)
                self._emit("on_case_end", result)
        self.target.close()
        self.notes += self.target.notes
        if self.target.restarts:
            self.notes.append(_restarts_summary(self.target))
        ran = {r.case.id: r for r in results}
        stale = self.baseline.stale(ran)
        for r in results:
            r.expected_failure = self.baseline.expects(r)
        run = RunResult(
            self.config, results, self.target, started, time.monotonic() - t0, stale, harness_error, self.notes
        )
        self._emit("on_finish", run)
        return run

    def prepare(self) -> pace.Pace:
        """Measure the target's reply time and scale the run's waits to it (pace.py); noted in the run."""
        p = pace.measure(self.target)
        pace.apply(p, self.config)
        self.notes.append(p.describe(self.config))
        if p.reply is None or p.reply > self.config.reply_timeout:
            self.watch.pace = self.notes[-1]
        return p

    def _case_budget(self) -> float:
        """A case's budget; a case begun late in the run ends near the run's budget, not beyond it."""
        budget = pace.case_budget(self.config)
        if self._run_end is not None:
            budget = min(budget, max(LAST_CASE_GRACE, self._run_end - time.monotonic()))
        return budget

    def _spent(self) -> bool:
        return self._run_end is not None and time.monotonic() >= self._run_end

    def _budget(self, seconds: float) -> None:
        self.target.budget.seconds = seconds
        self.target.budget.deadline = time.monotonic() + seconds

    def _unbudgeted(self) -> None:
        self.target.budget.deadline = None

    def reset(self, c: Case) -> None:
        """The known state before a group: Ready, MODE_MOTION_NO (best effort; the cases report what is wrong)."""
        if self.watch.tripped:
            return
        ctx = CaseContext(self.target, c)
        self._budget(pace.case_budget(self.config))
        self.target.case = f"the reset before {c.id}"
        try:
            ctx.ready()
        except Exception:
            pass
        finally:
            ctx.finish()
            self._unbudgeted()

    # ---- one case
    def run_case(self, c: Case) -> CaseResult:
        skip = self._gate(c)
        if skip:
            return CaseResult(c, Verdict.SKIPPED, skip)
        stuck = self.watch.blocks(self.target)
        if stuck:
            return CaseResult(c, Verdict.INCONCLUSIVE, stuck)
        attempts: list[Attempt] = []
        for _ in range(1 + max(0, self.config.reruns)):
            a = self._attempt(c)
            attempts.append(a)
            again = (a.verdict is Verdict.INCONCLUSIVE and not a.final) or (
                c.timing and a.verdict in (Verdict.FAIL, Verdict.NON_STRICT) and not a.precondition
            )
            if not again or a.silent or self._spent():
                break  # no re-run once the run's budget is spent: the run ends within it
        verdict, message = _resolve(attempts)
        last = attempts[-1]
        if last.silent and verdict in (Verdict.NON_STRICT, Verdict.NA):
            # a SHOULD or MAY case, but the target answers nobody any more: serving on is a MUST
            problem = pace.health(self.target)
            if problem:
                verdict, message = (
                    Verdict.FAIL,
                    (f"the target stopped answering during this case: {problem} (the case: {first_line(message)})"),
                )
        self.watch.record(c.id, last.silent, first_line(last.message))
        return CaseResult(c, verdict, message, attempts)

    def _gate(self, c: Case) -> str:
        if c.destructive and not self.config.allow_shutdown:
            return "safety gate: stops the target (needs --allow-shutdown)"
        if c.gated and not self.config.motion_allowed:
            what = "moves the platform" if c.moves_platform else "switches outputs"
            return f"safety gate: {what} (needs --allow-motion or --target-is-simulator)"
        return ""

    def _attempt(self, c: Case) -> Attempt:
        ctx = CaseContext(self.target, c)
        t0 = time.monotonic()
        budget = self._case_budget()
        self._budget(budget)
        restarts, prompt = self.target.restarts, self.target.prompt
        self.target.case = c.id
        try:
            verdict, message, pre, silent, lost = _outcome(c, ctx)
            if (lost or verdict in (Verdict.FAIL, Verdict.NON_STRICT)) and self.target.restarts == restarts:
                gone = _back(self.target, ctx, lost == "closed")  # a restart? (before the clean-up initialises)
                if gone:
                    message = f"{message}; then {gone}"

        finally:
            self._budget(max(10.0, budget / 4))  # the clean-up's own budget
            ctx.finish()
            self._unbudgeted()
        if c.abuse and verdict is not Verdict.ERROR:
            problem = _liveness(ctx, ctx.abuse_from)
            if problem:
                verdict, message = Verdict.FAIL, (message + "; " if message else "") + problem
        for dev in ctx.deviations:
            dv = deviation_verdict(dev, self.config.profile)
            if dv is not Verdict.PASS:
                if worst(verdict, dv) is not verdict and verdict in (Verdict.PASS, Verdict.NA):
                    message = (message + "; " if message else "") + dev.describe()
                verdict = worst(verdict, dv)
            else:
                ctx.note(f"informative: {dev.describe()}")
        if self.target.restarts > restarts and verdict not in (Verdict.PASS, Verdict.ERROR):
            verdict, silent, pre = Verdict.INCONCLUSIVE, False, False
            self.target.prompt = self.target.prompt or prompt  # the state the restart showed was no slow target's
            message = (
                f"the target restarted during this case ({self.target.restart_seen}: erratum "
                f"E-BEH-007, zoo behaviour matrix row 10), so the case is run again; it said: {message}"
            )
        if ctx.unsolicited:
            ctx.note(f"{len(ctx.unsolicited)} unsolicited frame(s) received (guide 6.1, erratum E-CMD-013)")
        return Attempt(
            verdict,
            message,
            time.monotonic() - t0,
            list(ctx.log.entries),
            list(ctx.deviations),
            list(ctx.notes),
            pre,
            silent,
            final=silent and verdict is Verdict.INCONCLUSIVE,
        )


def _outcome(c: Case, ctx: CaseContext) -> tuple[Verdict, str, bool, bool, str]:
    """Run the case: its verdict and message, whether it failed a precondition, whether the target answered nothing
    (silent) and how a connection was lost: "closed" (closed or reset), "silent" (no reply) or "" (a restart,
    perhaps)."""
    try:
        c.func(ctx)
    except Fail as exc:
        silent = isinstance(exc, (ReplyTimeout, NoConnection))
        return _fail_verdict(c, exc), str(exc), exc.precondition, silent, _lost(exc)
    except NotApplicable as exc:
        return Verdict.NA, str(exc), False, False, ""
    except Inconclusive as exc:
        return Verdict.INCONCLUSIVE, str(exc), False, isinstance(exc, BudgetSpent), ""
    except Exception as exc:
        tb = traceback.format_exception(exc)
        return Verdict.ERROR, f"harness error: {exc!r}\n{''.join(tb[-6:])}", False, False, ""
    return Verdict.PASS, "", False, False, ""


def _lost(exc: Fail) -> str:
    """How the case's connection was lost: "closed" (a close or a reset), "silent" (no reply), "" (not lost, or
    never had: a port that served no connection is the restart window's to judge)."""
    if isinstance(exc, NoConnection):
        return ""
    return "closed" if isinstance(exc, ConnectionClosed) else "silent" if isinstance(exc, ReplyTimeout) else ""


UNINITIALISING = frozenset({"CMD_SHUTDOWN_PLTF", "CMD_EXIT", "CMD_SHUTDOWN_HOST"})  # a lost initialisation's causes
BACK_AT_ONCE = 1.0  # wall s a port that takes connections gets to serve again after a lost connection


def _back(target: Target, ctx: CaseContext, closed: bool) -> str:
    """After an attempt that failed or lost its connection: was it a restart (erratum E-BEH-007)? A port A that
    refuses now is waited out (``RESTART_WINDOW``: Target.connect counts the restart when it serves again). After a
    connection closed or reset (not a silent one: a hung target is not waited for twice) on a port that takes
    connections, a new one is served (within ``BACK_AT_ONCE`` s) and its status read: a platform that was
    initialised and now is not lost its state with the connection - it restarted, unless the case sent what
    uninitialises it or malformed input. Whatever else happens is the next case's. Returns what was seen when a
    refusing port did not come back within the window, else ''."""
    before = target.last_status[2] if target.last_status is not None else None
    refused = _refused(target)
    if not (refused or (closed and not ctx.case.abuse and not ctx.sent & UNINITIALISING)):
        return ""  # a port that takes connections (a stuck target's too), nothing lost: no restart a connect shows
    target.close()  # one client per port: our sessions would keep the port busy
    restarts = target.restarts
    window = None if refused else BACK_AT_ONCE
    try:
        target.connect("A", WireLog(max_entries=50), NullObserver(), window=window).close()
    except Unreachable as exc:
        return str(exc) if refused else ""
    except Fail:
        return ""
    now = target.last_status[2] if target.last_status is not None else None
    if target.restarts == restarts and before is not None and now is not None and before.initialized > now.initialized:
        target.restarted(f"port A lost our connection and the platform its initialisation ({now.describe()})")
    return ""


def _restarts_summary(target: Target) -> str:
    """The run's note on the restarts: how many, during which cases (erratum E-BEH-007, zoo matrix row 10)."""
    cases = ", ".join(dict.fromkeys(c or "between cases" for c in target.restart_cases))
    return (
        f"the target restarted {target.restarts} time(s) during the run (erratum E-BEH-007, an alternative reading; "
        f"zoo behaviour matrix row 10), during: {cases}; each case a restart cut was run again"
    )


def _refused(target: Target) -> bool:
    """Whether port A refuses a connection now (one attempt, no probe: cheap against a stuck target)."""
    s = Session(target.config.host, target.port_of("A"), log=WireLog(max_entries=5), timeout=1.0)
    try:
        s.connect()
    except Unreachable as exc:
        return "refused" in str(exc).lower()
    finally:
        s.close()
    return False


def _fail_verdict(c: Case, exc: Fail) -> Verdict:
    return Verdict.FAIL if isinstance(exc, Absurd) else verdict_for_level(c.level)


def _liveness(ctx: CaseContext, before: Status | None) -> str:
    """'' when the target still serves every port in the state it had before the abuse; else the problem."""
    labels = ["A"] + (["B"] if ctx.config.second_port is not None else [])
    for label in labels:
        ctx.reset_session(label)
        try:
            ctx.session(label)  # a new client, probed with CMD_GET_STATUS: its reply is the status
            s = ctx.target.fresh_status() or ctx.status(label)
        except Exception as exc:
            return f"liveness after abuse: port {label} no longer serves a new client ({exc})"
        if before is not None and (s.op, s.mode) != (before.op, before.mode):
            return (
                f"liveness after abuse: the state changed from {before.describe()} to {s.describe()} "
                "(malformed input must change nothing, erratum E-WIRE-006)"
            )
    return ""


def _resolve(attempts: list[Attempt]) -> tuple[Verdict, str]:
    verdicts = [a.verdict for a in attempts]
    last = attempts[-1]
    definite = [v for v in verdicts if v is not Verdict.INCONCLUSIVE]
    if not definite:
        return Verdict.INCONCLUSIVE, last.message
    if Verdict.PASS in definite and any(v in (Verdict.FAIL, Verdict.NON_STRICT) for v in definite):
        bad = next(a for a in attempts if a.verdict in (Verdict.FAIL, Verdict.NON_STRICT))
        return Verdict.INCONCLUSIVE, (
            f"flaky: {verdicts.count(Verdict.PASS)} of {len(attempts)} attempts "
            f"passed; a failing attempt said: {bad.message}"
        )
    final = definite[-1]
    msg = next(a.message for a in reversed(attempts) if a.verdict is final)
    if len(attempts) > 1 and final is Verdict.PASS:
        msg = f"passed on attempt {len(attempts)}"
    return final, msg


def run(
    config: Config, cases: Sequence[Case], reporters: Sequence[Reporter] = (), baseline: Baseline | None = None
) -> RunResult:
    return Runner(config, cases, reporters, baseline).run()
