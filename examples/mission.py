"""Load a map, a roadmap and a program onto the platform, run the program from this computer and report each step.

    python examples/mission.py --target 127.0.0.1:10002 --program examples/mission/mission.xml \\
        --map fixtures/maps/office.map --roadmap fixtures/roadmaps/office.rm

The documents go to the platform with CMD_SET_MAP, CMD_SET_ROADMAP and CMD_SET_PROGRAM and are read back to check
they arrived. The program then runs in the guide's "remote mode" (guide 4.5): the toolkit's task interpreter
(pltf.reference_server.tasks) runs it here and drives the platform with socket commands only, so the same run
drives the original PlatformCtrl; every step it takes is printed:

    step 12.34 fetch:7 command <motion> settarget station Kitchen

(simulated seconds of the program's clock, task and line, kind, text). Last line ``mission finished`` or
``mission failed: ...``. Exit status 0 when every task ended without an error, 1 when one failed, logged an error
or ``--timeout`` passed, 2 when a document is invalid or the platform cannot be used.
"""

from __future__ import annotations

import argparse
import datetime
import sys
import time
from pathlib import Path

from pltf.client import MotionMode, OperationState, PlatformClient, PlatformError
from pltf.reference_server.tasks import interpreter
from pltf.reference_server.tasks.model import Program
from pltf.reference_server.tasks.program import load_program
from pltf.reference_server.tasks.remote import RemoteMachine
from pltf.spec.documents import DocumentError, DocumentKind, validate_document

TOOLKIT = Path(__file__).resolve().parents[1]  # the defaults: the toolkit's office and this example's mission
DEFAULTS = {
    "map": TOOLKIT / "fixtures/maps/office.map",
    "roadmap": TOOLKIT / "fixtures/roadmaps/office.rm",
    "program": TOOLKIT / "examples/mission/mission.xml",
}
READY, RUNNING = OperationState.ST_OP_READY, OperationState.ST_OP_RUNNING


def target(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise argparse.ArgumentTypeError(f"expected HOST:PORT, got {text!r}")
    return host.strip("[]"), int(port)


def running_in_automatic(pltf: PlatformClient) -> None:
    """Bring the platform up and to state Running in mode Automatic: the remote program's moves need both."""
    status = pltf.bring_up(timeout=30)
    if status.motion_mode != MotionMode.MODE_MOTION_AUTOMATIC:
        if status.operation_state != READY:
            pltf.stop()
            pltf.wait_state(READY)
        pltf.set_mode(MotionMode.MODE_MOTION_AUTOMATIC)
        pltf.wait_mode(MotionMode.MODE_MOTION_AUTOMATIC)
    if pltf.get_status().operation_state != RUNNING:
        pltf.start()
        pltf.wait_state(RUNNING)


def read_documents(args: argparse.Namespace) -> tuple[dict[str, bytes], Program]:
    """The three documents, checked here first (guide 6.5: the schemas; the program compiled as it will run)."""
    docs = {kind: getattr(args, kind).read_bytes() for kind in ("map", "roadmap", "program")}
    validate_document(DocumentKind.MAP, docs["map"])
    validate_document(DocumentKind.ROADMAP, docs["roadmap"])
    return docs, load_program(docs["program"])


def load_documents(pltf: PlatformClient, args: argparse.Namespace, docs: dict[str, bytes]) -> None:
    """Send the documents and read them back (the platform keeps its old one when it refuses a document)."""
    pltf.set_map(args.map.name, docs["map"])
    pltf.set_roadmap(args.roadmap.name, docs["roadmap"])
    pltf.set_program(docs["program"])
    for kind, reply in (("map", pltf.get_map()), ("roadmap", pltf.get_roadmap()), ("program", pltf.get_program())):
        if reply.xml != docs[kind]:
            raise PlatformError(f"the platform did not take the {kind} {getattr(args, kind)} (it keeps another)")
        print(f"loaded {kind} {getattr(args, kind).name}: {len(reply.xml)} bytes", flush=True)


def run(pltf: PlatformClient, args: argparse.Namespace, program: Program) -> int:
    machine = RemoteMachine(pltf, args.program.resolve().parent, datetime.datetime.now().replace(microsecond=0))
    interp = interpreter.Interpreter(program, machine, seed=0)
    errors: list[str] = []
    t0 = time.monotonic()
    now = 0.0
    records = interp.start(now)
    try:
        while True:
            for r in records:
                print(f"step {r.now:.2f} {r.task or 'program'}:{r.line} {r.kind} {r.text}", flush=True)
                if r.kind == "error" or (r.kind == "log" and r.text.startswith("[error]")):
                    errors.append(r.text)
            if interp.finished or (args.timeout is not None and now >= args.timeout):
                break
            time.sleep(args.period)
            now = (time.monotonic() - t0) * args.time_scale  # the program's clock runs with the platform's
            records = interp.tick(now)
    finally:
        if not interp.finished:
            for r in interp.stop(now):
                print(f"step {r.now:.2f} {r.task or 'program'}:{r.line} {r.kind} {r.text}", flush=True)
            errors.append(f"still running after {now:.1f} s")
            pltf.stop()  # the platform does not drive on without its program
    failed = [run.task.title for run in interp.runs if run.state is interpreter.RunState.FAILED]
    if failed or errors:
        print(f"mission failed: {'; '.join([*(f'task {t} failed' for t in failed), *errors])}", flush=True)
        return 1
    print("mission finished", flush=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--target", type=target, default=("127.0.0.1", 10002), help="HOST:PORT of PlatformCtrl")
    for kind, path in DEFAULTS.items():
        parser.add_argument(f"--{kind}", type=Path, default=path, help=f"the {kind} document (default: {path.name})")
    parser.add_argument(
        "--time-scale",
        type=float,
        default=1.0,
        help="the target's simulated seconds per wall second (default 1: a real platform)",
    )
    parser.add_argument("--period", type=float, default=0.05, help="wall seconds between two ticks (default 0.05)")
    parser.add_argument("--timeout", type=float, help="give up after this many simulated seconds")
    args = parser.parse_args(argv)
    if not args.time_scale > 0 or not args.period > 0:
        parser.error("--time-scale and --period must be > 0")
    host, port = args.target
    try:
        docs, program = read_documents(args)
        with PlatformClient(host, port, timeout=10.0) as pltf:
            load_documents(pltf, args, docs)
            running_in_automatic(pltf)
            return run(pltf, args, program)
    except (OSError, DocumentError, PlatformError) as exc:
        print(f"mission: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
