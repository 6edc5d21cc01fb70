"""context.py's known state over a slow link (issue 17): the way to a state and what a case sends there go in one
write when the target takes pipelined requests (erratum E-WIRE-008); a target that shows a state late is walked
one leg at a time; a target that answers out of order is never pipelined; a status read stands across cases."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import pytest

from pltf.conformance_tests import chart
from pltf.conformance_tests.catalogue import Case, Level, Tier, Verdict
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.runner import Runner, RunResult
from pltf.conformance_tests.target import Config, Status
from pltf.conformance_tests.wire import Pause
from pltf.spec.codec import build
from tests.conformance_tests.fakes import LinkTarget

ASK = build("request", "CMD_GET_STATUS")


def case(case_id: str, func: Callable[[CaseContext], None]) -> Case:
    return Case(
        id=case_id, func=func, requirement="a test of the context", level=Level.MUST, tier=Tier.SMOKE, group="state"
    )


def run(target: LinkTarget, *cases: Case, time_scale: float = 10.0) -> RunResult:
    config = Config(
        "127.0.0.1", target.ports[0], target.ports[1], time_scale=time_scale, reply_timeout=1.0, connect_window=1.0
    )
    config.min_wall = 0.05
    return Runner(config, cases).run()


def tx(ctx: CaseContext) -> list[str]:
    return [e.note for e in ctx.log.entries if e.direction == "tx"]


@pytest.fixture
def link() -> Iterator[LinkTarget]:
    with LinkTarget() as target:
        yield target


def test_the_way_to_a_state_and_the_step_there_go_in_one_write(link: LinkTarget) -> None:
    seen: dict[str, Any] = {}

    def step(ctx: CaseContext) -> None:
        ctx.ensure(St.NOT_CONNECTED)
        sent = len(tx(ctx))
        before, rest = ctx.enter(St.BREAKED, 3, then=[build("request", "CMD_SET_BRAKE", motor=1, state=0), ASK])
        seen["before"], seen["after"], seen["tx"] = before, Status.of(rest()[0]), tx(ctx)[sent:]

    result = run(link, case("4.2/t/enter", step))
    assert result.config.pipeline and "answers pipelined requests in order" in result.notes[0]
    assert result.results[0].verdict is Verdict.PASS, result.results[0].message
    assert seen["tx"] == [
        "CMD_CONNECT_TO_PLTF + CMD_INIT_PLTF + CMD_GET_STATUS + CMD_SET_MODE + CMD_GET_STATUS + CMD_START + "
        "CMD_BREAK + CMD_GET_STATUS + CMD_SET_BRAKE + CMD_GET_STATUS"
    ]
    assert link.state is St.BREAKED and link.mode == 3
    breaked = (chart.REPORTED[St.BREAKED], 3)
    assert (seen["before"].op, seen["before"].mode) == (seen["after"].op, seen["after"].mode) == breaked


def test_a_state_shown_late_is_walked_again_one_leg_at_a_time(link: LinkTarget) -> None:
    seen: dict[str, Any] = {}

    def step(ctx: CaseContext) -> None:
        ctx.ensure(St.NOT_CONNECTED)
        link.slow_init = True  # the first status after CMD_INIT_PLTF still shows the platform not initialized
        before, rest = ctx.enter(St.RUNNING, then=[build("request", "CMD_SET_BRAKE", motor=1, state=0), ASK])
        seen["before"], seen["after"], seen["prompt"] = before, Status.of(rest()[0]), ctx.target.prompt
        seen["notes"] = list(ctx.notes)
        link.commands.clear()
        ctx.ensure(St.READY)
        ctx.ensure(St.BREAKED)
        seen["tx"] = tx(ctx)

    result = run(link, case("4.2/t/late", step))
    assert result.results[0].verdict is Verdict.PASS, result.results[0].message
    running = chart.REPORTED[St.RUNNING]
    assert seen["before"].op == seen["after"].op == running and not seen["prompt"]  # reached the slow way
    assert "one leg at a time" in seen["notes"][0] and seen["notes"][0] in result.notes
    leg_by_leg = ["CMD_STOP", "CMD_GET_STATUS", "CMD_START", "CMD_BREAK", "CMD_GET_STATUS"]
    assert seen["tx"][-5:] == leg_by_leg and link.commands == leg_by_leg and link.state is St.BREAKED


def test_a_target_that_answers_out_of_order_is_never_pipelined() -> None:
    seen: list[str] = []

    def step(ctx: CaseContext) -> None:
        _, rest = ctx.enter(St.RUNNING, then=[build("request", "CMD_GET_POSITION"), Pause(0.01), ASK])
        assert [r.NAME for r in rest()] == ["CMD_GET_POSITION", "CMD_GET_STATUS"]
        seen.extend(tx(ctx))

    with LinkTarget(reorder=True) as link:
        result = run(link, case("4.2/t/order", step))
    assert not result.config.pipeline and "one at a time (three requests in one write" in result.notes[0]
    assert result.results[0].verdict is Verdict.PASS, result.results[0].message
    assert " + " not in "".join(seen) and seen[-2:] == ["CMD_GET_POSITION", "CMD_GET_STATUS"]


def test_a_status_read_stands_for_the_next_case_until_anything_is_sent(link: LinkTarget) -> None:
    firsts: list[str] = []

    def first(ctx: CaseContext) -> None:
        ctx.ready()
        ctx.send("CMD_SET_MODE", mode=0)
        ctx.status()

    def second(ctx: CaseContext) -> None:
        ctx.ensure(St.RUNNING)
        firsts.append(tx(ctx)[0])

    def third(ctx: CaseContext) -> None:
        ctx.reset_session()  # a new connection: its probe reads the status
        ctx.session()
        ctx.ensure(St.READY)
        last = max(i for i, e in enumerate(ctx.log.entries) if e.note.startswith("connected"))  # the port may be busy
        firsts.append(" / ".join(e.note for e in ctx.log.entries[last:] if e.direction == "tx"))

    result = run(link, case("4.2/t/a", first), case("4.2/t/b", second), case("4.2/t/c", third))
    assert [r.verdict for r in result.results] == [Verdict.PASS] * 3
    assert firsts == [
        "CMD_START + CMD_GET_STATUS",
        "CMD_GET_STATUS / CMD_STOP + CMD_GET_STATUS",
    ]  # the probe's  # no GET_STATUS of their own


def test_a_timeline_samples_at_the_platforms_pace_and_judges_each_reply_at_its_time(link: LinkTarget) -> None:
    seen: dict[str, Any] = {}

    def step(ctx: CaseContext) -> None:
        ctx.ensure(St.NOT_CONNECTED)
        seen["paced"] = ctx.link_paced(0.1)
        events = [(0.0, build("request", "CMD_CONNECT_TO_PLTF")), (0.5, build("request", "CMD_INIT_PLTF"))]
        seen["samples"] = [(t, r.initialized) for t, r in ctx.timeline(ASK, 1.0, events)]  # type: ignore[attr-defined]

    result = run(link, case("4.2/t/timeline", step), time_scale=2.0)  # 0.5 s of wall time: asks 50 ms apart
    assert result.results[0].verdict is Verdict.PASS, result.results[0].message
    samples = seen["samples"]
    assert seen["paced"] and len(samples) >= 8 and [t for t, _ in samples] == sorted(t for t, _ in samples)
    assert all(i == (1 if t >= 0.5 else 0) for t, i in samples)  # each reply as the platform was when asked
    assert link.writes >= 9  # the replies came joined and torn, after the requests stopped
