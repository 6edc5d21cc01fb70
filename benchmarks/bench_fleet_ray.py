"""The fleet past one machine (issue 30): ``pltf serve --fleet FILE --ray`` with 1, 2 and 3 shards, side by side.

Subjects, in one run on one local Ray cluster of three nodes (each its own raylet, all on 127.0.0.1, this machine):
- "1 shard": the fleet's N platforms in ONE shard (one process, no exchange: what ``pltf serve --fleet`` runs,
  inside the same actor shell) - the baseline;
- "2 shards", "3 shards": the same N platforms spread round-robin over 2 or 3 nodes, exchanging their snapshots
  every control period (lag 1: lockstep one period behind).
Each subject is the real driver (reference_server/fleet/ray_shards.py: actors, ports, the exchange) with N
platforms at free places of the office fixture, booted, fake CAN boards on, no client connected (the platforms
idle Not initialised: the world, the boards and the control loop tick; nobody drives). Two phases:
- flat out (``--time-scale 1000``, far beyond what the machine simulates: the control loop holds the time it
  cannot simulate): real-time factor = simulated seconds the slowest shard reached / wall seconds, over
  ``SECONDS`` after a warm-up;
- flat out with ``--ray-lag 5`` (2 and 3 shards): what a longer lag buys - a shard may run 5 periods ahead of the
  others instead of 1, so the scheduling jitter of a loaded machine is absorbed instead of waited out;
- real time (``--time-scale 1``): the pose-exchange latency (a snapshot's send to its receipt on the other shard,
  p50 and p95 over every snapshot of the phase) and the share of the wall time the shards waited for a peer.
Skipped with one line when the ray extra is missing or the local cluster does not come up.
"""

from __future__ import annotations

import argparse
import contextlib
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.harness import Config, Row, benchmark, make_row
from benchmarks.ray_local import local_cluster
from benchmarks.ray_local import say as _say

PLATFORMS = 6
SHARDS = (1, 2, 3)
SECONDS, QUICK_SECONDS = 10.0, 3.0
WARMUP = 2.0
FLAT_OUT = 1000.0
LONG_LAG = 5


def ray_cluster(nodes: int) -> contextlib.AbstractContextManager[Any]:
    """``nodes`` nodes on 127.0.0.1 (None without the ray extra or when the cluster does not come up)."""
    return local_cluster(nodes, "fleet_ray", logging_level="ERROR")


def free_poses(count: int, root: Path) -> list[tuple[float, float, float]]:
    """``count`` free places of the office fixture (as ``pltf serve --fleet N`` chooses them)."""
    from pltf.reference_server.fleet.cli import build_platforms
    from pltf.reference_server.fleet.config import of_count
    from pltf.reference_server.fleet.fleet import Fleet

    spec = of_count(count, [0, 0])
    args = argparse.Namespace(data_dir=str(root), seed=1, no_hardware=True, can_interface="virtual")
    fleet = Fleet(spec, build_platforms(spec, args))
    try:
        fleet.boot(0.0)
        return list(fleet._free_places())
    finally:
        fleet.close()


def fleet_spec(count: int, shards: int, root: Path) -> Any:
    from dataclasses import replace

    from pltf.reference_server.fleet.config import FleetSpec, of_count

    poses = free_poses(count, root / "places")
    spec = of_count(count, [0, 0])
    return FleetSpec(tuple(replace(p, pose=poses[k], node=k % shards) for k, p in enumerate(spec.platforms)))


def one_run(shards: int, time_scale: float, seconds: float, root: Path, lag: int = 1) -> dict[str, float]:
    """The driver with ``shards`` shards for ``seconds`` after the warm-up: RTF, latency, waiting."""
    from pltf.reference_server.fleet.ray_shards import Driver

    args = argparse.Namespace(
        ray="auto",
        ray_lag=lag,
        seed=1,
        host="127.0.0.1",
        time_scale=time_scale,
        data_dir=str(root / f"data-{shards}-{time_scale:g}"),
        no_hardware=False,
        can_interface="virtual",
        log_level="WARNING",
    )
    driver = Driver(fleet_spec(PLATFORMS, shards, root), args)
    ray = driver.ray
    try:
        driver.start()
        time.sleep(WARMUP)
        before = ray.get([a.stats.remote() for a in driver.actors.values()])
        t0 = time.perf_counter()
        time.sleep(seconds)
        after = ray.get([a.stats.remote() for a in driver.actors.values()])
        wall = time.perf_counter() - t0
    finally:
        for actor in driver.actors.values():
            actor.stop.remote()
        driver.close()
    ticks = min(b["ticks"] - a["ticks"] for a, b in zip(before, after, strict=True))
    waited = sum(b["waited"] - a["waited"] for a, b in zip(before, after, strict=True)) / len(after)
    return {
        "rtf": ticks * 0.02 / wall,
        "latency_p50": max(s["latency_p50"] for s in after),
        "latency_p95": max(s["latency_p95"] for s in after),
        "waited_share": waited / wall,
        "late": sum(s["late"] for s in after),
    }


@benchmark()
def shards(config: Config) -> list[Row]:
    """Real-time factor and pose-exchange latency of a fleet on 1, 2 and 3 Ray shards (nodes of one machine)."""
    seconds = QUICK_SECONDS if config.quick else SECONDS
    repeats = 1 if config.quick else max(1, min(config.repeats, 3))
    flat: dict[int, list[dict[str, float]]] = {n: [] for n in SHARDS}
    real: dict[int, list[dict[str, float]]] = {n: [] for n in SHARDS}
    lagged: dict[int, list[dict[str, float]]] = {n: [] for n in SHARDS if n > 1}
    with ray_cluster(max(SHARDS)) as cluster, tempfile.TemporaryDirectory() as tmp:
        if cluster is None:
            return []
        for _ in range(repeats):  # interleaved: the machine's load falls on every subject alike
            for n in SHARDS:
                flat[n].append(one_run(n, FLAT_OUT, seconds, Path(tmp)))
                _say(f"{n} shard(s) flat out: RTF {flat[n][-1]['rtf']:.2f}")
                real[n].append(one_run(n, 1.0, seconds, Path(tmp)))
                _say(f"{n} shard(s) real time: latency p50 {real[n][-1]['latency_p50'] * 1e3:.2f} ms")
                if n in lagged:
                    lagged[n].append(one_run(n, FLAT_OUT, seconds, Path(tmp), LONG_LAG))
                    _say(f"{n} shard(s) flat out, lag {LONG_LAG}: RTF {lagged[n][-1]['rtf']:.2f}")
    return rows(flat, real, lagged)


Runs = dict[int, list[dict[str, float]]]


def rows(flat: Runs, real: Runs, lagged: Runs) -> list[Row]:
    def med(runs: list[dict[str, float]], key: str) -> float:
        return statistics.median(r[key] for r in runs)

    name, out = "fleet_ray.shards", []
    base = med(flat[1], "rtf")
    for n in SHARDS:
        subject = f"{PLATFORMS} platforms on {n} shard{'s' if n > 1 else ''}"
        baseline = None if n == 1 else f"{PLATFORMS} platforms on 1 shard"
        out.append(
            make_row(
                name,
                subject,
                "realtime_factor",
                med(flat[n], "rtf"),
                "sim-s/s",
                higher_is_better=True,
                baseline_subject=baseline,
                baseline_value=None if n == 1 else base,
            )
        )
        if n > 1:
            for key, metric in (("latency_p50", "exchange_latency_p50"), ("latency_p95", "exchange_latency_p95")):
                out.append(make_row(name, subject, metric, med(real[n], key) * 1e3, "ms", higher_is_better=False))
            for runs, phase in ((flat[n], "flat_out"), (real[n], "real_time")):
                share = med(runs, "waited_share") * 100
                out.append(make_row(name, subject, f"waited_share_{phase}", share, "%", higher_is_better=False))
            late = sum(r["late"] for r in flat[n] + real[n])
            out.append(make_row(name, subject, "late_peers", late, "times", higher_is_better=False))
        if n in lagged:
            rtf = med(lagged[n], "rtf")
            slow = f"{subject}, lag {LONG_LAG}"
            out.append(
                make_row(
                    name,
                    slow,
                    "realtime_factor",
                    rtf,
                    "sim-s/s",
                    higher_is_better=True,
                    baseline_subject=f"{PLATFORMS} platforms on 1 shard",
                    baseline_value=base,
                )
            )
            share = med(lagged[n], "waited_share") * 100
            out.append(make_row(name, slow, "waited_share_flat_out", share, "%", higher_is_better=False))
    return out
