"""Run the registered benchmarks, print a table, write the rows and the machine's description as JSON.

Usage: ``python -m benchmarks --json FILE [--only NAME ...] [--quick] [--strict]``

``--only`` takes a group (``codec``: every benchmark of ``bench_codec.py``) or a full name
(``codec.status``); it may be repeated or comma-separated. ``--quick`` is a smoke test: few repeats, short
repeats, meaningless figures. ``--strict`` exits 1 when a target is missed.
"""

from __future__ import annotations

import argparse
import datetime
import importlib
import json
import os
import pkgutil
import platform
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

import benchmarks
from benchmarks.harness import REGISTRY, ROW_KEYS, Benchmark, Config, Row

PREFIX = "bench_"


def available_groups() -> list[str]:
    return sorted(
        m.name.removeprefix(PREFIX) for m in pkgutil.iter_modules(benchmarks.__path__) if m.name.startswith(PREFIX)
    )


def select(only: list[str]) -> list[Benchmark]:
    """Import the modules the selection needs and return the selected benchmarks, in registration order."""
    groups = available_groups()
    wanted = {sel.split(".", 1)[0] for sel in only} if only else set(groups)
    unknown = wanted - set(groups)
    if unknown:
        raise SystemExit(f"no benchmark group {', '.join(sorted(unknown))} (groups: {', '.join(groups)})")
    for group in groups:
        if group in wanted:
            importlib.import_module(f"benchmarks.{PREFIX}{group}")
    chosen = [b for b in REGISTRY.values() if not only or any(sel in (b.group, b.name) for sel in only)]
    missing = [sel for sel in only if not any(sel in (b.group, b.name) for b in chosen)]
    if missing:
        names = ", ".join(REGISTRY)
        raise SystemExit(f"no benchmark named {', '.join(missing)} (benchmarks: {names})")
    return chosen


def _git_commit() -> str | None:
    try:
        out = subprocess.run(
            ["git", "rev-parse", "HEAD"],
            cwd=Path(__file__).resolve().parent,
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def machine_info() -> dict[str, Any]:
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        usable = None
    return {
        "python_version": platform.python_version(),
        "python_implementation": platform.python_implementation(),
        "python_build": " ".join(platform.python_build()),
        "cpu_count": os.cpu_count(),
        "cpu_usable": usable,
        "platform": platform.platform(),
        "machine": platform.machine(),
        "processor": platform.processor() or None,
        "hostname": platform.node(),
    }


def _fmt(x: Any) -> str:
    if x is None:
        return ""
    if isinstance(x, bool):
        return str(x)
    if isinstance(x, float):
        if x >= 1000:
            return f"{x:,.0f}"
        return f"{x:.3g}" if x < 10 else f"{x:.1f}"
    return str(x)


def render(rows: list[Row], console: Console) -> None:
    table = Table(title="Benchmarks (medians)", show_lines=False)
    for col, justify in [
        ("benchmark", "left"),
        ("subject", "left"),
        ("metric", "left"),
        ("value", "right"),
        ("unit", "left"),
        ("baseline", "left"),
        ("ratio (time)", "right"),
        ("target", "left"),
        ("met", "center"),
    ]:
        table.add_column(col, justify=justify)  # type: ignore[arg-type]
    previous = None
    for r in rows:
        met = {True: "[green]yes[/green]", False: "[bold red]NO[/bold red]", None: ""}[r["met"]]
        bench = "" if r["benchmark"] == previous else r["benchmark"]
        if previous is not None and bench:
            table.add_section()
        previous = r["benchmark"]
        ratio = "" if r["ratio"] is None else f"{r['ratio']:.2f}x"
        table.add_row(
            bench,
            r["subject"],
            r["metric"],
            _fmt(r["value"]),
            r["unit"],
            _fmt(r["baseline_subject"]),
            ratio,
            _fmt(r["target"]),
            met,
        )
    console.print(table)


def _check_rows(bench: Benchmark, rows: list[Row]) -> None:
    for r in rows:
        if tuple(r) != ROW_KEYS:
            raise ValueError(f"{bench.name}: row keys {tuple(r)} differ from {ROW_KEYS}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", required=True, type=Path, metavar="FILE", help="write all rows here")
    parser.add_argument(
        "--only",
        action="append",
        default=[],
        metavar="NAME",
        help="a group (e.g. codec) or a benchmark (e.g. codec.status); repeatable, comma-separated",
    )
    parser.add_argument("--quick", action="store_true", help="smoke test: few short repeats (figures meaningless)")
    parser.add_argument("--strict", action="store_true", help="exit 1 when a target is missed")
    parser.add_argument("--list", action="store_true", help="list the benchmarks and exit")
    args = parser.parse_args(argv)
    only = [s.strip() for sel in args.only for s in sel.split(",") if s.strip()]

    console = Console() if sys.stdout.isatty() else Console(width=140)
    chosen = select(only)
    if args.list:
        for b in chosen:
            console.print(f"{b.name}: {b.description}")
        return 0
    config = Config.make(args.quick)
    info = machine_info()
    console.print(
        f"Python {info['python_version']} on {info['platform']}, {info['cpu_count']} CPUs "
        f"({info['cpu_usable']} usable); {config.repeats} repeats per subject, medians"
        + (" [yellow](--quick: smoke test, figures meaningless)[/yellow]" if config.quick else "")
    )
    started = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    rows: list[Row] = []
    runs = []
    for bench in chosen:
        console.print(f"running {bench.name} ...")
        t0 = time.perf_counter()
        bench_rows = bench.func(config)
        _check_rows(bench, bench_rows)
        runs.append({"name": bench.name, "description": bench.description, "seconds": time.perf_counter() - t0})
        rows.extend(bench_rows)
    render(rows, console)
    missed = [r for r in rows if r["met"] is False]
    for r in missed:
        console.print(
            f"[bold red]target missed[/bold red]: {r['benchmark']} {r['subject']}: {r['target']} "
            f"(value {_fmt(r['value'])}, ratio {_fmt(r['ratio'])})"
        )
    document = {
        "started": started,
        "git_commit": _git_commit(),
        "argv": sys.argv[1:] if argv is None else argv,
        "machine": info,
        "config": {
            "quick": config.quick,
            "repeats": config.repeats,
            "min_repeat_time": config.min_repeat_time,
            "statistic": "median",
            "clock": "time.perf_counter",
            "gc_during_timing": "disabled (collected before each repeat)",
        },
        "benchmarks": runs,
        "rows": rows,
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(document, indent=2) + "\n")
    console.print(f"wrote {len(rows)} rows to {args.json}")
    return 1 if args.strict and missed else 0
