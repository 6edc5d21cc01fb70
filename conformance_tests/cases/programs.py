"""Guide 4.5 / 6.5: task programs run in MODE_MOTION_PROGRAM - observed through the parameters they set.

A program here only sets a harmless parameter (ViewPlanObstEnabled, "View the obstacles used for planning")
and waits, so running it moves nothing; what it did is read back with CMD_GET_PLTF_PARAM. The task interpreter
is an optional feature: a target that does not run the program at all is N/A.
"""

from __future__ import annotations

import time

from pltf.conformance_tests.cases._common import MotionMode, param_table
from pltf.conformance_tests.catalogue import Level, case
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import Fail, Inconclusive, NotApplicable
from pltf.spec.codec import build

PROGRAM = MotionMode.MODE_MOTION_PROGRAM
KEY = "ViewPlanObstEnabled"
_RUN = (
    'guide 4.5: "A task is a list of commands, which define actions or behaviours of the platform"; 6.5 '
    '<parameter><set key value/> "Used to set a platform parameter", <wait><delay amount/> "Makes the '
    'task wait for a specified time"; MODE_MOTION_PROGRAM = 5: CMD_START runs the program'
)


def _program(steps: str) -> str:
    return (
        f'<?xml version="1.0" encoding="UTF-8"?>\n<program version="1.0">\n'
        f'  <task name="conformance" id="1" priority="1" version="1.0">\n{steps}  </task>\n</program>\n'
    )


def _set(value: str) -> str:
    return f'    <parameter><set key="{KEY}" value="{value}"/></parameter>\n'


def _delay(ms: int) -> str:
    return f'    <wait><delay amount="{ms}"/></wait>\n'


def _value(ctx: CaseContext) -> str:
    return ctx.get("CMD_GET_PLTF_PARAM", key=KEY).value  # type: ignore[attr-defined, no-any-return]


def _prepare(ctx: CaseContext, steps: str) -> tuple[str, str]:
    """Load a program and select MODE_MOTION_PROGRAM in Ready; (old value, the value the program sets)."""
    ctx.ready()
    if KEY not in param_table(ctx):
        raise NotApplicable(f"the target does not list {KEY}")
    ctx.preserve_document("program")
    old = ctx.preserve_param(KEY)
    new = "false" if old.strip().lower() in ("true", "1") else "true"
    ctx.send("CMD_SET_PROGRAM", xml=_program(steps.format(new=new, old=old)))
    ctx.send("CMD_SET_MODE", mode=PROGRAM)
    if ctx.poll(ctx.status, lambda s: s.mode == PROGRAM, within=2.0).mode != PROGRAM:
        raise NotApplicable("the target does not take MODE_MOTION_PROGRAM")
    ctx.on_exit("stop the program", ctx.ready)
    return old, new


def _until(ctx: CaseContext, value: str, within: float) -> bool:
    return ctx.poll(lambda: _value(ctx), lambda v: v.strip().lower() == value, within=within).strip().lower() == value


@case(
    "4.5/program/runs-on-start",
    level=Level.MAY,
    group="programs",
    timing=True,
    requirement=_RUN,
    telegrams=("CMD_SET_PROGRAM", "CMD_START"),
)
def runs_on_start(ctx: CaseContext) -> None:
    old, new = _prepare(ctx, _set("{new}") + _delay(1500) + _set("{old}"))
    if ctx.link_paced():
        _runs_on_start_sampled(ctx, old.strip().lower(), new)
        return
    ctx.send("CMD_START")
    started = time.monotonic()
    if not _until(ctx, new, 3.0):
        raise NotApplicable("CMD_START in MODE_MOTION_PROGRAM did not run the program (no parameter changed)")
    ctx.sleep(0.8)  # exactly 0.8 simulated s: a poll's wall-time floor would outlast the delay at a high time scale
    # the program set the value at CMD_START or later, so it must still hold up to 1.5 simulated s after CMD_START;
    # a reading that reaches the target after that (the suite saw the value late, or slept long: a loaded machine)
    # cannot tell a delay from none
    asked = (time.monotonic() - started + (ctx.config.reply_time or 0.0) / 2) * ctx.config.time_scale
    if _value(ctx).strip().lower() != new:
        if asked >= 1.5:
            raise Inconclusive(
                f"the value was read {asked:.2f} simulated s after CMD_START, past the program's delay of 1.5 s: "
                "the suite was late (a loaded machine), not the target"
            )
        raise Fail('the program\'s <delay amount="1500"/> did not delay the next step')
    if not _until(ctx, old.strip().lower(), 5.0):
        raise Fail("the program did not go on after its delay")


@case(
    "4.5/program/stop-aborts",
    level=Level.SHOULD,
    group="programs",
    timing=True,
    requirement=_RUN + "; CMD_STOP aborts the running program (issue 6)",
    telegrams=("CMD_STOP",),
)
def stop_aborts(ctx: CaseContext) -> None:
    _, new = _prepare(ctx, _set("{new}") + _delay(2000) + _set("{old}"))
    if ctx.link_paced():
        _stop_aborts_sampled(ctx, new)
        return
    ctx.send("CMD_START")
    if not _until(ctx, new, 3.0):
        raise NotApplicable("the program did not run")
    ctx.send("CMD_STOP")
    ctx.sleep(3.0)
    if _value(ctx).strip().lower() != new:
        raise Fail("the program went on after CMD_STOP")


@case(
    "4.5/program/break-pauses",
    level=Level.SHOULD,
    group="programs",
    timing=True,
    requirement=_RUN + "; CMD_BREAK pauses the program and CMD_CONTINUE resumes it (issue 6)",
    telegrams=("CMD_BREAK", "CMD_CONTINUE"),
)
def break_pauses(ctx: CaseContext) -> None:
    _, new = _prepare(ctx, _delay(1500) + _set("{new}"))
    ctx.send("CMD_START")
    ctx.send("CMD_BREAK")
    ctx.poll(ctx.status, lambda s: s.op == 2, within=2.0)
    ctx.sleep(3.0)
    if _value(ctx).strip().lower() == new:
        raise Fail("the program went on in Breaked")
    ctx.send("CMD_CONTINUE")
    if not _until(ctx, new, 5.0):
        raise NotApplicable("the program did not run after CMD_CONTINUE (or not at all)")


# ---- the same judgements through a slow link (issue 17): a poll one request at a time samples the parameter once a
# reply time, two simulated s through a link of 200 ms at time scale 10 - longer than the program's delays. There
# the parameter is sampled every 0.1 simulated s (CaseContext.timeline) and each reading judged at the time it was
# asked; CMD_STOP leaves at a fixed time, half the program's delay after CMD_START (a reply comes too late to react).


def _values(ctx: CaseContext, seconds: float, events: list[tuple[float, str]]) -> list[tuple[float, str]]:
    ask = build("request", "CMD_GET_PLTF_PARAM", key=KEY)
    sent = [(t, build("request", name)) for t, name in events]
    return [(t, r.value.strip().lower()) for t, r in ctx.timeline(ask, seconds, sent)]  # type: ignore[attr-defined]


def _first(samples: list[tuple[float, str]], after: float) -> str | None:
    return next((v for t, v in samples if t >= after), None)


def _runs_on_start_sampled(ctx: CaseContext, old: str, new: str) -> None:
    samples = _values(ctx, 3.0 + 0.8 + 5.0, [(0.0, "CMD_START")])
    began = next((t for t, v in samples if v == new and t <= 3.0), None)
    if began is None:
        raise NotApplicable("CMD_START in MODE_MOTION_PROGRAM did not run the program (no parameter changed)")
    if _first(samples, began + 0.8) != new:
        raise Fail('the program\'s <delay amount="1500"/> did not delay the next step')
    if not any(v == old for t, v in samples if began + 0.8 <= t <= began + 0.8 + 5.0):
        raise Fail("the program did not go on after its delay")


def _stop_aborts_sampled(ctx: CaseContext, new: str) -> None:
    stop = 1.0  # half the program's delay
    samples = _values(ctx, stop + 3.0 + 0.5, [(0.0, "CMD_START"), (stop, "CMD_STOP")])
    if not any(v == new for t, v in samples if t < stop):
        raise NotApplicable("the program did not run")
    if _first(samples, stop + 3.0) != new:
        raise Fail("the program went on after CMD_STOP")
