"""The runner against the tiny fake target: verdicts, re-runs, the safety gate, liveness, exit codes."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from pltf.conformance_tests.baseline import Baseline
from pltf.conformance_tests.catalogue import Case, Level, Tier, Verdict, load_all, select
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import Fail, Inconclusive, NotApplicable
from pltf.conformance_tests.runner import Runner
from pltf.conformance_tests.target import Config
from tests.conformance_tests.fakes import TinyTarget


def make(case_id: str, func: Callable[[Any], None], **kw: Any) -> Case:
    kw.setdefault("level", Level.MUST)
    return Case(
        id=case_id, func=func, requirement="a test requirement of the runner", tier=Tier.SMOKE, group="state", **kw
    )


def run(config: Config, *cases: Case, **kw: Any) -> dict[str, Any]:
    result = Runner(config, cases, baseline=kw.pop("baseline", None)).run()
    return {"run": result, **{r.case.id: r for r in result.results}}


def test_outcomes_become_verdicts_by_level(tiny_config: Config) -> None:
    def fail(ctx: CaseContext) -> None:
        ctx.status()
        raise Fail("broken")

    def na(ctx: CaseContext) -> None:
        raise NotApplicable("no such hardware")

    def bug(ctx: CaseContext) -> None:
        raise KeyError("oops")

    out = run(
        tiny_config,
        make("6.1/t/pass", lambda ctx: ctx.status()),
        make("6.1/t/must", fail),
        make("6.1/t/should", fail, level=Level.SHOULD),
        make("6.1/t/may", fail, level=Level.MAY),
        make("6.1/t/na", na),
        make("6.1/t/bug", bug),
    )
    assert [out[k].verdict for k in ("6.1/t/pass", "6.1/t/must", "6.1/t/should", "6.1/t/may", "6.1/t/na")] == [
        Verdict.PASS,
        Verdict.FAIL,
        Verdict.NON_STRICT,
        Verdict.NA,
        Verdict.NA,
    ]
    assert out["6.1/t/bug"].verdict is Verdict.ERROR and "KeyError" in out["6.1/t/bug"].message
    assert out["6.1/t/must"].wire and out["6.1/t/must"].message == "broken"
    assert out["run"].exit_code == 2


def test_deviations_are_graded_by_profile(tiny_config: Config) -> None:
    def deviate(ctx: CaseContext) -> None:
        ctx.deviate("E-REP-009", 0, "BYTE")

    c = make("6.4/t/dev", deviate)
    assert run(tiny_config, c)["6.4/t/dev"].verdict is Verdict.FAIL
    tiny_config.profile = "original"
    r = run(tiny_config, c)
    assert r["6.4/t/dev"].verdict is Verdict.NON_STRICT and "E-REP-009" in r["6.4/t/dev"].message
    assert r["run"].exit_code == 0


def test_inconclusive_is_rerun_and_a_flake_is_reported(tiny_config: Config) -> None:
    calls = {"noisy": 0, "flaky": 0}

    def noisy(ctx: CaseContext) -> None:
        calls["noisy"] += 1
        if calls["noisy"] < 3:
            raise Inconclusive("within the noise")

    def flaky(ctx: CaseContext) -> None:
        calls["flaky"] += 1
        if calls["flaky"] == 1:
            raise Fail("too late")

    out = run(tiny_config, make("6.1/t/noisy", noisy), make("6.1/t/flaky", flaky, timing=True))
    assert out["6.1/t/noisy"].verdict is Verdict.PASS and len(out["6.1/t/noisy"].attempts) == 3
    assert out["6.1/t/flaky"].verdict is Verdict.INCONCLUSIVE and "flaky" in out["6.1/t/flaky"].message
    assert out["run"].exit_code == 1


def test_the_safety_gate_skips_motion_outputs_and_shutdown(tiny_config: Config) -> None:
    ran: list[str] = []
    cases = [
        make(f"4.3/t/{n}", lambda ctx, n=n: ran.append(n), **{n: True})
        for n in ("moves_platform", "switches_outputs", "destructive")
    ]
    out = run(tiny_config, *cases)
    assert ran == [] and all(out[c.id].verdict is Verdict.SKIPPED for c in cases)
    assert "allow-motion" in out["4.3/t/moves_platform"].message
    tiny_config.allow_motion = True
    out = run(tiny_config, *cases)
    assert ran == ["moves_platform", "switches_outputs"] and out["run"].exit_code == 0


def test_an_abuse_that_changes_the_state_fails_liveness(tiny_config: Config) -> None:
    def abuse(ctx: CaseContext) -> None:
        ctx.ready()
        ctx.before_abuse()
        ctx.fresh().send_raw(bytes.fromhex("ff01fe02 00000005 0f 00000003"), "a valid SET_MODE, as abuse")

    r = run(tiny_config, make("6.2/t/abuse", abuse, abuse=True))["6.2/t/abuse"]
    assert r.verdict is Verdict.FAIL and "state changed" in r.message


def test_ensure_walks_the_chart(tiny: TinyTarget, tiny_config: Config) -> None:
    seen = []

    def walk(ctx: CaseContext) -> None:
        for state in (St.BREAKED, St.CONNECTED, St.RUNNING, St.NOT_CONNECTED, St.READY):
            ctx.ensure(state, mode=3)
            seen.append(tiny.state)

    assert run(tiny_config, make("4.2/t/walk", walk))["4.2/t/walk"].verdict is Verdict.PASS
    assert seen == [St.BREAKED, St.CONNECTED, St.RUNNING, St.NOT_CONNECTED, St.READY] and tiny.mode == 3


def test_ensure_reads_no_status_it_just_read(tiny: TinyTarget, tiny_config: Config) -> None:
    """Each round trip counts against a slow link (issue 17): a status read a moment ago with nothing sent since
    stands for the current one; anything sent since (a raw frame too) asks again."""
    sent: list[list[str]] = []

    def tx(ctx: CaseContext) -> list[str]:
        return [e.note for e in ctx.log.entries if e.direction == "tx"]

    def walk(ctx: CaseContext) -> None:
        ctx.ensure(St.READY)
        ctx.status()
        before = len(tx(ctx))
        ctx.ensure(St.RUNNING)
        sent.append(tx(ctx)[before:])
        ctx.session().send_raw(bytes.fromhex("ff01fe02 00000001 0c"), "CMD_BREAK, raw")
        before = len(tx(ctx))
        ctx.ensure(St.BREAKED)
        sent.append(tx(ctx)[before:])
        ctx.status()
        before = len(tx(ctx))
        ctx.ensure(St.BREAKED)
        sent.append(tx(ctx)[before:])

    assert run(tiny_config, make("4.2/t/memo", walk))["4.2/t/memo"].verdict is Verdict.PASS
    assert sent[0][0] == "CMD_START + CMD_GET_STATUS"  # no GET_STATUS first (the way pipelined, E-WIRE-008)
    assert sent[1][0] == "CMD_GET_STATUS"  # the raw BREAK was sent since
    assert sent[2][0].startswith("CMD_STOP + CMD_GET_STATUS + CMD_START")  # in Breaked: via Ready, as before
    assert tiny.state is St.BREAKED


def test_the_chart_cases_pass_an_independent_implementation(tiny_config: Config) -> None:
    cases = select(load_all().values(), tier=Tier.STANDARD, keyword="6.3/CMD_*/in-*")
    assert len(cases) == 40
    out = run(tiny_config, *cases)
    assert {r.verdict for r in out["run"].results} == {Verdict.PASS}


def test_baseline_expected_and_stale(tiny_config: Config) -> None:
    def fail(ctx: CaseContext) -> None:
        raise Fail("known")

    load_all()
    c = make("6.1/ports/reconnect", fail)
    out = run(tiny_config, c, baseline=Baseline.parse("6.1/ports/reconnect FAIL"))
    assert out["6.1/ports/reconnect"].expected_failure and out["run"].exit_code == 0
    out = run(
        tiny_config, make("6.1/ports/reconnect", lambda ctx: None), baseline=Baseline.parse("6.1/ports/reconnect FAIL")
    )
    assert out["run"].exit_code == 1 and out["run"].stale


def test_an_unreachable_target_is_a_harness_error() -> None:
    import socket

    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    out = run(Config("127.0.0.1", port), make("6.1/t/x", lambda ctx: None))
    assert out["run"].exit_code == 2 and out["run"].harness_error


def test_no_rerun_and_a_clipped_case_budget_once_the_run_budget_is_spent(tiny_config: Config, monkeypatch: Any) -> None:
    """A run ends within its budget (issue 17: a case begun at 279 s with two re-runs ended a run at 310 s).

    The cases wait for the runner's own end of the run, not for a fixed time: the connection and the pace
    measurement before the first case take what the machine gives them (CI, stop 28: with a fixed 0.2 s budget
    they took it all, and the slow case was never run)."""
    import time

    from pltf.conformance_tests import runner

    monkeypatch.setattr(runner, "LAST_CASE_GRACE", 0.3)
    tiny_config.run_budget = 3.0
    waited: list[float] = []

    def until_end(r: Runner, before: float) -> None:
        assert r._run_end is not None
        time.sleep(max(0.0, r._run_end - before - time.monotonic()))

    def late(ctx: CaseContext) -> None:
        until_end(late_run, -0.1)  # the budget is spent during this case
        raise Inconclusive("a measurement spoiled by the machine (would be re-run)")

    def slow(ctx: CaseContext) -> None:
        t0 = time.monotonic()
        try:
            ctx.poll(ctx.status, lambda s: False, within=100.0)  # waits until its budget ends
        finally:
            waited.append(time.monotonic() - t0)

    late_run = Runner(tiny_config, [make("6.1/t/late", late)])
    (late_result,) = late_run.run().results
    assert len(late_result.attempts) == 1  # the budget was spent during it: no re-run
    slow_run = Runner(
        tiny_config, [make("6.1/t/first", lambda ctx: until_end(slow_run, 1.0)), make("6.1/t/slow", slow)]
    )
    result = slow_run.run()
    assert waited, f"the slow case was not run: {result.results[-1].message}"
    assert result.results[-1].verdict is Verdict.INCONCLUSIVE
    assert waited[0] < 2.0  # about the 1 s left of the run, not the case budget of 54 s
