"""Benchmark harness: ``python -m benchmarks --json FILE [--only NAME] [--quick]``.

Each ``benchmarks/bench_<group>.py`` module registers its benchmark functions with ``@benchmark()`` (see
``benchmarks.harness``); the runner (``benchmarks.runner``) times them, prints a table and writes the rows
with the machine's description to a JSON file.
"""

from benchmarks.harness import (
    REGISTRY,
    ROW_KEYS,
    Config,
    Row,
    Target,
    benchmark,
    make_row,
    median_rates,
    median_times,
    rate_rows,
)

__all__ = [
    "REGISTRY",
    "ROW_KEYS",
    "Config",
    "Row",
    "Target",
    "benchmark",
    "make_row",
    "median_rates",
    "median_times",
    "rate_rows",
]
