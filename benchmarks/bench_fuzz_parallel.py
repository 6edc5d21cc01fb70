"""Parallel campaigns (issue 34): ``pltf fuzz --jobs N`` locally and on a local Ray cluster, beside boofuzz x N; the
fuzzer's own CPU per case beside boofuzz's; the time to the first finding of each planted bug with one and two
workers.

- ``scaling``: aggregate cases/s (the sum of the workers' own rates, each counted from its target's start) with
  N = 1, 2, 4 workers, each with its own reference server; the same on a Ray cluster this benchmark starts (a head
  and one more node on 127.0.0.1, ``ray.cluster_utils.Cluster``), and N boofuzz processes each against its own
  reference server (boofuzz set up as in ``benchmarks.bench_fuzz``). Scaling efficiency: aggregate / (N x the
  rate with one). Every worker's target runs on this machine too: with 2 cores, N = 4 is bounded by the cores.
- ``cpu_per_case``: CPU seconds of the fuzzer's own processes per case the target served (ours: this process and
  its case generator child; boofuzz: this process), on the reference server, the Go emulator and the zoo's
  accept-once, the targets' CPU not counted. Goal: ours <= 1/20 of boofuzz's.
- ``first_finding``: seconds of fuzzing to the first (believed) finding of each planted bug of the zoo, N = 1 and
  N = 2 (``--max-findings 1``; one run each: the figure is a draw, not a median).

Rates and CPU: medians of 3 runs of 10 s per subject, interleaved (``--quick``: one run of 2 s).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import resource
import statistics
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from benchmarks.bench_fuzz import REFERENCE, ZOO, _boofuzz, _served, started
from benchmarks.harness import Config, Row, Target, benchmark, make_row
from benchmarks.proc_cpu import process_cpu
from benchmarks.ray_local import local_cluster
from benchmarks.ray_local import say as _say
from pltf.fuzz.engine import Campaign, HarnessError, Options
from pltf.fuzz.options import Stats
from pltf.fuzz.parallel import LocalCampaign
from pltf.harness.launch import REPO
from pltf.harness.ports import free_ports

# a worker reads its target's ports from its "server started at port N" lines, which --log-level ERROR hides: the
# scaling runs (ours and boofuzz's alike) use the server at its default level
SERVER = REFERENCE.replace(" --log-level ERROR", "")
EMULATOR = f"{REPO / 'emulator' / 'bin' / 'emulator'} --ports {{ports}} --data-dir {{tmpdir}}"
CPU_TARGETS = {"reference server": REFERENCE, "emulator": EMULATOR, "zoo accept-once": ZOO.format(member="accept-once")}
MEMBER = f"{sys.executable} -m pltf.zoo {{member}} --serve emulator --ports {{{{ports}}}} {{args}}"
BUGS = {
    "crash-after-start": MEMBER.format(member="crash-after-start", args=""),
    "crash-in-velocity-mode": MEMBER.format(member="faithful", args="--bug crash-in-velocity-mode"),
    "hang-unknown-key": MEMBER.format(member="hang-unknown-key", args="--hang-seconds 120"),
    "leak": MEMBER.format(member="leak", args=""),
}
LOCAL, RAY, BOOFUZZ_N = "pltf fuzz --jobs", "pltf fuzz --ray --jobs", "boofuzz processes"
CPU_GOAL = 1 / 20  # ours per case over boofuzz's per case
FIND_BUDGET = 60.0  # s of fuzzing to find a planted bug
STARTS = 3  # starts of a target on ports we chose, at most (``ours_cpu``)


def options(launch: str, seconds: float, out: Path, **changes: Any) -> Options:
    opts = Options(
        host="127.0.0.1",
        port=0,
        second_port=0,
        duration=seconds,
        seed=1,
        out=out,
        allow_motion=True,
        launch=launch,
    )
    for k, v in changes.items():
        setattr(opts, k, v)
    return opts


def aggregate(summary: dict[str, Any]) -> float:
    """The campaign's aggregate rate: the sum of its workers' own rates."""
    return float(sum(w.get("cases_per_second", 0.0) for w in summary["workers"]))


def efficiency(rate: float, n: int, single: float) -> float:
    """aggregate / (N x single): 1.0 is perfect scaling."""
    return rate / (n * single) if single > 0 else 0.0


def first_found(summary: dict[str, Any]) -> float | None:
    """Seconds of fuzzing to the campaign's first finding (None: nothing found)."""
    times = [float(f["found_after_s"]) for f in summary["findings"]]
    return min(times) if times else None


# ---------------------------------------------------------------------------------------------- the runs
def local(n: int, launch: str, seconds: float, **changes: Any) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as out:
        campaign = LocalCampaign(options(launch, seconds, Path(out), **changes), n)
        campaign.run()
        return campaign.view.summary()


def on_ray(n: int, launch: str, seconds: float, address: str) -> dict[str, Any]:
    from pltf.fuzz.ray_fuzz import RayCampaign

    with tempfile.TemporaryDirectory() as out:
        campaign = RayCampaign(options(launch, seconds, Path(out)), n, address)
        campaign.run()
        return campaign.view.summary()


def _boofuzz_one(launch: str, seconds: float, results: Any) -> None:
    import boofuzz as bf

    with tempfile.TemporaryDirectory() as tmp, started(launch) as target:
        rate, _ = _boofuzz(bf, target.ports[0], seconds, Path(tmp))
    results.put(rate)


def boofuzz_n(n: int, seconds: float) -> float:
    """N boofuzz processes, each against its own reference server: the sum of their rates."""
    ctx = multiprocessing.get_context("fork")
    results = ctx.Queue()
    procs = [ctx.Process(target=_boofuzz_one, args=(SERVER, seconds, results)) for _ in range(n)]
    for p in procs:
        p.start()
    rates = [results.get(timeout=seconds + 120) for _ in procs]
    for p in procs:
        p.join(timeout=30)
    return float(sum(rates))


def _self_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def ours_cpu(launch: str, seconds: float) -> tuple[float, float]:
    """(ms of the fuzzer's own CPU per case served, cases/s): this process and its case generator child. The
    ports are ours to choose (``_ours_cpu``); another process may take one before the target binds it (a CI run
    beside: "nothing listening on 127.0.0.1:47337 ... connection refused"), so a start that fails runs again on
    other ports, ``STARTS`` times at most."""
    for _ in range(STARTS - 1):
        try:
            return _ours_cpu(launch, seconds)
        except HarnessError as exc:
            _say(f"the target did not start ({exc}): again on other ports")
    return _ours_cpu(launch, seconds)


def _ours_cpu(launch: str, seconds: float) -> tuple[float, float]:
    a, b = free_ports()  # fixed ports: the targets here may log at ERROR, without their ports
    with tempfile.TemporaryDirectory() as out:
        campaign = Campaign(options(launch, seconds, Path(out), port=a, second_port=b))
        child = {"cpu": 0.0}

        def tick(_st: Stats) -> None:  # the generator child's CPU, read while it lives
            proc = campaign.prefetch.proc if campaign.prefetch is not None else None
            cpu = process_cpu(proc.pid) if proc is not None else None
            child["cpu"] = cpu if cpu is not None else child["cpu"]

        campaign.on_tick = tick
        before = _self_cpu()
        campaign.run()
        used = _self_cpu() - before + child["cpu"]
        st = campaign.stats
        return used / max(1, st.cases) * 1e3, st.rate


def boofuzz_cpu(launch: str, seconds: float) -> tuple[float, float]:
    """(ms of boofuzz's CPU per case the target served, cases/s served)."""
    import boofuzz as bf

    member = "pltf.zoo" in launch
    with tempfile.TemporaryDirectory() as tmp:
        stats = Path(tmp) / "served.json"
        with started(launch, stats if member else None) as target:
            before = _self_cpu()
            nominal, elapsed = _boofuzz(bf, target.ports[0], seconds, Path(tmp))
            used = _self_cpu() - before
        served = _served(stats) if member else nominal * elapsed
    return used / max(1.0, served) * 1e3, served / elapsed


@contextlib.contextmanager
def ray_cluster() -> Iterator[str | None]:
    """A head and one more node on 127.0.0.1, its address (None without the ray extra)."""
    with local_cluster(2, "Ray") as cluster:
        yield None if cluster is None else cluster.address


# ---------------------------------------------------------------------------------------------- the benchmarks
@benchmark()
def scaling(config: Config) -> list[Row]:
    """Aggregate cases/s with N = 1, 2, 4 workers (own reference servers), locally and on Ray, vs boofuzz x N."""
    seconds, repeats = (2.0, 1) if config.quick else (10.0, 3)
    ns = (1, 2) if config.quick else (1, 2, 4)
    samples: dict[tuple[str, int], list[float]] = {}

    def add(subject: str, n: int, rate: float) -> None:
        _say(f"{subject} x{n}: {rate:,.0f} cases/s")
        samples.setdefault((subject, n), []).append(rate)

    for _ in range(repeats):  # interleaved; Ray last (a process that started Ray's threads forks no more)
        for n in ns:
            add(LOCAL, n, aggregate(local(n, SERVER, seconds)))
            add(BOOFUZZ_N, n, boofuzz_n(n, seconds))
    with ray_cluster() as address:
        for _ in range(repeats if address else 0):
            for n in ns:
                add(RAY, n, aggregate(on_ray(n, SERVER, seconds, str(address))))
    rates = {k: statistics.median(v) for k, v in samples.items()}
    return scaling_rows(rates)


def scaling_rows(rates: dict[tuple[str, int], float]) -> list[Row]:
    name, rows = "fuzz_parallel.scaling", []
    for (subject, n), rate in rates.items():
        base = (BOOFUZZ_N, n)
        baseline = None if subject.startswith("boofuzz") or base not in rates else rates[base]
        rows.append(
            make_row(
                name,
                f"{subject} {n}",
                "cases_per_second",
                rate,
                "cases/s",
                higher_is_better=True,
                baseline_subject=None if baseline is None else f"{BOOFUZZ_N} {n}",
                baseline_value=baseline,
            )
        )
        if (subject, 1) in rates and n > 1:
            eff = efficiency(rate, n, rates[subject, 1])
            rows.append(make_row(name, f"{subject} {n}", "scaling_efficiency", eff, "x", higher_is_better=True))
    return rows


@benchmark()
def cpu_per_case(config: Config) -> list[Row]:
    """The fuzzer's own CPU per case served, pltf fuzz vs boofuzz, on the reference server, the emulator and
    accept-once (goal: ours <= 1/20 of boofuzz's)."""
    seconds, repeats = (2.0, 1) if config.quick else (10.0, 3)
    ours: dict[str, list[float]] = {}
    theirs: dict[str, list[float]] = {}
    for _ in range(repeats):
        for target, launch in CPU_TARGETS.items():
            ms, rate = ours_cpu(launch, seconds)
            _say(f"pltf fuzz ({target}): {ms:.4f} ms per case, {rate:,.0f} cases/s")
            ours.setdefault(target, []).append(ms)
            ms, rate = boofuzz_cpu(launch, seconds)
            _say(f"boofuzz ({target}): {ms:.4f} ms per case, {rate:,.0f} cases/s served")
            theirs.setdefault(target, []).append(ms)
    rows = []
    for target in CPU_TARGETS:
        base, value = statistics.median(theirs[target]), statistics.median(ours[target])
        subject = f"boofuzz ({target})"
        rows.append(make_row("fuzz_parallel.cpu_per_case", subject, "fuzzer_cpu", base, "ms", higher_is_better=False))
        rows.append(
            make_row(
                "fuzz_parallel.cpu_per_case",
                f"pltf fuzz ({target})",
                "fuzzer_cpu",
                value,
                "ms",
                higher_is_better=False,
                baseline_subject=subject,
                baseline_value=base,
                target=Target("ratio", "<=", CPU_GOAL),
            )
        )
    return rows


@benchmark()
def first_finding(config: Config) -> list[Row]:
    """Seconds of fuzzing to the first finding of each planted bug, with one worker and with two."""
    bugs = dict(list(BUGS.items())[:1]) if config.quick else BUGS
    rows = []
    for bug, launch in bugs.items():
        found: dict[int, float | None] = {}
        for n in (1, 2):
            t0 = time.monotonic()
            summary = local(n, launch, FIND_BUDGET, max_findings=1, minimize_seconds=1.0)
            found[n] = first_found(summary)
            _say(f"{bug} x{n}: first finding after {found[n]} s of fuzzing ({time.monotonic() - t0:.0f} s in all)")
        for n in (1, 2):
            got = found[n]
            value = got if got is not None else float("nan")
            base = found[1] if n == 2 else None
            rows.append(
                make_row(
                    "fuzz_parallel.first_finding",
                    f"{bug}, --jobs {n}",
                    "seconds",
                    value,
                    "s",
                    higher_is_better=False,
                    baseline_subject=f"{bug}, --jobs 1" if base is not None else None,
                    baseline_value=base,
                )
            )
    return rows
