"""A fleet split over this machine's cores (issue 30, ``pltf serve --fleet N --processes K``): the real-time factor
and the CPU of N platforms in K shard processes, beside the same fleet in one process, in one run.

Subjects, each a fresh set of processes:
- "fleet of N in K processes (lag L)": K child processes (multiprocessing ``spawn``), each a ``Shard`` of
  reference_server/fleet/shard.py wired to the others by the pipes of ``local_shards`` (what ``pltf serve
  --processes K --ray-lag L`` runs), with its round-robin share of the N platforms of bench_fleet's hall at full
  fidelity, brought up and driven as bench_fleet drives them (each shuttles between its place and that of the
  platform half the fleet away). Timed: ``ShardWorld.tick`` for SECONDS of simulated time, i.e. the fleet's ticks
  with the snapshots exchanged and waited for (lag L), from one start signal to the last shard's end. Sockets idle.
- baseline "fleet of N in one process": bench_fleet's own subject (``bench_fleet.child``), the same platforms and
  driving in one ``Fleet``.
Figures: real-time factor (simulated s per wall s) and CPU s per platform per simulated second (every shard's CPU
summed: what the split costs beside what it buys).
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import statistics
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from benchmarks.bench_fleet import DT, RTF_TARGETS, _bring_up, _hall, drive, fleet_run
from benchmarks.harness import Config, Row, Target, benchmark, make_row

SIZES = (10, 100, 250)
QUICK_SIZES = (4,)
SPLITS = ((2, 1), (2, 5))  # (processes, lag)
START_TIMEOUT = 600.0


def _shard(plan: Any, opts: dict[str, Any], lag: int, inbox: Any, outbox: Any, ctrl: Any, homes: Any) -> None:
    """One shard's process: prepared and brought up, aligned on the common first tick, driven, timed."""
    from pltf.reference_server.fleet.local_shards import wire
    from pltf.reference_server.fleet.shard import Shard

    shard = Shard()
    shard.prepare(plan, opts, lag)
    wire(shard, inbox, outbox)
    fleet, world = shard.fleet, shard.world
    assert fleet is not None and world is not None
    first = _bring_up(fleet, boot=False)
    ctrl.send(first)
    start, seconds = ctrl.recv()
    for k in range(first + 1, start + 1):  # the shards that came up sooner idle to the common tick
        fleet.tick(k * DT)
    world.send([world.snapshot(start)])  # what the others' first tick waits for
    cpu, wall = time.process_time(), time.perf_counter()
    drive(fleet.members, homes, world.tick, start, seconds)
    ctrl.send({"cpu": time.process_time() - cpu, "wall": time.perf_counter() - wall, **shard.stats()})


def split_run(count: int, seconds: float, processes: int, lag: int) -> dict[str, float]:
    """``count`` platforms in ``processes`` shards, driven ``seconds``: the slowest shard's wall, the CPU summed."""
    from pltf.reference_server.fleet.config import of_count
    from pltf.reference_server.fleet.local_shards import pipes
    from pltf.reference_server.fleet.shard import placed
    from pltf.reference_server.fleet.shards import plan

    ctx = mp.get_context("spawn")
    with tempfile.TemporaryDirectory() as tmp:
        spec = of_count(count, [0, 0])
        _hall(Path(tmp), [p.name for p in spec.platforms])
        opts = {"data_dir": tmp, "seed": 1, "no_hardware": False, "can_interface": "virtual", "log_level": "WARNING"}
        spec = placed(spec, argparse.Namespace(**opts))
        spec = replace(spec, platforms=tuple(replace(p, seed=1 + k) for k, p in enumerate(spec.platforms)))
        homes = [p.pose for p in spec.platforms]
        plans = plan(spec, processes, 1)
        inbox, outbox = pipes(plans, ctx)
        ctrls, procs = [], []
        for p in plans:
            ours, theirs = ctx.Pipe()
            args = (p, opts, lag, inbox[p.shard], outbox[p.shard], theirs, homes)
            procs.append(ctx.Process(target=_shard, args=args))
            procs[-1].start()
            ctrls.append(ours)
        start = max(_get(c) for c in ctrls)
        t0 = time.perf_counter()
        for c in ctrls:
            c.send((start, seconds))
        results = [_get(c) for c in ctrls]
        wall = time.perf_counter() - t0
        for proc in procs:
            proc.join(30)
    return {
        "wall": max(wall, *(r["wall"] for r in results)),
        "cpu": sum(r["cpu"] for r in results),
        "waited": statistics.mean(r["waited"] for r in results),
    }


def _get(conn: Any) -> Any:
    if not conn.poll(START_TIMEOUT):
        raise RuntimeError(f"a shard said nothing in {START_TIMEOUT:g} s")
    try:
        return conn.recv()
    except EOFError:
        raise RuntimeError("a shard's process ended before it reported (its error is above)") from None


@benchmark()
def processes(config: Config) -> list[Row]:
    """Real-time factor and CPU per platform-second of N platforms in K shard processes, beside one process."""
    sizes = QUICK_SIZES if config.quick else SIZES
    seconds = 1.0 if config.quick else 5.0
    rows: list[Row] = []
    for n in sizes:
        one = fleet_run(n, seconds)
        for k, lag in SPLITS:
            split = split_run(n, seconds, k, lag)
            subject, baseline = f"fleet of {n} in {k} processes (lag {lag})", f"fleet of {n} in one process"
            target = Target("value", ">=", RTF_TARGETS[n]) if n in RTF_TARGETS else None
            rows.append(
                make_row(
                    "fleet_split.processes",
                    subject,
                    "realtime_factor",
                    seconds / split["wall"],
                    "sim-s/s",
                    higher_is_better=True,
                    baseline_subject=baseline,
                    baseline_value=seconds / one["wall"],
                    target=target,
                )
            )
            rows.append(
                make_row(
                    "fleet_split.processes",
                    subject,
                    "cpu_per_platform_second",
                    split["cpu"] / (n * seconds),
                    "cpu-s",
                    higher_is_better=False,
                    baseline_subject=baseline,
                    baseline_value=one["cpu"] / (n * seconds),
                )
            )
            rows.append(
                make_row(
                    "fleet_split.processes",
                    subject,
                    "share_of_wall_waiting_for_peers",
                    split["waited"] / split["wall"],
                    "fraction",
                    higher_is_better=False,
                )
            )
    return rows
