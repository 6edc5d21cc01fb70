"""The task interpreter (guide 4.5, 6.5): runs a ``model.Program`` against a ``facade.Machine``, sans-IO.

Rules:
- Time and randomness come in: ``tick(now)`` with simulated seconds, a seed at construction (E-TASK-009). The
  same program, seed and sensor readings give the same commands in the same order, locally or remotely.
- ``start`` starts every task except the error handlers, the tasks some onErrorTask names (E-TASK-002).
  Tasks are cooperative: in a tick the interpreter runs the highest-priority ready task (E-XML-022: larger
  number first, document order among equals) until it waits, calls a handler, ends or has run
  ``STEP_BUDGET`` commands, then looks again from the top, so a task readied by another one's command runs in
  the same tick (E-TASK-001). Commands take no time; only waits do.
- A failed <moveto> (no such entity) calls its onErrorTask: the handler runs from its first command and the
  failing task goes on after the <moveto> once the handler has ended (E-TASK-003). Any other ``TaskError``
  (and a failed moveto without onErrorTask) ends that task with an error; the other tasks go on.
- ``pause`` freezes the program's clock, so delays and timeouts count running time only (E-TASK-005);
  ``stop`` ends every task. The interpreter never commands the platform on pause/stop: the platform's own
  CMD_BREAK/CMD_STOP handling holds or stops the motion.
"""

from __future__ import annotations

import enum
import math
import random
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from pltf.reference_server.tasks import conditions, waits
from pltf.reference_server.tasks import model as m
from pltf.reference_server.tasks.facade import Machine, TaskError

STEP_BUDGET = 1000  # commands one task may run in one tick before it must yield (a goto loop without waits)
APPROACH_DISTANCE = 800.0  # mm short of a tracked entity where <moveto> stops, facing it (E-TASK-008)


class RunState(enum.Enum):
    IDLE = "idle"  # a handler not called yet
    READY = "ready"
    WAITING = "waiting"
    CALLING = "calling"  # waits for its onErrorTask handler to end
    DONE = "done"
    FAILED = "failed"


ACTIVE = frozenset({RunState.READY, RunState.WAITING, RunState.CALLING})


@dataclass(frozen=True)
class Progress:
    """One thing that happened, for the log and the progress view."""

    now: float
    task: str
    line: int
    kind: str  # command | wait | log | error | task | program
    text: str


@dataclass
class TaskRun:
    task: m.Task
    index: int
    state: RunState = RunState.IDLE
    pc: int = 0
    pending: waits.PendingWait | None = None
    handler: TaskRun | None = None
    budget: int = 0
    warned: bool = False

    @property
    def current(self) -> m.Command | None:
        return self.task.commands[self.pc] if self.pc < len(self.task.commands) else None


@dataclass
class Interpreter:
    program: m.Program
    machine: Machine
    seed: int = 0
    runs: list[TaskRun] = field(init=False)
    started: bool = field(default=False, init=False)
    paused: bool = field(default=False, init=False)
    stopped: bool = field(default=False, init=False)
    t: float = field(default=0.0, init=False)  # program time, s: stands still while paused
    _last: float | None = field(default=None, init=False)
    _out: list[Progress] = field(default_factory=list, init=False)
    _now: float = field(default=0.0, init=False)

    def __post_init__(self) -> None:
        self.rng = random.Random(self.seed)
        self.runs = [TaskRun(task, i) for i, task in enumerate(self.program.tasks)]
        self._order = sorted(self.runs, key=lambda r: (-r.task.priority, r.index))

    # ---- control (guide 6.3: CMD_START, CMD_BREAK, CMD_CONTINUE, CMD_STOP in MODE_MOTION_PROGRAM)
    def start(self, now: float) -> list[Progress]:
        self._now, self._last, self.started = now, now, True
        handlers = self.program.handlers()
        for run in self.runs:
            if run.task not in handlers:
                run.state = RunState.READY
        self._emit(None, "program", f"program started: {len(self.runs)} task(s), seed {self.seed}")
        return self.tick(now)

    def pause(self, now: float) -> None:
        if self.running:
            self._advance(now)
            self.paused = True
            self._emit(None, "program", "program paused")

    def resume(self, now: float) -> None:
        if self.paused and not self.stopped:
            self.paused, self._last, self._now = False, now, now
            self._emit(None, "program", "program resumed")

    def stop(self, now: float) -> list[Progress]:
        if self.started and not self.stopped:
            self._now, self.stopped = now, True
            for run in self.runs:
                if run.state in ACTIVE:
                    run.state, run.pending = RunState.DONE, None
            self._emit(None, "program", "program stopped")
        return self._flush()

    @property
    def running(self) -> bool:
        return self.started and not self.stopped and not self.paused and not self.finished

    def waiting_for(self, event_id: str) -> int:
        """How many tasks wait for user event ``event_id`` now (E-TASK-012)."""
        return sum(1 for r in self.runs if r.pending is not None and r.pending.wait.event == m.UserEvent(event_id))

    @property
    def finished(self) -> bool:
        return self.started and not any(run.state in ACTIVE for run in self.runs)

    # ---- the tick
    def tick(self, now: float) -> list[Progress]:
        if not self.running:
            return self._flush()
        self._advance(now)
        self.machine.begin_tick(now)
        events = self.machine.take_user_events()
        for run in self.runs:
            run.budget = STEP_BUDGET
        while (ready := self._next_ready(events)) is not None:
            self._run(ready, events)
        if self.finished:
            self._emit(None, "program", "program finished")
        return self._flush()

    def _advance(self, now: float) -> None:
        if self._last is not None and now > self._last:
            self.t += now - self._last
        self._last, self._now = now, now

    def _next_ready(self, events: frozenset[str]) -> TaskRun | None:
        for run in self._order:
            if run.state is RunState.WAITING and self._wait_over(run, events):
                run.state = RunState.READY
            if run.state is RunState.READY and run.budget > 0:
                return run
        return None

    def _wait_over(self, run: TaskRun, events: frozenset[str]) -> bool:
        p = run.pending
        assert p is not None
        if waits.event_holds(p, self.t, self._now, self.machine, events):
            run.pending, run.pc = None, run.pc + 1
            self._emit(run, "wait", f"wait over: {waits.describe_event(p.wait.event) if p.wait.event else 'event'}")
            return True
        if waits.timed_out(p, self.t):
            run.pending = None
            label = p.wait.timeout_label
            run.pc = run.task.labels[label] if label is not None else run.pc + 1
            self._emit(
                run, "wait", f"wait timed out after {p.wait.timeout_ms:g} ms" + (f": goto {label}" if label else "")
            )
            return True
        return False

    def _run(self, run: TaskRun, events: frozenset[str]) -> None:
        while run.state is RunState.READY:
            cmd = run.current
            if cmd is None:
                self._end(run, RunState.DONE, "task ended")
                return
            if run.budget <= 0:
                if not run.warned:
                    run.warned = True
                    self._emit(run, "error", f"{STEP_BUDGET} commands in one tick without a wait: yields")
                return
            run.budget -= 1
            try:
                self._execute(run, cmd, events)
            except TaskError as exc:
                self._end(run, RunState.FAILED, f"{cmd.tag} (line {cmd.line}) failed: {exc}")
                return

    def _execute(self, run: TaskRun, cmd: m.Command, events: frozenset[str]) -> None:
        if isinstance(cmd, m.Wait):
            run.pending = waits.enter(cmd, self.t, self._now, self.rng)
            run.state = RunState.WAITING
            self._emit(run, "wait", f"wait: {run.pending.describe(self.t)}")
            if self._wait_over(run, events):
                run.state = RunState.READY
            return
        if isinstance(cmd, m.Goto):
            if conditions.evaluate(cmd.condition, self.machine):
                run.pc = run.task.labels[cmd.label]
                self._emit(
                    run, "command", f"goto {cmd.label}" + ("" if cmd.condition == "true" else f" ({cmd.condition})")
                )
                return
        elif isinstance(cmd, m.MoveTo):
            if not self._move_to(run, cmd):
                return
        elif not isinstance(cmd, m.Label):
            text = _ACTIONS[type(cmd)](self.machine, cmd)
            self._emit(run, "log" if isinstance(cmd, m.Log) else "command", text)
        run.pc += 1

    def _move_to(self, run: TaskRun, cmd: m.MoveTo) -> bool:
        """Drive to the entity; False when the task now waits for its onErrorTask handler."""
        target = self.machine.entity(cmd.entity)
        if target is not None:
            x, y, angle = approach(self.machine.pose(), target)
            self.machine.move_to_pose(x, y, angle)
            self._emit(run, "command", f"moveto {cmd.entity.value}: x {x:.0f} y {y:.0f} a {angle:.1f}")
            return True
        reason = f"moveto {cmd.entity.value}: no {cmd.entity.value} in sight"
        if cmd.on_error_task is None:
            raise TaskError(reason)
        handler = next(r for r in self.runs if r.task is self.program.task(cmd.on_error_task))
        self._emit(run, "error", f"{reason}: onErrorTask {handler.task.title}")
        run.pc += 1  # the caller goes on after the moveto once the handler has ended
        if handler is run:
            run.pc = 0  # a task that is its own handler starts again
            return False
        if handler.state not in ACTIVE:
            handler.state, handler.pc, handler.pending = RunState.READY, 0, None
            self._emit(handler, "task", f"task started as onErrorTask of {run.task.title}")
        run.state, run.handler = RunState.CALLING, handler
        return False

    def _end(self, run: TaskRun, state: RunState, text: str) -> None:
        run.state, run.pending = state, None
        self._emit(run, "error" if state is RunState.FAILED else "task", text)
        for caller in self.runs:
            if caller.state is RunState.CALLING and caller.handler is run:
                caller.state, caller.handler = RunState.READY, None

    def _emit(self, run: TaskRun | None, kind: str, text: str) -> None:
        if run is None:
            self._out.append(Progress(self._now, "", 0, kind, text))
            return
        cmd = run.current
        self._out.append(Progress(self._now, run.task.title, cmd.line if cmd else 0, kind, text))
        if kind in ("error", "task"):
            self.machine.log("error" if kind == "error" else "info", f"task {run.task.title}: {text}")

    def _flush(self) -> list[Progress]:
        out, self._out = self._out, []
        return out


def approach(pose: tuple[float, float, float], target: tuple[float, float, float | None]) -> tuple[float, float, float]:
    """E-TASK-008: a frame (x, y, degrees) at ``APPROACH_DISTANCE`` short of a tracked entity, facing it; the
    charging station's own frame when it has an angle."""
    tx, ty, angle = target
    if angle is not None:
        return tx, ty, angle
    px, py = pose[0], pose[1]
    dx, dy = tx - px, ty - py
    dist = math.hypot(dx, dy)
    heading = math.degrees(math.atan2(dy, dx)) if dist > 0 else pose[2]
    if dist <= APPROACH_DISTANCE:
        return px, py, heading
    k = (dist - APPROACH_DISTANCE) / dist
    return px + k * dx, py + k * dy, heading


def _digital_out(mc: Machine, c: m.DigitalOut) -> str:
    mc.set_digital_outputs(c.states)
    return "digitalout " + " ".join(f"D{i + 1}={s}" for i, s in enumerate(c.states) if s != -1)


def _load(mc: Machine, c: m.Load) -> str:
    mc.load(c.map, c.roadmap)
    return f"load map={c.map} roadmap={c.roadmap}"


def _log(mc: Machine, c: m.Log) -> str:
    mc.log(c.type, c.message)
    return f"[{c.type}] {c.message}"


def _stop(mc: Machine, c: m.Stop) -> str:
    mc.stop_motion()
    return "motion stop"


def _coord(mc: Machine, c: m.MoveCoord) -> str:
    mc.move_to_pose(c.x, c.y, c.angle)
    return f"settarget coord x {c.x:g} y {c.y:g} a {c.angle:g}"


def _station(mc: Machine, c: m.MoveStation) -> str:
    mc.move_to_station(c.name)
    return f"settarget station {c.name}"


def _parameter(mc: Machine, c: m.SetParameter) -> str:
    mc.set_parameter(c.key, c.value)
    return f"parameter {c.key} = {c.value}"


def _grab(mc: Machine, c: m.Grab) -> str:
    written = mc.grab(c.filename, c.scan, c.image, c.auto_observation)
    return f"grab {c.filename}: " + (", ".join(written) or "nothing")


def _camera(mc: Machine, c: m.MoveCamera) -> str:
    mc.move_camera(c.position)
    return f"movecamera {c.position}"


def _speak(mc: Machine, c: m.Speak) -> str:
    mc.speak(c.text)
    return f"speak {c.text!r}"


def _play(mc: Machine, c: m.Play) -> str:
    mc.play(c.filename)
    return f"play {c.filename}"


def _turnhead(mc: Machine, c: m.TurnHead) -> str:
    mc.turn_head(c.angle)
    return f"turnhead {c.angle:g}"


_ACTIONS: dict[type[m.Command], Callable[[Machine, Any], str]] = {
    m.DigitalOut: _digital_out,
    m.Load: _load,
    m.Log: _log,
    m.Stop: _stop,
    m.MoveCoord: _coord,
    m.MoveStation: _station,
    m.SetParameter: _parameter,
    m.Grab: _grab,
    m.MoveCamera: _camera,
    m.Speak: _speak,
    m.Play: _play,
    m.TurnHead: _turnhead,
}
