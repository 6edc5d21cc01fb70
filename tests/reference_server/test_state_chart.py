"""The state chart table (guide 4.2 figure 2) in isolation."""

from __future__ import annotations

import pytest

from pltf.reference_server.state_chart import (
    ANY,
    CAN_UP,
    EMERGENCY_RESET_TIME,
    RULES,
    EmergencyState,
    OperationState,
    State,
    StateChart,
)
from pltf.spec.codec import REQUESTS

NC, CO, RD, RU, BR = State

# The transitions of guide 4.2 / 6.3, written out independently of RULES: (command, from) -> to.
GUIDE_TRANSITIONS = {
    ("CMD_CONNECT_TO_PLTF", NC): CO,
    ("CMD_INIT_PLTF", CO): RD,
    ("CMD_START", RD): RU,
    ("CMD_BREAK", RU): BR,
    ("CMD_CONTINUE", BR): RU,
    ("CMD_STOP", RU): RD,
    ("CMD_STOP", BR): RD,
    **{("CMD_SHUTDOWN_PLTF", s): NC for s in (CO, RD, RU, BR)},
}
MOVES = {"CMD_MOVE_PATH", "CMD_MOVE_TO_STATION", "CMD_MOVE_ABS", "CMD_MOVE_REL", "CMD_MOVE_VEL_WHEEL", "CMD_MOVE_VEL"}


def chart_in(state: State) -> StateChart:
    chart = StateChart()
    chart.state = state
    return chart


def test_every_telegram_of_the_spec_has_a_rule() -> None:
    assert set(RULES) == {cls.NAME for cls in REQUESTS}


def test_every_get_request_is_allowed_everywhere() -> None:
    for cls in REQUESTS:
        if cls.DEF.answered:
            assert RULES[cls.NAME].allowed == ANY, cls.NAME


@pytest.mark.parametrize("state", list(State))
@pytest.mark.parametrize("name", sorted(RULES))
def test_transitions_match_the_guide(name: str, state: State) -> None:
    chart = chart_in(state)
    reason = chart.check(name)
    expected = GUIDE_TRANSITIONS.get((name, state))
    if expected is not None:
        assert reason is None
        assert chart.fire(name) == (state, expected)
    elif reason is None:
        assert chart.fire(name) == (state, state), f"{name} must not change the state"
    else:
        assert f"command {name} not allowed in state {state.value}" == reason


def test_only_the_guide_transitions_change_the_state() -> None:
    changing = {(n, s) for n, rule in RULES.items() for s in rule.allowed if rule.target not in (None, s)}
    assert changing == set(GUIDE_TRANSITIONS)


def test_reported_states() -> None:
    assert chart_in(NC).operation_state == OperationState.ST_OP_NOT_INITIALIZED
    assert chart_in(CO).operation_state == OperationState.ST_OP_NOT_INITIALIZED
    assert chart_in(RD).operation_state == OperationState.ST_OP_READY
    assert chart_in(RU).operation_state == OperationState.ST_OP_RUNNING
    assert chart_in(BR).operation_state == OperationState.ST_OP_BREAKED
    assert [chart_in(s).initialized for s in State] == [False, False, True, True, True]


def test_set_mode_only_in_ready_and_moves_only_in_running() -> None:
    assert RULES["CMD_SET_MODE"].allowed == {RD}
    for name in MOVES:
        assert RULES[name].allowed == {RU}
    assert RULES["CMD_SET_BRAKE"].allowed == CAN_UP


@pytest.mark.parametrize("state", [RU, BR])
def test_emergency_press_brings_motion_states_to_ready(state: State) -> None:
    chart = chart_in(state)
    assert chart.press_emergency() == (state, RD)
    assert chart.emergency == EmergencyState.ST_EM_ACTIVE


def test_emergency_blocks_start_continue_and_moves_until_released() -> None:
    chart = chart_in(RD)
    chart.press_emergency()
    assert "emergency" in (chart.check("CMD_START") or "")
    chart.state = BR
    assert "emergency" in (chart.check("CMD_CONTINUE") or "")
    chart.state = RU
    for name in MOVES:
        assert "emergency" in (chart.check(name) or "")
    chart.state = RD
    assert chart.check("CMD_SET_MODE") is None
    assert chart.check("CMD_GET_STATUS") is None
    assert chart.release_emergency(10.0)
    assert chart.emergency == EmergencyState.ST_EM_RESET
    assert chart.check("CMD_START") is None  # guide 4.2: after the reset the platform is 'Ready' again
    assert not chart.tick(10.0 + EMERGENCY_RESET_TIME / 2)
    assert chart.tick(10.0 + EMERGENCY_RESET_TIME)
    assert chart.emergency == EmergencyState.ST_EM_NOT_ACTIVE


def test_release_without_press_and_press_during_reset() -> None:
    chart = chart_in(NC)
    assert not chart.release_emergency(0.0)
    assert chart.press_emergency() == (NC, NC)
    chart.release_emergency(1.0)
    chart.press_emergency()
    assert not chart.tick(5.0)
    assert chart.emergency == EmergencyState.ST_EM_ACTIVE


def test_exit_drops_the_can_bus() -> None:
    chart = chart_in(RU)
    chart.shutdown()
    assert chart.state is NC
