"""``pltf fuzz --jobs N --launch CMD``: N worker processes, each with a target of its own, one campaign.

Rules (models: AFL++'s main and secondary instances, libFuzzer's ``-jobs``):
- Worker N runs the ordinary campaign (``pltf.fuzz.parallel_worker``) with seed S+N against its own instance of
  the launch command (ephemeral ports, its own restarts and fresh instances for reproduction and
  minimisation): the workers draw different parts of the case space and never share a port (guide 6.1: one
  client per port).
- This process is the driver: it keeps the campaign's view (``pltf.fuzz.parallel_view``), passes each worker's
  new inputs on to the others, keeps each finding once and writes one report (``pltf.fuzz.parallel_store``).
- Request and answer: a worker sends its events down its pipe and waits for the driver's answer (what the
  driver has for it); the driver answers at once. Neither side writes to a pipe the other is not reading, so
  no worker blocks on another, however long it minimises.
- A worker that dies is reported (``lost_workers`` in ``summary.json``) and the campaign goes on with the rest;
  each worker ends by itself ``--duration`` after its target came up (``campaign_end``: a stop is the
  backstop), and the driver waits for their findings (a minimisation in progress) up to ``--minimize-seconds``
  times ``END_MINIMIZE`` more;
  once ``--max-findings`` were kept, ``CUT_GRACE``: whatever a worker still finds would not be kept.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import replace
from multiprocessing.connection import Connection, wait
from pathlib import Path
from typing import Any

from pltf.fuzz.engine import HarnessError
from pltf.fuzz.options import Options
from pltf.fuzz.parallel_store import Store
from pltf.fuzz.parallel_view import CampaignView
from pltf.fuzz.parallel_worker import run_worker, worker_seed
from pltf.fuzz.preludes import StatePlan
from pltf.harness.launch import START_TIMEOUT

STOP_GRACE = 2.0  # s past a worker's own end (its --duration from its target's start) before it is told to stop
CUT_GRACE = 3.0  # s the workers get to end once --max-findings were kept (a minimisation then is in vain)
END_MINIMIZE = 4  # the driver waits up to so many --minimize-seconds (and a minute) for the workers' last findings
TICK = 0.25  # s between the live view's updates


def worker_options(opts: Options, index: int, scratch: Path) -> Options:
    """A worker's options: its seed, its own scratch output (its findings come to the driver), and with --corpus DIR
    its own DIR/wN. Without --corpus nothing is written per input: a file per new coverage key cost a worker 40 %
    of its rate in its first seconds (198 against 332 cases/s of the plain campaign in 9 s at load 27)."""
    own = scratch / f"w{index}"
    corpus = opts.corpus / f"w{index}" if opts.corpus is not None else None  # sharing needs no directory
    return replace(opts, seed=worker_seed(opts.seed, index), out=own / "out", corpus=corpus, max_findings=None)


def campaign_end(started: float, opts: Options) -> float:
    """When the driver tells the workers to stop: each fuzzes ``--duration`` from its own target's start (and ends
    by itself), which may come up to ``START_TIMEOUT`` after the workers were started. Stopping them at
    ``--duration`` from their start cut the campaign short by their targets' start-up (5 s of 8 at load 35)."""
    return started + START_TIMEOUT + opts.duration + STOP_GRACE


def state_targets(opts: Options) -> int:
    return len(StatePlan(opts.allow_motion).targets)


class PipeLink:
    def __init__(self, conn: Connection) -> None:
        self.conn = conn

    def exchange(self, events: list[dict[str, Any]]) -> list[dict[str, Any]]:
        self.conn.send(events)
        answer: list[dict[str, Any]] = self.conn.recv()
        return answer


def _worker_main(opts: Options, index: int, conn: Connection) -> None:
    try:
        run_worker(opts, index, PipeLink(conn))
    except (EOFError, BrokenPipeError):  # the driver is gone: nobody to report to
        pass
    finally:
        conn.close()


class LocalCampaign:
    def __init__(self, opts: Options, jobs: int, on_tick: Callable[[CampaignView], None] | None = None) -> None:
        self.o, self.jobs, self.on_tick = opts, jobs, on_tick
        seeds = [worker_seed(opts.seed, k) for k in range(jobs)]
        self.view = CampaignView(seeds, state_targets(opts), time.monotonic(), opts.max_findings)
        self.store = Store(opts.out)
        self.procs: list[Any] = []
        self.conns: dict[int, Connection] = {}
        self.scratch: Path | None = None

    def start(self) -> None:
        """Fork the workers (before any thread of ours exists: the live view's is started after this)."""
        self.scratch = Path(tempfile.mkdtemp(prefix="pltf-fuzz-jobs-"))
        ctx = multiprocessing.get_context("fork")
        for k in range(self.jobs):
            ours, theirs = ctx.Pipe()
            p = ctx.Process(target=_worker_main, args=(worker_options(self.o, k, self.scratch), k, theirs))
            p.start()
            theirs.close()
            self.procs.append(p)
            self.conns[k] = ours
        self.view.started = time.monotonic()

    def run(self) -> int:
        if self.scratch is None:
            self.start()
        try:
            self._loop(self.conns)
        finally:
            self.close()
        self.store.write_new(self.view)
        self.store.summary(self.view)
        return self._code()

    def close(self) -> None:
        for p in self.procs:
            if p.is_alive():
                p.terminate()
            p.join(timeout=10)
        for conn in self.conns.values():
            conn.close()
        if self.scratch is not None:
            shutil.rmtree(self.scratch, ignore_errors=True)

    def _code(self) -> int:
        if self.view.findings:
            return 1
        failed = [w for w in self.view.workers if w.status == "failed"]
        if len(failed) == len(self.view.workers):
            raise HarnessError(f"worker 0: {failed[0].error}")
        return 0

    def _loop(self, conns: dict[int, Connection]) -> None:
        view, o = self.view, self.o
        stop_at = campaign_end(view.started, o)
        give_up = stop_at + END_MINIMIZE * o.minimize_seconds + 60.0
        stopping, last_tick = False, 0.0
        while conns:
            now = time.monotonic()
            view.now = now
            if view.enough() and not stopping:  # what the others still find would not be kept
                give_up = min(give_up, now + CUT_GRACE)
            if (now > stop_at or view.enough()) and not stopping:
                stopping = True
                for k in conns:
                    view.outbox[k].append({"stop": True})
            if now > give_up and view.enough():
                for k in list(conns):
                    view.cut(k)
                return
            if now > give_up:
                for k in list(conns):
                    view.lose(k, f"still running {give_up - stop_at:.0f} s after the campaign's end: stopped", False)
                return
            for ready in wait(list(conns.values()), timeout=TICK):
                k = next(i for i, c in conns.items() if c is ready)
                if not self._serve(k, conns[k]):
                    del conns[k]
            self.store.write_new(view)
            if self.on_tick is not None and now - last_tick >= TICK:
                last_tick = now
                self.on_tick(view)

    def _serve(self, k: int, conn: Connection) -> bool:
        """One request of worker ``k`` answered; False when its pipe closed (it ended, or died)."""
        view = self.view
        try:
            events = conn.recv()
        except (EOFError, OSError):
            conn.close()
            if view.workers[k].status not in ("done", "failed"):
                p = self.procs[k]
                p.join(timeout=1.0)
                view.lose(k, f"the worker process exited (status {p.exitcode})", again=False)
            return False
        for e in events:
            view.take(e, time.monotonic())
        with contextlib.suppress(OSError):
            conn.send(view.drain(k))
        return True


__all__ = ["LocalCampaign", "campaign_end", "worker_options"]
