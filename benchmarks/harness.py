"""The benchmark registry, the timing loop and the result rows.

Rules:
- A benchmark module is ``benchmarks/bench_<group>.py``; its functions decorated with ``@benchmark()`` are
  registered as ``<group>.<function name>`` (or ``<group>.<name>``). The runner imports only the modules a
  ``--only`` selection needs, so adding a module is all it takes to extend the harness.
- A benchmark function takes a ``Config`` and returns a list of rows (``make_row``), each a dict with exactly
  the keys of ``ROW_KEYS``.
- Times come from ``time.perf_counter``; every subject is timed over ``config.repeats`` repeats and the MEDIAN
  is reported. Subjects compared with each other are timed interleaved (repeat 1 of A, B, C, then repeat 2,
  ...), so a noisy spell on the machine hits all of them rather than one. As in ``timeit``, the garbage
  collector is paused inside a timed repeat (and collected before it).
- ``ratio`` is always a TIME ratio: the subject's time per operation over its baseline's (so ``ratio <= 1.5``
  means "at most 1.5x slower than the baseline", ``ratio >= 10`` means "at least 10x slower").
"""

from __future__ import annotations

import gc
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

ROW_KEYS = (
    "benchmark",
    "subject",
    "metric",
    "value",
    "unit",
    "baseline_subject",
    "baseline_value",
    "ratio",
    "target",
    "met",
)

Row = dict[str, Any]


@dataclass(frozen=True)
class Config:
    """How hard to measure: ``quick`` is a smoke test, its figures mean nothing."""

    quick: bool = False
    repeats: int = 7  # timed repeats per subject; the median is reported
    min_repeat_time: float = 0.2  # seconds one repeat should last (sets the calls per repeat)

    @classmethod
    def make(cls, quick: bool) -> Config:
        if quick:
            return cls(quick=True, repeats=2, min_repeat_time=0.005)
        return cls()


@dataclass(frozen=True)
class Benchmark:
    name: str  # "<group>.<name>"
    group: str
    func: Callable[[Config], list[Row]]
    description: str


REGISTRY: dict[str, Benchmark] = {}


def benchmark(name: str | None = None) -> Callable[[Callable[[Config], list[Row]]], Callable[[Config], list[Row]]]:
    """Register a benchmark function of a ``benchmarks.bench_<group>`` module."""

    def register(func: Callable[[Config], list[Row]]) -> Callable[[Config], list[Row]]:
        module = func.__module__.rsplit(".", 1)[-1]
        if not module.startswith("bench_"):
            raise ValueError(f"benchmark {func.__qualname__} must live in a benchmarks.bench_<group> module")
        group = module.removeprefix("bench_")
        full = f"{group}.{name or func.__name__}"
        if full in REGISTRY and REGISTRY[full].func is not func:
            raise ValueError(f"benchmark {full} registered twice")
        doc = (func.__doc__ or "").strip().splitlines()
        REGISTRY[full] = Benchmark(full, group, func, doc[0] if doc else "")
        return func

    return register


# ---------------------------------------------------------------------------------------------- targets


@dataclass(frozen=True)
class Target:
    """A goal on one numeric key of a row, e.g. ``Target("ratio", "<=", 1.5)``."""

    key: str  # "value" or "ratio"
    op: str  # ">=" or "<="
    bound: float

    def __post_init__(self) -> None:
        if self.key not in ("value", "ratio") or self.op not in (">=", "<="):
            raise ValueError(f"unsupported target {self}")

    def __str__(self) -> str:
        return f"{self.key} {self.op} {self.bound:g}"

    def met(self, row: Row) -> bool | None:
        x = row[self.key]
        if x is None:
            return None
        return bool(x >= self.bound) if self.op == ">=" else bool(x <= self.bound)


# ---------------------------------------------------------------------------------------------- rows


def make_row(
    benchmark: str,
    subject: str,
    metric: str,
    value: float,
    unit: str,
    *,
    higher_is_better: bool,
    baseline_subject: str | None = None,
    baseline_value: float | None = None,
    target: Target | None = None,
) -> Row:
    """One result; ``ratio`` is the time ratio subject/baseline (see the module docstring); None where a divisor
    is 0 (a figure that rounds to nothing in one build or subject has no ratio, not a crash of the run)."""
    ratio = None
    if baseline_value is not None:
        num, den = (baseline_value, value) if higher_is_better else (value, baseline_value)
        ratio = num / den if den else None
    row: Row = {
        "benchmark": benchmark,
        "subject": subject,
        "metric": metric,
        "value": value,
        "unit": unit,
        "baseline_subject": baseline_subject,
        "baseline_value": baseline_value,
        "ratio": ratio,
        "target": None if target is None else str(target),
        "met": None,
    }
    if target is not None:
        row["met"] = target.met(row)
    return row


def rate_rows(
    benchmark: str,
    metric: str,
    unit: str,
    rates: dict[str, float],
    baselines: dict[str, str] | None = None,
    targets: dict[str, Target] | None = None,
) -> list[Row]:
    """Rows of rates (operations per second) of several subjects, each against an optional baseline subject."""
    baselines, targets = baselines or {}, targets or {}
    rows = []
    for subject, value in rates.items():
        base = baselines.get(subject)
        rows.append(
            make_row(
                benchmark,
                subject,
                metric,
                value,
                unit,
                higher_is_better=True,
                baseline_subject=base,
                baseline_value=None if base is None else rates[base],
                target=targets.get(subject),
            )
        )
    return rows


# ---------------------------------------------------------------------------------------------- timing


def _time_calls(func: Callable[[], object], number: int) -> float:
    """Seconds for ``number`` calls of ``func`` with the collector paused."""
    loop = range(number)
    gc.collect()
    enabled = gc.isenabled()
    gc.disable()
    try:
        t0 = time.perf_counter()
        for _ in loop:
            func()
        return time.perf_counter() - t0
    finally:
        if enabled:
            gc.enable()


def calibrate(func: Callable[[], object], min_time: float) -> int:
    """Calls per repeat so that one repeat lasts about ``min_time`` (the first call doubles as a warm-up)."""
    func()
    number = 1
    while True:
        elapsed = _time_calls(func, number)
        if elapsed >= min_time:
            return number
        if elapsed <= 0:
            number *= 10
            continue
        number = max(number + 1, int(number * min(10.0, 1.2 * min_time / elapsed)))


def median_times(
    subjects: dict[str, Callable[[], object]],
    config: Config,
    number: int | None = None,
) -> dict[str, float]:
    """Median seconds per call of each subject, timed interleaved over ``config.repeats`` repeats.

    ``number`` fixes the calls per repeat (e.g. 1 for a callable that walks a whole stream); by default it is
    calibrated per subject from ``config.min_repeat_time``.
    """
    numbers = {
        name: number if number is not None else calibrate(func, config.min_repeat_time)
        for name, func in subjects.items()
    }
    if number is not None:
        for func in subjects.values():
            func()  # warm-up
    samples: dict[str, list[float]] = {name: [] for name in subjects}
    for _ in range(config.repeats):
        for name, func in subjects.items():
            samples[name].append(_time_calls(func, numbers[name]) / numbers[name])
    return {name: statistics.median(times) for name, times in samples.items()}


def median_rates(
    subjects: dict[str, Callable[[], object]],
    config: Config,
    number: int | None = None,
    ops_per_call: int = 1,
) -> dict[str, float]:
    """Operations per second of each subject (``ops_per_call`` operations per call), from the median time."""
    return {name: ops_per_call / t for name, t in median_times(subjects, config, number).items()}
