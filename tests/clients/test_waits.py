"""clients/pltf_client/waits.py without sockets: the judges fed statuses as a platform's control loop makes them.

Issue 22: after a refused goal the platform still shows the refusal (PLANNER_COLLISION_TARGET) in the first status
requested after the next move, until its control loop takes the move up; the wait judged that status and
reported a reachable goal refused. Erratum E-CLI-001 decides which statuses belong to the move.
"""

from __future__ import annotations

from typing import Any

import pytest
from client_fakes import status_telegram

from pltf.client import CommandRejected, MotionMode, OperationState, PlannerState, Status, Timeout
from pltf.client.waits import TAKE_UP_MS, TAKE_UP_S, Belongs, TargetWait, stamp_after

RUNNING, AUTOMATIC = OperationState.ST_OP_RUNNING, MotionMode.MODE_MOTION_AUTOMATIC
COLLISION, FOUND = PlannerState.PLANNER_COLLISION_TARGET, PlannerState.PLANNER_PATH_FOUND
STANDBY = PlannerState.PLANNER_STANDBY


def status(stamp: int, planner: PlannerState = STANDBY, reached: bool = False, **more: Any) -> Status:
    fields = {
        "operation_state": int(RUNNING),
        "motion_mode": int(AUTOMATIC),
        "timestamp": stamp,
        "planner_state": int(planner),
        "target_reached": int(reached),
        **more,
    }
    return Status.from_telegram(status_telegram(**fields))


def judge(seq: int = 10, timeout: float = 60.0) -> TargetWait:
    return TargetWait({"CMD_MOVE_ABS": seq}, now=0.0, timeout=timeout)


def test_a_retried_goal_is_not_judged_by_the_refusal_before_it() -> None:
    # issue 22, bug 1: the goal before was refused; the retried goal is taken up one control period later
    wait = judge()
    assert wait.observe(status(5000, COLLISION), now=0.001, seq=11) is False  # the old verdict: no verdict
    assert wait.observe(status(5020, FOUND), now=0.05, seq=12) is False  # the planner took the move up
    assert wait.observe(status(7000, STANDBY, reached=True), now=3.0, seq=13) is True


def test_a_refusal_of_the_same_kind_is_reported_once_the_platform_time_moved_on() -> None:
    wait = judge()
    assert wait.observe(status(5000, COLLISION), now=0.001, seq=11) is False
    assert wait.observe(status(5000 + TAKE_UP_MS - 1, COLLISION), now=0.01, seq=12) is False
    # made after the take-up time, but a platform may answer before it runs the periods due: the next one counts
    assert wait.observe(status(5000 + TAKE_UP_MS, COLLISION), now=0.02, seq=13) is False
    with pytest.raises(CommandRejected, match=r"CMD_MOVE_ABS .*target collides.*PLANNER_COLLISION_TARGET"):
        wait.observe(status(5000 + TAKE_UP_MS + 20, COLLISION), now=0.03, seq=14)


def test_a_refusal_after_a_different_planner_state_is_reported_at_once() -> None:
    wait = judge()
    assert wait.observe(status(5000, STANDBY), now=0.001, seq=11) is False
    with pytest.raises(CommandRejected, match="PLANNER_NO_PATH"):
        wait.observe(status(5020, PlannerState.PLANNER_NO_PATH), now=0.002, seq=12)


def test_a_stale_target_reached_does_not_end_the_wait() -> None:
    wait = judge()
    assert wait.observe(status(100, STANDBY, reached=True), now=0.0, seq=11) is False  # the move before's flag
    assert wait.observe(status(140, STANDBY, reached=True), now=0.01, seq=12) is False
    assert wait.observe(status(100 + TAKE_UP_MS, STANDBY, reached=True), now=0.02, seq=13) is False
    assert wait.observe(status(120 + TAKE_UP_MS, STANDBY, reached=True), now=0.03, seq=14) is True  # at the goal


def test_a_platform_whose_time_stamp_stands_still_is_judged_after_the_client_waited() -> None:
    wait = judge()
    assert wait.observe(status(0, COLLISION), now=0.0, seq=11) is False
    assert wait.observe(status(0, COLLISION), now=TAKE_UP_S - 0.01, seq=12) is False
    assert wait.observe(status(0, COLLISION), now=TAKE_UP_S, seq=13) is False
    with pytest.raises(CommandRejected):
        wait.observe(status(0, COLLISION), now=TAKE_UP_S + 0.05, seq=14)


def test_state_and_mode_are_judged_at_once() -> None:
    ready = {"operation_state": int(OperationState.ST_OP_READY)}
    with pytest.raises(CommandRejected, match="ST_OP_READY"):
        judge().observe(status(0, **ready), now=0.0, seq=11)
    with pytest.raises(CommandRejected, match="MODE_MOTION_VEL"):
        judge().observe(status(0, motion_mode=int(MotionMode.MODE_MOTION_VEL)), now=0.0, seq=11)


def test_without_a_move_on_the_connection_every_status_counts() -> None:
    wait = TargetWait({}, now=0.0, timeout=1.0)
    assert wait.command is None
    assert wait.observe(status(0, COLLISION, reached=True), now=0.0, seq=1) is True


def test_the_time_out_names_the_move_and_the_pose() -> None:
    wait = judge(timeout=0.5)
    assert wait.observe(status(0, FOUND, est_x=1200), now=0.1, seq=11) is False
    with pytest.raises(Timeout, match=r"within 0.5 s after CMD_MOVE_ABS: the platform is at x=1200 mm"):
        wait.observe(status(20, FOUND, est_x=1200), now=0.5, seq=12)


def test_a_stall_does_not_pass_for_the_take_up() -> None:
    # the reference server after a stall: the status is made at the new time, before the periods that fell due
    belongs = Belongs(started=0.0)
    assert not belongs(status(1000, COLLISION), 0.0)  # the reference
    assert not belongs(status(1000 + 5 * TAKE_UP_MS, COLLISION), 0.05)  # the periods since the move not run yet
    assert belongs(status(1000 + 5 * TAKE_UP_MS + 20, COLLISION), 0.1)  # made after them


def test_belongs_stays_taken_up() -> None:
    belongs = Belongs(started=0.0)
    assert not belongs(status(0, FOUND), 0.0)
    assert belongs(status(0, STANDBY), 0.0)
    assert belongs(status(0, FOUND), 0.0)  # once the move showed, every later status is its


@pytest.mark.parametrize(
    ("later", "earlier", "diff"),
    [(220, 20, 200), (20, 220, -200), (5, 2**31 - 195, 200), (2**31 - 195, 5, -200)],
)
def test_time_stamps_wrap_at_2_31(later: int, earlier: int, diff: int) -> None:
    assert stamp_after(later, earlier) == diff
