"""Judges for the client's waits: given the statuses polled so far, done, keep polling, or which error.

Rules:
- Sans-IO: a judge gets each polled ``Status`` with ``now`` (monotonic seconds) and the sequence number of
  the request that fetched it; the sync and asyncio clients only poll and sleep. Both wait the same way.
- Commands are not acknowledged (guide 6.1), so a refused command shows only in the status telegram. A judge
  knows which command the wait follows (``ClientCore.last_sent``) and names it in ``CommandRejected`` when the
  status shows it did not take effect, quoting the rule of the guide (``STATE_COMMANDS``).
- The platform handles one connection's telegrams in order, so a status requested after a command shows
  the platform after that command (the reason a judge ignores statuses requested before it).
- But a move is taken up in the platform's control loop, later: the planner state and the target-reached flag
  of a status requested right after a move may still describe the move before. ``TargetWait`` judges them only
  in a status that belongs to the move (erratum E-CLI-001, ``Belongs``); the operation state and the motion mode
  are decided when the command is handled and are judged at once.
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
# erratum E-CLI-001: a status belongs to the move once one of these shows the control loop took it up
TAKE_UP_MS = 200  # platform time stamp (ms, E-REP-010) after the first status requested after the move
TAKE_UP_S = 2.0  # client clock since the wait began, for a platform whose time stamp does not advance
STAMP_MODULO = 2**31  # E-REP-010: the time stamp wraps at 2^31
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
        if self.check(status, now):
            return True
        if now >= self.deadline:
            raise self.timed_out(status)
        return False

    def check(self, status: Status, now: float) -> bool:
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

    def check(self, status: Status, now: float) -> bool:
        return self.condition(status)


class StateWait(Judge):
    """Wait until the operation state is ``want`` (after the last state command sent, if any)."""

    def __init__(self, want: OperationState, last_sent: Mapping[str, int], now: float, timeout: float) -> None:
        self.want = want
        self.command = last_of(last_sent, list(STATE_COMMANDS))
        super().__init__(now, timeout, self.command[1] if self.command else 0)
        self.what = f"operation state {want.name}"

    def check(self, status: Status, now: float) -> bool:
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

    def check(self, status: Status, now: float) -> bool:
        return status.motion_mode == self.want

    def timed_out(self, status: Status) -> Exception:
        if self.command is not None:
            return CommandRejected(
                "CMD_SET_MODE",
                f"the motion mode is still {status.motion_mode.name} {self.timeout:g} s after it was sent; the mode "
                f"can only change in state Ready (guide 6.3 CMD_SET_MODE), the state is "
                f"{status.operation_state.name}",
            )
        return Timeout(
            f"motion mode {self.want.name} not reached within {self.timeout:g} s: it is {status.motion_mode.name}"
        )


def stamp_after(later: int, earlier: int) -> int:
    """Milliseconds from time stamp ``earlier`` to ``later`` across the wrap at 2^31 (negative: not later)."""
    diff = (later - earlier) % STAMP_MODULO
    return diff if diff < STAMP_MODULO // 2 else diff - STAMP_MODULO


class Belongs:
    """Whether a status describes the move it follows, or may still show the move before (erratum E-CLI-001).

    Fed every status requested after the move, in order; the first is the reference. A later one belongs to the
    move when its planner state differs from the reference's (the planner worked since), or when the status
    before it was made ``TAKE_UP_MS`` of platform time after the reference, or ``TAKE_UP_S`` after the wait
    began: a platform answers a request before it runs the control periods that fell due meanwhile (the
    reference server after a stall does), so the time is trusted from the next status on. From then on every
    status belongs to the move.
    """

    def __init__(self, started: float) -> None:
        self.started = started
        self.reference: Status | None = None
        self.taken_up = False
        self._due = False  # a status after the take-up time was seen: the next one belongs

    def __call__(self, status: Status, now: float) -> bool:
        ref = self.reference
        if ref is None:
            self.reference = status
        elif not self.taken_up:
            self.taken_up = self._due or status.planner_state != ref.planner_state
            self._due = (
                stamp_after(status.timestamp_ms, ref.timestamp_ms) >= TAKE_UP_MS or now - self.started >= TAKE_UP_S
            )
        return self.taken_up


class TargetWait(Judge):
    """Wait until the platform reports its target reached, after the last move command sent (if any).

    With a move command sent on this connection, a status showing that the move cannot run (not in state
    Running or Breaked, not in mode Automatic) raises CommandRejected at once; a failed plan and the target
    flag count only in a status that belongs to the move (erratum E-CLI-001).
    """

    what = "target"

    def __init__(self, last_sent: Mapping[str, int], now: float, timeout: float) -> None:
        self.command = last_of(last_sent, TARGET_COMMANDS)
        super().__init__(now, timeout, self.command[1] if self.command else 0)
        self.belongs = Belongs(now)

    def check(self, status: Status, now: float) -> bool:
        if self.command is None:  # no move sent here (a new connection): nothing to tell old from new
            return status.target_reached
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
        # guide 4.3 Mode Automatic: "If a new move command is set while the platform is moving, the execution of
        # the old command will be stopped immediately and the new command will be started": until the status
        # shows the new command started, its planner state and target flag may be the old command's (E-CLI-001)
        if not self.belongs(status, now):
            return False
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
