"""pace.py: the early measurement of the target's reply time, the budgets, and the watch that ends a run against
a target that stopped answering - each against a tiny target that is slow or stuck on request."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from pltf.conformance_tests import pace
from pltf.conformance_tests.catalogue import Case, Level, Tier, Verdict
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.runner import Runner, RunResult
from pltf.conformance_tests.target import Config, Target
from tests.conformance_tests.fakes import TinyTarget
from tests.conformance_tests.relays import Relay


class SlowTarget(TinyTarget):
    """TinyTarget whose replies take ``delay`` s; ``stuck`` makes it answer nobody until cleared."""

    def __init__(self, delay: float = 0.0) -> None:
        super().__init__()
        self.delay = delay
        self.stuck = threading.Event()

    def handle(self, t: Any) -> Any:
        while self.stuck.is_set() and not self._stop.is_set():
            time.sleep(0.01)
        reply = super().handle(t)
        if reply is not None and self.delay:
            time.sleep(self.delay)
        return reply


@pytest.fixture
def slow() -> Iterator[SlowTarget]:
    with SlowTarget() as target:
        yield target


def config(target: TinyTarget, **kw: Any) -> Config:
    kw = {"reply_timeout": 0.5, "connect_window": 1.0, "min_wall": 0.05, **kw}
    return Config("127.0.0.1", target.ports[0], target.ports[1], time_scale=10.0, reruns=2, **kw)


def cases(n: int, func: Callable[[CaseContext], None] = lambda ctx: ctx.status()) -> list[Case]:
    return [
        Case(
            id=f"6.1/pace/c{i:02}",
            func=func,
            requirement="a test case of the pace",
            level=Level.MUST,
            tier=Tier.SMOKE,
            group="state",
        )
        for i in range(n)
    ]


def run(cfg: Config, chosen: list[Case]) -> RunResult:
    return Runner(cfg, chosen).run()


def test_the_reply_time_is_measured_once_and_scales_the_waits(slow: SlowTarget) -> None:
    slow.delay = 0.15
    cfg = config(slow)
    result = run(cfg, cases(2))
    assert [r.verdict for r in result.results] == [Verdict.PASS] * 2
    assert cfg.min_wall >= 2 * 0.15 and cfg.probe_timeout >= 4 * 0.15
    assert "answers CMD_GET_STATUS in 1" in result.notes[0]  # ~150 ms


def test_a_target_slower_than_the_reply_timeout_is_named_at_the_start(slow: SlowTarget) -> None:
    slow.delay = 1.2
    cfg = config(slow)
    p = Runner(cfg, []).prepare()
    assert p.reply is not None and p.reply >= 1.2
    assert cfg.min_wall == 0.05, "a target slower than MAX_SCALED does not stretch the waits"
    assert "over the reply timeout of 0.5 s" in p.describe(cfg)


def test_a_target_that_stops_answering_ends_the_run_soon_and_says_why(slow: SlowTarget) -> None:
    def first_then_stuck(ctx: CaseContext) -> None:
        ctx.status()
        slow.stuck.set()

    chosen = [cases(1, first_then_stuck)[0], *cases(40)[1:]]
    t0 = time.monotonic()
    result = run(config(slow), chosen)
    verdicts = [r.verdict for r in result.results]
    assert verdicts[0] is Verdict.PASS
    assert verdicts[1 : 1 + pace.STUCK_AFTER] == [Verdict.FAIL] * pace.STUCK_AFTER  # the target's own failures
    rest = result.results[1 + pace.STUCK_AFTER :]
    assert rest and all(r.verdict is Verdict.INCONCLUSIVE for r in rest)
    assert all(r.message.startswith("not run: the target stopped answering at 6.1/pace/c01") for r in rest)
    assert result.exit_code == 1
    assert time.monotonic() - t0 < 30, "40 cases against a stuck target"
    slow.stuck.clear()


def test_cases_run_again_when_the_target_answers_again(slow: SlowTarget, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(pace, "RECHECK", 0.5)
    timer = threading.Timer(4.0, slow.stuck.clear)  # the target answers again after a while

    def first_then_stuck(ctx: CaseContext) -> None:
        ctx.status()
        slow.stuck.set()
        timer.start()

    def paced(ctx: CaseContext) -> None:
        time.sleep(0.1)
        ctx.status()

    try:
        result = run(config(slow), [cases(1, first_then_stuck)[0], *cases(60, paced)[1:]])
    finally:
        timer.cancel()
    verdicts = [r.verdict for r in result.results]
    assert Verdict.INCONCLUSIVE in verdicts and verdicts[-1] is Verdict.PASS, verdicts
    back = verdicts.index(Verdict.PASS, 1)
    assert verdicts[1 : 1 + pace.STUCK_AFTER] == [Verdict.FAIL] * pace.STUCK_AFTER
    assert all(v is Verdict.INCONCLUSIVE for v in verdicts[1 + pace.STUCK_AFTER : back])
    assert all(v is Verdict.PASS for v in verdicts[back:])


def test_a_case_over_its_budget_is_inconclusive_and_not_rerun(slow: SlowTarget) -> None:
    def forever(ctx: CaseContext) -> None:
        ctx.poll(ctx.status, lambda s: False, within=1000.0)

    t0 = time.monotonic()
    (r,) = run(config(slow, case_budget=1.0), cases(1, forever)).results
    assert r.verdict is Verdict.INCONCLUSIVE and r.message.startswith("case budget of 1 s spent")
    assert len(r.attempts) == 1 and time.monotonic() - t0 < 10


def test_the_run_budget_leaves_the_rest_not_run(slow: SlowTarget) -> None:
    def slow_case(ctx: CaseContext) -> None:
        ctx.status()
        time.sleep(0.6)

    result = run(config(slow, run_budget=1.0), cases(6, slow_case))
    verdicts = [r.verdict for r in result.results]
    assert verdicts[:2] == [Verdict.PASS] * 2 and verdicts[-1] is Verdict.INCONCLUSIVE
    assert result.results[-1].message == "not run: the run's budget of 1 s is spent (--budget)"


def test_the_default_run_budget_is_five_minutes_unless_the_time_scale_needs_more() -> None:
    assert pace.run_budget(Config("h", 1, time_scale=10.0)) == 280.0
    assert pace.run_budget(Config("h", 1, time_scale=1.0)) == 680.0


def test_the_connection_set_up_is_measured_and_scales_the_newcomer_waits(tiny: TinyTarget) -> None:
    """Issue 32: behind a timer-driven accept (every 0.3 s) a new connection is answered up to a tick after its
    connect; the run says so, and the probe of a new connection and the waits on a newcomer allow for it."""
    with Relay(tiny.ports, accept_every=0.3) as relay:
        cfg = Config("127.0.0.1", relay.ports[0], relay.ports[1], time_scale=10.0, min_wall=0.05)
        p = pace.measure(Target(cfg))
    assert 0.05 < p.setup < 1.0, p
    assert p.reply is not None and p.reply < p.setup
    assert "a new connection is answered" in p.describe(cfg)
    pace.apply(p, cfg)
    assert cfg.probe_timeout >= pace.SCALE * p.setup
    ctx = CaseContext(Target(cfg), cases(1)[0])
    assert ctx.newcomer_wait(1.0) == pytest.approx(0.1 + p.setup)


def test_a_target_that_serves_at_once_has_no_set_up_to_speak_of(tiny: TinyTarget) -> None:
    p = pace.measure(Target(config(tiny)))
    assert p.setup < 0.05, p
