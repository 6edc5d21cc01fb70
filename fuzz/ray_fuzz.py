"""``pltf fuzz --jobs N --ray ADDRESS``: the parallel campaign with its workers as Ray actors on a cluster.

Rules (Ray: actors for state that lives, the driver keeps the campaign's view):
- The one adapter between the fuzzer and Ray. Each worker is an actor that runs the ordinary worker
  (``pltf.fuzz.parallel_worker``) in a thread of its own and starts its target on its node (the actors are spread
  over the nodes); the engine knows nothing of Ray. The driver (this process) polls every actor: what the driver
  has for the worker goes in, the worker's events (corpus entries, findings with their files, figures) come back,
  and the same view (``pltf.fuzz.parallel_view``) and report (``pltf.fuzz.parallel_store``) as the local
  campaign's keep them. A finding is reproduced and minimised by the worker that found it, on fresh instances of
  its own target.
- A worker whose actor (or node) dies is reported in the campaign (``lost_workers``) and started again as a new
  actor wherever the cluster has room, up to ``STARTS`` times; the campaign goes on meanwhile.
- Ray is imported here only, and this module only under ``--ray``: without the extra the user gets one line.
"""

from __future__ import annotations

import os
import queue
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from pltf.fuzz.engine import HarnessError
from pltf.fuzz.options import Options
from pltf.fuzz.parallel import CUT_GRACE, END_MINIMIZE, TICK, campaign_end, state_targets, worker_options
from pltf.fuzz.parallel_store import Store
from pltf.fuzz.parallel_view import CampaignView
from pltf.fuzz.parallel_worker import run_worker, worker_seed
from pltf.harness.ray_actors import kill_actors

STARTS = 3  # starts of one worker at most (the first and two after losing it)
POLL_WAIT = 0.25  # s an actor holds a poll open for the worker's next events (no busy polling)
MISSING = "--ray needs the ray extra: pip install 'pltf-toolkit[ray]'"


def import_ray() -> Any:
    try:
        import ray
    except ImportError:
        raise HarnessError(MISSING) from None
    return ray


class QueueLink:
    """The worker's side of the actor: events wait for the driver's next poll, its messages for the worker's next
    exchange. Never blocks."""

    def __init__(self) -> None:
        self.events: queue.SimpleQueue[dict[str, Any]] = queue.SimpleQueue()
        self.inbox: queue.SimpleQueue[dict[str, Any]] = queue.SimpleQueue()

    def exchange(self, events: list[dict[str, Any]]) -> list[dict[str, Any]]:
        for e in events:
            self.events.put(e)
        return _take(self.inbox)

    def poll(self, messages: list[dict[str, Any]], wait: float = POLL_WAIT) -> list[dict[str, Any]]:
        """Take the driver's messages; the worker's events, waiting up to ``wait`` for the first."""
        for m in messages:
            self.inbox.put(m)
        try:
            first = [self.events.get(timeout=wait)]
        except queue.Empty:
            return []
        return first + _take(self.events)


def _take(q: queue.SimpleQueue[dict[str, Any]]) -> list[dict[str, Any]]:
    out = []
    while True:
        try:
            out.append(q.get_nowait())
        except queue.Empty:
            return out


class FuzzWorker:
    """The actor (``ray.remote`` is applied in ``RayCampaign``, so that this module imports without Ray)."""

    def __init__(self) -> None:
        self.link = QueueLink()
        self.thread: threading.Thread | None = None

    def start(self, opts: Options, index: int) -> tuple[int, str]:
        """The worker's campaign in a thread (the actor's other thread answers ``poll``); this process's id and
        its node's."""
        scratch = Path(tempfile.mkdtemp(prefix=f"pltf-fuzz-ray-w{index}-"))
        wopts = worker_options(opts, index, scratch)
        self.thread = threading.Thread(target=run_worker, args=(wopts, index, self.link), daemon=True)
        self.thread.start()
        import ray  # in the actor: Ray is there

        return os.getpid(), ray.get_runtime_context().get_node_id()

    def poll(self, messages: list[dict[str, Any]]) -> list[dict[str, Any]]:
        return self.link.poll(messages)


class RayCampaign:
    def __init__(
        self, opts: Options, jobs: int, address: str, on_tick: Callable[[CampaignView], None] | None = None
    ) -> None:
        self.ray = import_ray()
        self.o, self.jobs, self.address, self.on_tick = opts, jobs, address, on_tick
        seeds = [worker_seed(opts.seed, k) for k in range(jobs)]
        self.view = CampaignView(seeds, state_targets(opts), time.monotonic(), opts.max_findings)
        self.store = Store(opts.out)
        self.actors: dict[int, Any] = {}
        self.pids: dict[int, int] = {}
        self.polls: dict[Any, int] = {}  # a poll in flight -> its worker
        self.actor_class: Any = None

    def start(self) -> None:
        ray = self.ray
        if not ray.is_initialized():
            try:
                ray.init(address=self.address, log_to_driver=False, logging_level="ERROR")
            except (ConnectionError, ValueError, RuntimeError) as exc:
                raise HarnessError(f"--ray {self.address}: {str(exc).splitlines()[0]}") from None
        self.actor_class = ray.remote(num_cpus=1, max_concurrency=2, scheduling_strategy="SPREAD")(FuzzWorker)
        for k in range(self.jobs):
            self._start_worker(k)
        self.view.started = time.monotonic()

    def _start_worker(self, k: int) -> None:
        actor = self.actor_class.remote()
        self.actors[k] = actor
        self.pids[k], node = self.ray.get(actor.start.remote(self.o, k))
        self.view.workers[k].where = f"node {node[:12]}"
        self.polls[actor.poll.remote(self.view.drain(k))] = k

    def run(self) -> int:
        if not self.actors:
            self.start()
        try:
            self._loop()
        finally:
            self.close()
        self.store.write_new(self.view)
        self.store.summary(self.view)
        if self.view.findings:
            return 1
        if all(w.status in ("failed", "lost") for w in self.view.workers):
            raise HarnessError(f"worker 0: {self.view.workers[0].error}")
        return 0

    def _loop(self) -> None:
        ray, view, o = self.ray, self.view, self.o
        stop_at = campaign_end(view.started, o)
        give_up = stop_at + END_MINIMIZE * o.minimize_seconds + 60.0
        stopping, last_tick = False, 0.0
        while self.polls:
            now = time.monotonic()
            view.now = now
            if view.enough() and not stopping:  # what the others still find would not be kept
                give_up = min(give_up, now + CUT_GRACE)
            if (now > stop_at or view.enough()) and not stopping:
                stopping = True
                for k in self.actors:
                    view.outbox[k].append({"stop": True})
            if now > give_up and view.enough():
                for k in set(self.polls.values()):
                    view.cut(k)
                return
            if now > give_up:
                for k in set(self.polls.values()):
                    view.lose(k, f"still running {give_up - stop_at:.0f} s after the campaign's end: stopped", False)
                return
            ready, _ = ray.wait(list(self.polls), num_returns=len(self.polls), timeout=TICK)
            for ref in ready:
                self._answer(ref, self.polls.pop(ref))
            self.store.write_new(view)
            if self.on_tick is not None and now - last_tick >= TICK:
                last_tick = now
                self.on_tick(view)

    def _answer(self, ref: Any, k: int) -> None:
        ray, view = self.ray, self.view
        try:
            events = ray.get(ref)
        except ray.exceptions.RayError as exc:
            again = view.workers[k].starts < STARTS and view.workers[k].status not in ("done", "failed")
            view.lose(k, f"its actor died ({type(exc).__name__}: {str(exc).splitlines()[0][:200]})", again)
            if again:
                self._start_worker(k)
            return
        for e in events:
            view.take(e, time.monotonic())
        if view.workers[k].status not in ("done", "failed"):
            self.polls[self.actors[k].poll.remote(view.drain(k))] = k

    def close(self) -> None:
        kill_actors(self.ray, self.actors.values())
        self.actors.clear()
        self.polls.clear()


__all__ = ["MISSING", "FuzzWorker", "QueueLink", "RayCampaign", "import_ray"]
