"""``pltf run-program FILE.xml --target HOST:PORT``: run a program on this computer (guide 4.5 "remote mode").

The program is validated and compiled here (an invalid one exits 2 with the schema's message), the platform is
brought to Running in MODE_MOTION_AUTOMATIC, then the sans-IO interpreter (reference_server.tasks) ticks every
``--period`` wall seconds on this computer's simulated clock (wall time x ``--time-scale``) and drives the
platform through reference_server.tasks.remote (socket commands only). A live rich view shows every task's
state, its current element and wait, and the log; ``--plain`` prints the log lines only.

Exit status: 0 when every task ended without error, 1 when a task failed or ``--timeout`` expired, 2 for a
usage error (unreadable or invalid program, target unreachable), 130 on Ctrl-C (the platform is stopped).
"""

from __future__ import annotations

import argparse
import datetime
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from rich.console import Console, Group
from rich.live import Live
from rich.panel import Panel
from rich.table import Table

from pltf.cli.options import CommandError, exit_status, positive, target
from pltf.client import MotionMode, OperationState, PlatformClient, PlatformError
from pltf.reference_server.tasks import interpreter as ip
from pltf.reference_server.tasks.model import Program
from pltf.reference_server.tasks.program import load_program
from pltf.reference_server.tasks.remote import RemoteMachine
from pltf.spec.documents import DocumentError

LOG_LINES = 14


def _epoch(text: str) -> datetime.datetime:
    try:
        return datetime.datetime.fromisoformat(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an ISO date and time, got {text!r}") from None


def add_run_program_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("program", type=Path, metavar="FILE.xml", help="the program document (guide 6.5 Program)")
    p.add_argument("--target", type=target, required=True, metavar="HOST:PORT", help="the platform to drive")
    p.add_argument(
        "--time-scale",
        type=positive,
        default=1.0,
        metavar="X",
        help="the target's simulated seconds per wall second (default 1: a real platform)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of <random> waits (default 0, E-TASK-009)")
    p.add_argument(
        "--data-dir",
        type=Path,
        metavar="DIR",
        help="where <load> finds Map/NAME and Roadmap/NAME and <grab> writes (default: the program's folder)",
    )
    p.add_argument(
        "--epoch",
        type=_epoch,
        metavar="ISO",
        help="local time at the start, for <date> waits (default: this computer's clock)",
    )
    p.add_argument("--period", type=positive, default=0.05, metavar="S", help="wall seconds per tick (default 0.05)")
    p.add_argument("--timeout", type=positive, metavar="S", help="give up after S simulated seconds (exit 1)")
    p.add_argument(
        "--stdin-events",
        action="store_true",
        help="raise user events from standard input: one id per line (E-TASK-012)",
    )
    p.add_argument("--plain", action="store_true", help="print log lines instead of the live view")
    p.epilog = exit_status(
        ok="every task ended without error",
        failed="a task failed, or --timeout expired (the platform is stopped)",
        usage="usage or connection error: an unreadable or invalid program, the target unreachable or lost",
    )


@dataclass
class RunResult:
    finished: bool
    failed: list[str]
    records: list[ip.Progress] = field(default_factory=list)
    elapsed: float = 0.0  # simulated seconds


def prepare(client: PlatformClient, timeout: float = 10.0) -> None:
    """Bring the platform up and into Running in MODE_MOTION_AUTOMATIC (the remote program's moves need both)."""
    status = client.bring_up(timeout)
    if status.motion_mode != MotionMode.MODE_MOTION_AUTOMATIC:
        if status.operation_state in (OperationState.ST_OP_RUNNING, OperationState.ST_OP_BREAKED):
            client.stop()
            client.wait_state(OperationState.ST_OP_READY, timeout)
        client.set_mode(MotionMode.MODE_MOTION_AUTOMATIC)
        client.wait_mode(MotionMode.MODE_MOTION_AUTOMATIC, timeout)
        status = client.get_status()
    if status.operation_state == OperationState.ST_OP_BREAKED:
        client.continue_()
    elif status.operation_state != OperationState.ST_OP_RUNNING:
        client.start()
    client.wait_state(OperationState.ST_OP_RUNNING, timeout)


def run_remote(
    program: Program,
    machine: RemoteMachine,
    *,
    time_scale: float = 1.0,
    seed: int = 0,
    period: float = 0.05,
    timeout: float | None = None,
    on_tick: Callable[[ip.Interpreter, list[ip.Progress], float], None] | None = None,
    cancel: threading.Event | None = None,
) -> RunResult:
    """Tick the interpreter on this computer's simulated clock until the program ends (the platform prepared)."""
    interp = ip.Interpreter(program, machine, seed)
    records: list[ip.Progress] = []
    t0 = time.monotonic()
    now = 0.0
    new = interp.start(now)
    try:
        while True:
            records += new
            if on_tick is not None:
                on_tick(interp, new, now)
            if interp.finished or (timeout is not None and now >= timeout) or (cancel is not None and cancel.is_set()):
                break
            time.sleep(period)
            now = (time.monotonic() - t0) * time_scale
            new = interp.tick(now)
    finally:
        if not interp.finished:
            records += interp.stop(now)
    failed = [r.task.title for r in interp.runs if r.state is ip.RunState.FAILED]
    return RunResult(interp.finished and not interp.stopped, failed, records, now)


# ---- the view
class View:
    def __init__(self, program_name: str, target: str) -> None:
        self.title = f"{program_name} on {target}"
        self.log: deque[ip.Progress] = deque(maxlen=LOG_LINES)
        self.now = 0.0
        self.interp: ip.Interpreter | None = None

    def update(self, interp: ip.Interpreter, records: list[ip.Progress], now: float) -> None:
        self.interp, self.now = interp, now
        self.log.extend(records)

    def render(self) -> Group:
        tasks = Table(expand=True, title=f"{self.title}  t = {self.now:8.2f} s simulated")
        for col in ("task", "prio", "state", "line", "element", "wait"):
            tasks.add_column(col)
        if self.interp is not None:
            for run in self.interp.runs:
                cmd = run.current
                wait = run.pending.describe(self.interp.t) if run.pending is not None else ""
                tasks.add_row(
                    run.task.title,
                    str(run.task.priority),
                    run.state.value,
                    str(cmd.line) if cmd else "",
                    cmd.tag if cmd else "",
                    wait,
                )
        lines = "\n".join(_line(r) for r in self.log) or "(nothing yet)"
        return Group(tasks, Panel(lines, title="log"))


def _line(r: ip.Progress) -> str:
    who = f"{r.task}:{r.line}" if r.task else "program"
    return f"{r.now:8.2f}  {who:<18} {r.kind:<7} {r.text}"


def _stop_quietly(client: PlatformClient) -> None:
    """Ctrl-C: the platform must not drive on without its program (best effort, the socket may be gone)."""
    try:
        with PlatformClient(client.host, client.port, timeout=2.0) as again:
            again.stop()
    except PlatformError:
        pass


def _stdin_events(machine: RemoteMachine) -> None:
    for line in sys.stdin:
        word = line.strip().removeprefix("event").strip()
        if word:
            machine.raise_event(word)


def run_run_program(args: argparse.Namespace) -> int:
    err = Console(stderr=True)
    try:
        program = load_program(args.program.read_bytes())
    except OSError as exc:
        raise CommandError(f"{args.program}: {exc.strerror or exc}") from None
    except DocumentError as exc:
        raise CommandError(f"{args.program}: {exc}") from None
    host, port = args.target
    try:
        client = PlatformClient(host, port)
    except PlatformError as exc:
        raise CommandError(str(exc)) from None
    data_dir = args.data_dir or args.program.resolve().parent
    view = View(args.program.name, f"{host}:{port}")
    machine = RemoteMachine(client, data_dir, args.epoch or datetime.datetime.now().replace(microsecond=0))
    if args.stdin_events:
        threading.Thread(target=_stdin_events, args=(machine,), daemon=True).start()
    out = Console()

    def run(on_tick: Callable[[ip.Interpreter, list[ip.Progress], float], None]) -> RunResult:
        return run_remote(
            program,
            machine,
            time_scale=args.time_scale,
            seed=args.seed,
            period=args.period,
            timeout=args.timeout,
            on_tick=on_tick,
        )

    try:
        with client:
            prepare(client)
            result = run(_plain_lines(out)) if args.plain or not out.is_terminal else _run_live(view, out, run)
    except KeyboardInterrupt:
        _stop_quietly(client)
        return 130
    except PlatformError as exc:
        raise CommandError(str(exc)) from None
    if result.failed:
        err.print(f"pltf run-program: task(s) failed: {', '.join(result.failed)}", markup=False)
    if not result.finished:
        err.print(
            f"pltf run-program: program still running after {result.elapsed:.1f} s simulated: stopped", markup=False
        )
    return 0 if result.finished and not result.failed else 1


def _plain_lines(out: Console) -> Callable[[ip.Interpreter, list[ip.Progress], float], None]:
    """Progress as one printed line per record (not a terminal, or --plain)."""

    def on_tick(interp: ip.Interpreter, records: list[ip.Progress], now: float) -> None:
        for r in records:
            out.print(_line(r), markup=False, highlight=False)

    return on_tick


def _run_live(
    view: View, out: Console, run: Callable[[Callable[[ip.Interpreter, list[ip.Progress], float], None]], RunResult]
) -> RunResult:
    """Progress as a live view on the terminal."""
    with Live(view.render(), console=out, refresh_per_second=8) as live:

        def on_live(interp: ip.Interpreter, records: list[ip.Progress], now: float) -> None:
            view.update(interp, records, now)
            live.update(view.render())

        return run(on_live)
