"""``pltf serve --fleet FILE|N --processes K``: the fleet's shards as K processes of this machine (issue 30: one
process steps a fleet on one core; a machine has more).

Rules (the shards' rules, the lag and the snapshots: reference_server/fleet/shards.py, erratum E-FLEET-004; a
shard's life: reference_server/fleet/shard.py):
- The driver (this process) plans K shards (``shards.plan``: a platform's ``node`` in the fleet file is its
  process's index, the others go round-robin), starts each as a child process (multiprocessing's ``spawn``: a
  fresh interpreter, no state of the driver's), and wires them with one pipe per ordered pair of shards: a shard
  sends its batch of snapshots every ``--ray-lag`` periods down the pipe to each peer, and a thread of the peer
  reads it into its ``Exchange``. Nothing but the snapshots crosses between shards; each child serves its own
  platforms' ports.
- Start-up is in two steps, as on Ray: every child builds and boots its platforms (``prepared``), then the driver
  sends one epoch (``time.time()``: simulated time 0) to all and each serves its ports (``serving``). Each child
  logs "server started at port N" and "platform NAME at HOST:PORT,PORT" as ``pltf serve --fleet`` does, on the
  driver's stderr; the driver adds "shard K (pid P) serves platforms A, B" for each.
- A child whose platforms all exited says so (``ended``) and ends; a child that dies without saying so (killed,
  out of memory) is LOST: the driver logs "shard K (pid P) lost (exit status S): platforms A, B stopped serving";
  the other shards see its pipes close, take its bodies out of their worlds and keep serving. The driver exits
  when no shard is left (status 0; 1 when one was lost) or on SIGINT/SIGTERM (it stops every shard, status 0).
  The children ignore SIGINT (a Ctrl-C reaches the whole process group): the driver stops them. A child whose
  driver is gone (its control pipe closed) stops too.
- A send to a peer never raises: a dead peer's pipe is broken, and the pipe's close tells the receiving side.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import multiprocessing as mp
import signal
import sys
import threading
import time
from multiprocessing.connection import Connection, wait
from multiprocessing.process import BaseProcess
from typing import Any

from pltf.reference_server.fleet import shard as common
from pltf.reference_server.fleet.config import FleetError, FleetSpec
from pltf.reference_server.fleet.shard import START_TIMEOUT, Shard, first_line
from pltf.reference_server.fleet.shards import ShardPlan, Snapshot, plan

log = logging.getLogger("pltf.server")

STOP_GRACE = 10.0  # s the shards have to stop at SIGINT/SIGTERM before they are terminated
WATCH = 0.5  # s between two looks at the shards
Boxes = dict[int, dict[int, Connection]]  # shard -> peer -> its end of the pipe between them


class ShardFailed(RuntimeError):
    """A child could not build, boot or serve its platforms: its one line."""


# ------------------------------------------------------------------------------------------ a child process
def child(
    shard_plan: ShardPlan,
    opts: dict[str, Any],
    lag: int,
    serve: tuple[str, float],
    inbox: dict[int, Connection],
    outbox: dict[int, Connection],
    ctrl: Connection,
) -> None:
    """A shard's process: prepared, then serving from the epoch the driver sends, until it ends."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    shard = Shard()
    try:
        pid = shard.prepare(shard_plan, opts, lag)
    except Exception as exc:  # a data dir refused, a map that does not parse: the user's one line
        ctrl.send(("error", f"{type(exc).__name__}: {exc}"))
        sys.exit(2)
    wire(shard, inbox, outbox)
    ctrl.send(("prepared", pid))
    try:
        epoch = ctrl.recv()
        ports = shard.go(epoch, *serve)
    except (EOFError, OSError):  # the driver went before the start
        sys.exit(2)
    except RuntimeError as exc:
        ctrl.send(("error", str(exc)))
        sys.exit(2)
    ctrl.send(("serving", ports))
    threading.Thread(target=_control, args=(shard, ctrl), name="control", daemon=True).start()
    code = shard.wait()
    _quietly(ctrl.send, ("ended", code))
    for conn in outbox.values():
        conn.close()
    sys.exit(code)


def pipes(plans: list[ShardPlan], ctx: Any) -> tuple[Boxes, Boxes]:
    """One pipe per ordered pair of shards: ``inbox[b][a]`` reads what ``outbox[a][b]`` sends."""
    outbox: Boxes = {p.shard: {} for p in plans}
    inbox: Boxes = {p.shard: {} for p in plans}
    for a in plans:
        for b in plans:
            if a.shard != b.shard:
                inbox[b.shard][a.shard], outbox[a.shard][b.shard] = ctx.Pipe(duplex=False)
    return inbox, outbox


def wire(shard: Shard, inbox: dict[int, Connection], outbox: dict[int, Connection]) -> None:
    """The shard's batches go down ``outbox``'s pipes; a thread per peer reads ``inbox``'s into its exchange."""
    shard.connect({k: _sender(conn) for k, conn in outbox.items()})
    for peer, conn in inbox.items():
        threading.Thread(target=_receive, args=(shard, peer, conn), name=f"from-{peer}", daemon=True).start()


def _sender(conn: Connection) -> Any:
    def send(snaps: list[Snapshot]) -> None:
        _quietly(conn.send, snaps)

    return send


def _quietly(fn: Any, *args: Any) -> None:
    with contextlib.suppress(OSError, ValueError):  # BrokenPipeError: the other end is gone; ValueError: closed here
        fn(*args)


def _receive(shard: Shard, peer: int, conn: Connection) -> None:
    while True:
        try:
            snaps = conn.recv()
        except (EOFError, OSError):  # the peer's process ended or died: its bodies leave
            shard.drop(peer)
            return
        shard.receive(snaps)


def _control(shard: Shard, ctrl: Connection) -> None:
    """Stop on the driver's word, or when the driver is gone."""
    with contextlib.suppress(EOFError, OSError):
        ctrl.recv()
    shard.stop()


# ------------------------------------------------------------------------------------------ the driver
class Child:
    def __init__(self, shard_plan: ShardPlan, process: BaseProcess, ctrl: Connection) -> None:
        self.plan, self.process, self.ctrl = shard_plan, process, ctrl
        self.pid = 0
        self.ended: int | None = None  # the exit status it said it ends with

    @property
    def names(self) -> str:
        return ", ".join(p.name for p in self.plan.platforms)

    def expect(self, what: str, timeout: float) -> Any:
        """The child's next message, which must be ``what``; ShardFailed with its error otherwise."""
        if not self.ctrl.poll(timeout):
            raise ShardFailed(f"shard {self.plan.shard} (platforms {self.names}) did not get {what} in {timeout:g} s")
        try:
            kind, value = self.ctrl.recv()
        except (EOFError, OSError):
            raise ShardFailed(
                f"shard {self.plan.shard} (platforms {self.names}) ended before it was {what} "
                f"(exit status {self.process.exitcode})"
            ) from None
        if kind != what:
            raise ShardFailed(f"shard {self.plan.shard} (platforms {self.names}): {first_line(RuntimeError(value))}")
        return value


class Driver:
    def __init__(self, spec: FleetSpec, args: argparse.Namespace) -> None:
        self.spec, self.args = spec, args
        self.children: dict[int, Child] = {}
        self._stopping = threading.Event()

    def start(self) -> None:
        n = self.args.processes
        plans = plan(self.spec, n, self.args.seed, across="--processes gives")
        ctx = mp.get_context("spawn")
        inbox, outbox = pipes(plans, ctx)
        opts, serve = common.options(self.args), (self.args.host, self.args.time_scale)
        for p in plans:
            ours, theirs = ctx.Pipe()
            args = (p, opts, self.args.ray_lag, serve, inbox[p.shard], outbox[p.shard], theirs)
            process = ctx.Process(target=child, args=args, name=f"pltf-shard-{p.shard}")
            process.start()
            theirs.close()
            self.children[p.shard] = Child(p, process, ours)
        for conns in (*inbox.values(), *outbox.values()):  # the children hold them now: a child's end closes
            for conn in conns.values():  # with its process only
                conn.close()
        for c in self.children.values():
            c.pid = c.expect("prepared", START_TIMEOUT)
        epoch = time.time()
        for c in self.children.values():
            c.ctrl.send(epoch)
        for shard, c in self.children.items():  # each child logged its ports as pltf serve --fleet does
            c.expect("serving", START_TIMEOUT)
            log.info("shard %d (pid %d) serves platforms %s", shard, c.pid, c.names)

    def watch(self) -> int:
        """Until every shard has ended: report the lost ones."""
        live, lost = dict(self.children), 0
        while live:
            if self._stopping.is_set():
                return self._stop(live)
            wait([c.process.sentinel for c in live.values()], timeout=WATCH)
            for shard, c in list(live.items()):
                if c.process.is_alive():
                    continue
                del live[shard]
                if self._said_ended(c):
                    log.info("shard %d (pid %d) ended: its platforms exited", shard, c.pid)
                else:
                    lost += 1
                    log.error(
                        "shard %d (pid %d) lost (exit status %s): platforms %s stopped serving",
                        shard,
                        c.pid,
                        c.process.exitcode,
                        c.names,
                    )
        log.info("fleet stopped: %d shard(s) ended, %d lost", len(self.children) - lost, lost)
        return 1 if lost else 0

    @staticmethod
    def _said_ended(c: Child) -> bool:
        try:
            while c.ctrl.poll(0):
                kind, value = c.ctrl.recv()
                if kind == "ended":
                    c.ended = value
        except (EOFError, OSError):
            pass
        return c.ended is not None

    def stop(self) -> None:
        self._stopping.set()

    def _stop(self, live: dict[int, Child]) -> int:
        for c in live.values():
            _quietly(c.ctrl.send, "stop")
        deadline = time.monotonic() + STOP_GRACE
        for c in live.values():
            c.process.join(max(0.0, deadline - time.monotonic()))
        log.info("fleet stopped: %d shard(s) stopped", len(live))
        return 0

    def close(self) -> None:
        for c in self.children.values():
            if c.process.is_alive():
                c.process.terminate()
                c.process.join(5.0)
            c.ctrl.close()


def run(spec: FleetSpec, args: argparse.Namespace, prog: str) -> int:
    """``pltf serve --fleet FILE|N --processes K``: user errors are one line and status 2, as ``pltf serve``'s."""
    try:
        spec = common.settled(common.placed(spec, args))
    except FleetError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    driver = Driver(spec, args)
    try:
        with common.stopped_by_signals(driver.stop):
            driver.start()
            return driver.watch()
    except (FleetError, ShardFailed) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    finally:
        driver.close()


__all__ = ["Driver", "ShardFailed", "child", "pipes", "run", "wire"]
