"""Judges for the client's waits: given the statuses polled so far, done, keep polling, or which error.

Rules:
- Sans-IO: a judge gets each polled ``Status`` with ``now`` (monotonic seconds) and the sequence number of
  the request that fetched it; the sync and asyncio clients only poll and sleep. Both wait the same way.
- Commands are not acknowledged (guide 6.1), so a refused command shows only in the status telegram. A judge
  knows which command the wait follows (``ClientCore.last_sent``) and names it in ``CommandRejected`` when the
  status shows it did not take effect, quoting the rule of the guide (``STATE_COMMANDS``).
- The platform handles one connection's telegrams in order, so a status requested after a command shows
  the platform after that command (the reason a judge ignores statuses requested before it).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from pltf.client._enums import EmergencyState, MotionMode, OperationState, PlannerState
from pltf.client._replies import Status
from pltf.client.errors import CommandRejected, Timeout

_READY, _RUNNING, _BREAKED = OperationState.ST_OP_READY, OperationState.ST_OP_RUNNING, OperationState.ST_OP_BREAKED
_NOT_INITIALIZED = OperationState.ST_OP_NOT_INITIALIZED

# The state chart of guide 4.2 figure 2: command -> (the state it leads to, the rule that lets it run).
STATE_COMMANDS: dict[str, tuple[OperationState, str]] = {
    "CMD_INIT_PLTF": (_READY, "it needs CMD_CONNECT_TO_PLTF first (guide 4.2) and leads to Ready after the self test"),
    "CMD_START": (_RUNNING, "it is accepted only in state Ready (guide 4.2 figure 2, 6.3 CMD_START)"),
    "CMD_BREAK": (_BREAKED, "it is accepted only in state Running (guide 6.3 CMD_BREAK)"),
    "CMD_CONTINUE": (_RUNNING, "it is accepted only in state Breaked, after CMD_BREAK (guide 6.3 CMD_CONTINUE)"),
    "CMD_STOP": (_READY, "it is accepted only in state Running or Breaked (guide 6.3 CMD_STOP)"),
    "CMD_SHUTDOWN_PLTF": (_NOT_INITIALIZED, "it needs the CAN bus up, after CMD_CONNECT_TO_PLTF (guide 6.3)"),
}
# guide 4.3 "Mode Automatic": the move commands that drive to a target (target_reached tells when).
TARGET_COMMANDS = ("CMD_MOVE_ABS", "CMD_MOVE_REL", "CMD_MOVE_PATH", "CMD_MOVE_TO_STATION")
# Planner states that end a planned move without reaching the target.
PLANNER_FAILED = {
    PlannerState.PLANNER_NO_PATH: "the planner found no path to the target",
    PlannerState.PLANNER_COLLISION_START: "the start of the planned path collides with an obstacle",
    PlannerState.PLANNER_COLLISION_TARGET: "the target collides with an obstacle",
}


def last_of(last_sent: Mapping[str, int], names: tuple[str, ...] | list[str]) -> tuple[str, int] | None:
    """The most recently sent of ``names`` as (name, sequence number), or None if none was sent."""
    sent = [(last_sent[n], n) for n in names if n in last_sent]
    if not sent:
        return None
    seq, name = max(sent)
    return name, seq


def _emergency_note(status: Status) -> str:
    if status.emergency_state == EmergencyState.ST_EM_ACTIVE:
        return "; the emergency stop is active"
    return ""


class Judge:
    """Base of the wait judges: a deadline and the status last seen."""

    what = "condition"

    def __init__(self, now: float, timeout: float, after_seq: int = 0) -> None:
        if timeout < 0:
            raise ValueError(f"timeout must be >= 0, got {timeout}")
        self.started = now
        self.timeout = timeout
        self.deadline = now + timeout
        self.after_seq = after_seq
        self.last: Status | None = None

    def remaining(self, now: float) -> float:
        """Seconds left before the deadline (never negative)."""
        return max(0.0, self.deadline - now)

    def observe(self, status: Status, now: float, seq: int) -> bool:
        """True when the wait is over; raises CommandRejected or Timeout when it failed."""
        if seq <= self.after_seq:  # fetched before the command the wait follows: says nothing about it
            if now >= self.deadline:
                raise Timeout(f"{self.what}: no status requested after the command within {self.timeout:g} s")
            return False
        self.last = status
        if self.check(status):
            return True
        if now >= self.deadline:
            raise self.timed_out(status)
        return False

    def check(self, status: Status) -> bool:
        """True when ``status`` shows the condition met (raises CommandRejected when it cannot be any more)."""
        raise NotImplementedError

    def timed_out(self, status: Status) -> Exception:
        """The error for a wait whose deadline passed with ``status`` last seen."""
        return Timeout(f"{self.what} not reached within {self.timeout:g} s{_emergency_note(status)}")


class ConditionWait(Judge):
    """Wait until a caller's predicate holds for a status."""

    def __init__(self, condition: Callable[[Status], bool], what: str, now: float, timeout: float) -> None:
        super().__init__(now, timeout)
        self.condition = condition
        self.what = what

    def check(self, status: Status) -> bool:
        return self.condition(status)


class StateWait(Judge):
    """Wait until the operation state is ``want`` (after the last state command sent, if any)."""

    def __init__(self, want: OperationState, last_sent: Mapping[str, int], now: float, timeout: float) -> None:
        self.want = want
        self.command = last_of(last_sent, list(STATE_COMMANDS))
        super().__init__(now, timeout, self.command[1] if self.command else 0)
        self.what = f"operation state {want.name}"

    def check(self, status: Status) -> bool:
        return status.operation_state == self.want

    def timed_out(self, status: Status) -> Exception:
        seen = f"the operation state is still {status.operation_state.name} {self.timeout:g} s after it was sent"
        if self.command is not None and STATE_COMMANDS[self.command[0]][0] == self.want:
            name = self.command[0]
            return CommandRejected(name, f"{seen}; {STATE_COMMANDS[name][1]}{_emergency_note(status)}")
        return Timeout(
            f"operation state {self.want.name} not reached within {self.timeout:g} s: "
            f"it is {status.operation_state.name}{_emergency_note(status)}"
        )


class ModeWait(Judge):
    """Wait until the motion mode is ``want`` (after the last CMD_SET_MODE sent, if any)."""

    def __init__(self, want: MotionMode, last_sent: Mapping[str, int], now: float, timeout: float) -> None:
        self.want = want
        self.command = last_of(last_sent, ["CMD_SET_MODE"])
        super().__init__(now, timeout, self.command[1] if self.command else 0)
        self.what = f"motion mode {want.name}"

    def check(self, status: Status) -> bool:
        return status.motion_mode == self.want

    def timed_out(self, status: Status) -> Exception:
        if self.command is not None:
            return CommandRejected(
                "CMD_SET_MODE",
                f"the motion mode is still {status.motion_mode.name} {self.timeout:g} s after it was sent; the mode "
                f"can only change in state Ready (guide 6.3 CMD_SET_MODE), the state is "
                f"{status.operation_state.name}",
            )
        return Timeout(f"motion mode {self.want.name} not reached within {self.timeout:g} s: it is "
                       f"{status.motion_mode.name}")  # fmt: skip


class TargetWait(Judge):
    """Wait until the platform reports its target reached, after the last move command sent (if any).

    With a move command sent on this connection, a status showing that the move cannot run (not in state
    Running or Breaked, not in mode Automatic, a failed plan) raises CommandRejected at once.
    """

    what = "target"

    def __init__(self, last_sent: Mapping[str, int], now: float, timeout: float) -> None:
        self.command = last_of(last_sent, TARGET_COMMANDS)
        super().__init__(now, timeout, self.command[1] if self.command else 0)

    def check(self, status: Status) -> bool:
        if self.command is not None:
            name = self.command[0]
            if status.operation_state not in (_RUNNING, _BREAKED):
                raise CommandRejected(
                    name,
                    f"the operation state is {status.operation_state.name}: the platform moves only in state Running "
                    f"(guide 4.2){_emergency_note(status)}",
                )
            if status.motion_mode != MotionMode.MODE_MOTION_AUTOMATIC:
                raise CommandRejected(
                    name,
                    f"the motion mode is {status.motion_mode.name}: move commands with a target run in mode "
                    f"MODE_MOTION_AUTOMATIC only (guide 4.3)",
                )
            if not status.target_reached and status.planner_state in PLANNER_FAILED:
                raise CommandRejected(name, f"{PLANNER_FAILED[status.planner_state]} ({status.planner_state.name})")
        return status.target_reached

    def timed_out(self, status: Status) -> Exception:
        after = f" after {self.command[0]}" if self.command else ""
        pose = status.pose
        return Timeout(
            f"target not reached within {self.timeout:g} s{after}: the platform is at x={pose.x_mm:g} mm "
            f"y={pose.y_mm:g} mm angle={pose.angle_deg:g} deg, state {status.operation_state.name}, planner "
            f"{status.planner_state.name}{_emergency_note(status)}"
        )
