"""Guide 4.2 / 6.3: every command of the state chart in every state (allowed: effect; not allowed: none)."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

from pltf.conformance_tests import chart
from pltf.conformance_tests.cases._common import (
    NO,
    STATES,
    MotionMode,
    expect_state,
    expect_unchanged,
    no_unsolicited,
    probe_connected,
)
from pltf.conformance_tests.catalogue import Level, Tier, add, case
from pltf.conformance_tests.chart import St
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import Fail, NotApplicable
from pltf.conformance_tests.target import Status
from pltf.conformance_tests.wire import Pause
from pltf.spec.codec import build

_GUIDE_TEXT = {
    "CMD_CONNECT_TO_PLTF": 'guide 4.2: "The initialization process starts with the command CMD_CONNECT_CAN" '
    "(= CMD_CONNECT_TO_PLTF, erratum E-CMD-002)",
    "CMD_INIT_PLTF": 'guide 4.2: "The command CMD_INIT_CAN initializes all hardware components and executes a '
    'platform self test" (= CMD_INIT_PLTF, erratum E-CMD-002)',
    "CMD_SHUTDOWN_PLTF": 'guide 6.3 CMD_SHUTDOWN_PLTF: "Used to shutdown the CAN communication."',
    "CMD_START": 'guide 6.3 CMD_START: "Start a platform motion mode. The operation state changes into the state '
    "'Moving'.\"; 4.2: \"In the state 'Initialized' the platform can be started\"",
    "CMD_BREAK": 'guide 6.3 CMD_BREAK: "Break a platform motion mode. The operation state changes into the state '
    "'Break'.\"",
    "CMD_CONTINUE": 'guide 6.3 CMD_CONTINUE: "Continue the execution of a platform motion mode. The operation state '
    "changes into the state 'Moving'.\"",
    "CMD_STOP": 'guide 6.3 CMD_STOP: "Stop the motion of the platform. The operation state changes into the state '
    "'Ready'\"",
    "CMD_SET_MODE": "guide 6.3 CMD_SET_MODE: \"The operation state has to be in 'Ready' before changing to another "
    'motion mode."',
}
_DECISION = "; the project's state chart (figure 2 is lost in the text guide, erratum {erratum}): {what}"


def _fields(command: str) -> dict[str, Any]:
    return {"mode": MotionMode.MODE_MOTION_VEL} if command == "CMD_SET_MODE" else {}


def _mode_is(mode: int) -> Callable[[Status], bool]:
    return lambda s: s.mode == mode


def _cell(ctx: CaseContext, state: St, command: str) -> None:
    how = f"{command} in {state.value}"
    dest = chart.target(state, command)
    ask = build("request", "CMD_GET_STATUS")
    sent = build("request", command, **_fields(command))
    if chart.allowed(state, command):
        _, rest = ctx.enter(state, NO, then=[sent, ask])
        (first,) = rest()
        mode = MotionMode.MODE_MOTION_VEL if command == "CMD_SET_MODE" else None
        slow = command in ("CMD_CONNECT_TO_PLTF", "CMD_INIT_PLTF")  # a real platform tests its hardware
        expect_state(ctx, dest, how, mode=mode, within=30.0 if slow else 5.0, first=Status.of(first))
        if dest is St.CONNECTED:
            probe_connected(ctx, how)
    else:
        before, rest = ctx.enter(state, NO, then=[sent, Pause(ctx.settle_time()), ask])
        (after,) = rest()
        expect_unchanged(ctx, state, before, how, after=Status.of(after))
    no_unsolicited(ctx, command)
    ctx.target.coverage.transition(state, command, dest)


def _requirement(state: St, command: str) -> str:
    base = _GUIDE_TEXT[command]
    dest = chart.target(state, command)
    if chart.allowed(state, command):
        what = f"allowed in {state.value}, leads to {dest.value}"
    else:
        what = f"not allowed in {state.value}: changes nothing"
    if (state, command) in chart.GUIDE:
        return f"{base} ({what})"
    return base + _DECISION.format(erratum=chart.DECIDED_BY[state, command], what=what)


for _command in chart.CHART_COMMANDS:
    for _state in STATES:
        add(
            f"6.3/{_command}/in-{_state.value}",
            partial(_cell, state=_state, command=_command),
            requirement=_requirement(_state, _command),
            level=Level.MUST if (_state, _command) in chart.GUIDE else None,  # None: the erratum's level
            errata=() if (_state, _command) in chart.GUIDE else (chart.DECIDED_BY[_state, _command],),
            tier=Tier.STANDARD,
            group="state",
            telegrams=(_command, "CMD_GET_STATUS"),
        )


@case(
    "4.2/chart/full-cycle",
    tier=Tier.SMOKE,
    group="state",
    requirement="guide 4.2 and 6.3: connect, initialize, start, break, continue, stop and shut down walk the "
    "state chart, each change visible in CMD_GET_STATUS",
    telegrams=chart.CHART_COMMANDS,
)
def full_cycle(ctx: CaseContext) -> None:
    ctx.ensure(St.NOT_CONNECTED)
    walk = [
        ("CMD_CONNECT_TO_PLTF", St.NOT_CONNECTED, St.CONNECTED),
        ("CMD_INIT_PLTF", St.CONNECTED, St.READY),
        ("CMD_START", St.READY, St.RUNNING),
        ("CMD_BREAK", St.RUNNING, St.BREAKED),
        ("CMD_CONTINUE", St.BREAKED, St.RUNNING),
        ("CMD_STOP", St.RUNNING, St.READY),
        ("CMD_SHUTDOWN_PLTF", St.READY, St.NOT_CONNECTED),
    ]
    for command, source, dest in walk:
        ctx.send(command)
        expect_state(ctx, dest, f"{command} in {source.value}", within=30.0)
        ctx.target.coverage.transition(source, command, dest)
    ctx.ready()


@case(
    "6.3/CMD_SET_MODE/every-mode",
    tier=Tier.SMOKE,
    group="state",
    requirement='guide 6.3 CMD_SET_MODE: "Set the motion mode of the platform" - MODE_MOTION_NO, JOYSOFT, VEL and '
    "AUTOMATIC (4.3) are set in Ready and reported in CMD_GET_STATUS 'Active motion mode'",
    telegrams=("CMD_SET_MODE",),
)
def every_mode(ctx: CaseContext) -> None:
    ctx.ready()
    for mode in (MotionMode.MODE_MOTION_VEL, MotionMode.MODE_MOTION_JOYSOFT, MotionMode.MODE_MOTION_AUTOMATIC, NO):
        ctx.send("CMD_SET_MODE", mode=mode)
        expect_state(ctx, St.READY, f"CMD_SET_MODE({MotionMode(mode).name})", mode=mode, within=5.0)


@case(
    "6.3/CMD_SET_MODE/optional-modes",
    level=Level.MAY,
    group="state",
    requirement="guide 6.3 CMD_SET_MODE lists MODE_MOTION_JOYHARD = 1, MODE_MOTION_PROGRAM = 5 and "
    "MODE_MOTION_POST_PROCESS_REPLAY = 6; a platform without a hardware joystick, task interpreter or "
    "replay may refuse them",
    telegrams=("CMD_SET_MODE",),
)
def optional_modes(ctx: CaseContext) -> None:
    ctx.ready()
    missing = []
    for mode in (
        MotionMode.MODE_MOTION_JOYHARD,
        MotionMode.MODE_MOTION_PROGRAM,
        MotionMode.MODE_MOTION_POST_PROCESS_REPLAY,
    ):
        ctx.send("CMD_SET_MODE", mode=mode)
        s = ctx.poll(ctx.status, _mode_is(mode), within=5.0)
        if s.mode != mode:
            missing.append(MotionMode(mode).name)
        ctx.send("CMD_SET_MODE", mode=NO)
    if missing:
        raise NotApplicable(f"the target did not take {', '.join(missing)}")


@case(
    "6.3/CMD_SET_MODE/kept-over-start-stop",
    level=Level.SHOULD,
    group="state",
    requirement="guide 4.3 / 5.6: a motion mode is selected in Ready and then started; CMD_START and CMD_STOP do "
    "not change the selected mode",
    telegrams=("CMD_SET_MODE", "CMD_START", "CMD_STOP"),
)
def mode_kept(ctx: CaseContext) -> None:
    ctx.ready(MotionMode.MODE_MOTION_JOYSOFT)
    for command, state in (("CMD_START", St.RUNNING), ("CMD_BREAK", St.BREAKED), ("CMD_STOP", St.READY)):
        ctx.send(command)
        expect_state(ctx, state, command, mode=MotionMode.MODE_MOTION_JOYSOFT, within=10.0)


@case(
    "6.3/CMD_SET_MODE/out-of-range-changes-nothing",
    level=Level.SHOULD,
    abuse=True,
    group="state",
    errata=("E-WIRE-006",),
    requirement="guide 6.3 CMD_SET_MODE codes the modes 0..6; erratum E-WIRE-006: a telegram with a field out of "
    "its range is malformed input - it changes nothing (the connection may be closed)",
    telegrams=("CMD_SET_MODE",),
)
def mode_out_of_range(ctx: CaseContext) -> None:
    ctx.ready()
    before = ctx.before_abuse()
    s = ctx.fresh()
    s.send_raw(bytes.fromhex("ff01fe02 00000005 0f 00000063"), "CMD_SET_MODE(99)")
    if not s.wait_closed(ctx.wall(1.0)):
        got = s.request(build("request", "CMD_GET_STATUS"))
        if got.motion_mode != before.mode:  # type: ignore[attr-defined]
            raise Fail(f"CMD_SET_MODE(99) changed the motion mode to {got.motion_mode}")  # type: ignore[attr-defined]
        ctx.deviate("E-WIRE-006", 1, "CMD_SET_MODE(99) was ignored and the connection kept open")


@case(
    "6.4/CMD_GET_STATUS/initialized-flag",
    group="state",
    requirement="guide 6.4 CMD_GET_STATUS 'Platform initialization 0: Not initialized 1: Initialized' agrees with "
    "'Active operation state' (ST_OP_NOT_INITIALIZED <=> 0)",
    telegrams=("CMD_GET_STATUS",),
)
def initialized_flag(ctx: CaseContext) -> None:
    for state in (St.NOT_CONNECTED, St.READY, St.RUNNING, St.BREAKED):
        s = ctx.ensure(state)
        if s.initialized != chart.INITIALIZED[state]:
            raise Fail(f"in {state.value} the status says {s.describe()}")
    ctx.ready()
