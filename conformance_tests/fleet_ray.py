"""The fleet on a Ray cluster (``pltf conform --targets FILE --ray ADDRESS|auto``): each target's suite is one Ray
task, the run ``fleet.run_target`` does in a thread locally; the driver keeps the fleet's view and its reports.

Rules:
- Ray is an optional extra: this module imports it only when called, and without it ``RayMissing`` says in one
  line what to install. Nothing else of the suite knows Ray (the runner and the reports are Ray-agnostic).
- A task returns ``TargetRun``, plain data (the JSON report's dict, the JUnit text), so nothing of the runner's
  sockets or the case functions crosses to the driver. A task whose worker or node dies is retried by Ray
  (``RETRIES``); one that still fails is that target's exit status 2 with the reason, the others' reports stand.
- A task needs only a CPU's share: a run mostly waits on its target (``num_cpus`` 0.25), so a node of 2 CPUs runs
  eight targets at once.
- The driver connects with ``ray.init(address=...)`` unless it is connected already (a test's cluster), and
  disconnects only what it connected.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from pltf.conformance_tests.fleet import FleetOptions, FleetTarget, TargetRun, failed_run, run_target

INSTALL = "pip install 'pltf-toolkit[ray]'"
RETRIES = 1  # a task lost with its worker or node runs once more
CPUS = 0.25


class RayMissing(RuntimeError):
    """Ray is not installed (one line naming the extra), or its cluster cannot be reached (one line: why)."""


def _ray() -> Any:
    try:
        import ray
    except ImportError:
        raise RayMissing(f"--ray needs Ray, an optional extra: {INSTALL}") from None
    return ray


def _task(target: FleetTarget, options: FleetOptions) -> TargetRun:
    """On a Ray worker: one target's run (the suite's own code, nothing Ray-specific)."""
    return run_target(target, options)


def run_ray(
    targets: Sequence[FleetTarget],
    options: FleetOptions,
    address: str,
    on_done: Callable[[TargetRun], None] | None = None,
) -> list[TargetRun]:
    """Every target's run as a Ray task on the cluster at ``address`` ('auto': the one this machine joined)."""
    ray = _ray()
    connected_here = not ray.is_initialized()
    if connected_here:
        try:
            ray.init(address=address, log_to_driver=False)
        except Exception as exc:  # ConnectionError, or Ray's own: no cluster at that address
            raise RayMissing(f"cannot connect to the Ray cluster at {address}: {' '.join(str(exc).split())}") from None
    try:
        remote = ray.remote(num_cpus=CPUS, max_retries=RETRIES, retry_exceptions=False)(_task)
        pending = {remote.remote(t, options): i for i, t in enumerate(targets)}
        runs: list[TargetRun | None] = [None] * len(targets)
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            i = pending.pop(done[0])
            try:
                runs[i] = ray.get(done[0])
            except Exception as exc:  # the task's worker or node died for good, or the task raised
                runs[i] = failed_run(targets[i], exc)
            if on_done is not None:
                on_done(runs[i])  # type: ignore[arg-type]
        return [r for r in runs if r is not None]
    finally:
        if connected_here:
            ray.shutdown()
