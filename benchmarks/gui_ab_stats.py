"""How sure an A/B of two GUI builds is (bench_gui_ab): the pooled quantiles of a subject's samples, their new/old
ratio, a cluster bootstrap CI of the ratio over rounds and a permutation p over the rounds' sides.

Usage (RUNS: the file ``PLTF_GUI_AB_RUNS`` named in a ``python -m benchmarks --only gui_ab...`` run)::

    .venv/bin/python -m benchmarks.gui_ab_stats RUNS [--benchmark edit] [--subject move] [--seed 1]

Rules:
- A round is the unit: its samples (an action's 15 in an edit round) came from one page in one browser at one
  moment of the shared machine's load, so they are not independent of each other. Quantiles are taken of all
  rounds' samples of a side pooled (as bench_gui_ab's ``pooled_p50``/``pooled_p95`` rows, nearest rank).
- CI95: the cluster bootstrap - each side's rounds drawn with replacement (``BOOT`` times), their samples pooled,
  the ratio of the quantiles; the 2.5 and 97.5 percentiles of those ratios.
- p: the rounds were run in pairs (ABBA: round r holds one old and one new run, one just after the other), so the
  permutation swaps the two sides within a round: every one of the 2^R ways when R <= ``EXACT_MAX``, else
  ``PERMS`` drawn. Two-sided on |log ratio|: the share of relabellings at least as far from 1 as the one measured
  (the measured one among them). With 8 rounds the smallest p there is is 2/256 = 0.008.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import random
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmarks.bench_gui import _percentile

QUANTILES = (("p50", 0.5), ("p95", 0.95))
BOOT = 2000
PERMS = 4096
EXACT_MAX = 12

Rounds = list[list[float]]  # one list of samples (ms) per round


@dataclass(frozen=True)
class Compared:
    """One quantile of one subject, old against new."""

    quantile: str
    old: float
    new: float
    ratio: float
    low: float  # CI95 of the ratio, cluster bootstrap over rounds
    high: float
    p: float  # permutation over the rounds' sides, two-sided


def _pooled(rounds: Rounds, q: float) -> float:
    return _percentile([x for r in rounds for x in r], q)


def _ratio(old: Rounds, new: Rounds, q: float) -> float:
    base = _pooled(old, q)
    return _pooled(new, q) / base if base > 0 else math.inf


def bootstrap(old: Rounds, new: Rounds, q: float, rng: random.Random, n: int = BOOT) -> tuple[float, float]:
    """CI95 of the new/old ratio of the pooled quantile ``q``, each side's rounds resampled with replacement."""
    ratios = sorted(_ratio(rng.choices(old, k=len(old)), rng.choices(new, k=len(new)), q) for _ in range(n))
    return ratios[int(0.025 * (n - 1))], ratios[int(0.975 * (n - 1))]


def _swaps(rounds: int, rng: random.Random) -> list[tuple[bool, ...]]:
    if rounds <= EXACT_MAX:
        return list(itertools.product((False, True), repeat=rounds))
    return [tuple(rng.random() < 0.5 for _ in range(rounds)) for _ in range(PERMS)]


def permutation_p(old: Rounds, new: Rounds, q: float, rng: random.Random) -> float:
    """Two-sided p of the ratio of the pooled quantile ``q`` when round r's old and new runs are swapped at random
    (``old[r]`` and ``new[r]`` are one round's pair)."""
    if len(old) != len(new):
        raise ValueError(f"paired rounds needed: {len(old)} old, {len(new)} new")
    far = abs(math.log(_ratio(old, new, q)))
    hits = total = 0
    for swap in _swaps(len(old), rng):
        a = [n if s else o for o, n, s in zip(old, new, swap, strict=True)]
        b = [o if s else n for o, n, s in zip(old, new, swap, strict=True)]
        total += 1
        hits += abs(math.log(_ratio(a, b, q))) >= far - 1e-12
    return hits / total


def compare(old: Rounds, new: Rounds, seed: int = 1) -> list[Compared]:
    """p50 and p95 of a subject, old rounds against new (paired by index)."""
    out = []
    for name, q in QUANTILES:
        rng = random.Random(seed)
        low, high = bootstrap(old, new, q, rng)
        p = permutation_p(old, new, q, rng)
        out.append(Compared(name, _pooled(old, q), _pooled(new, q), _ratio(old, new, q), low, high, p))
    return out


# ---------------------------------------------------------------------------------------------- a RUNS file
def subjects(doc: dict[str, Any], benchmark: str) -> dict[str, tuple[Rounds, Rounds]]:
    """A RUNS file's benchmark: per sampled subject, the old and the new rounds' samples, in round order."""
    if benchmark not in doc:
        raise SystemExit(f"no benchmark {benchmark!r} in the runs file (it has: {', '.join(doc) or 'none'})")
    out: dict[str, tuple[Rounds, Rounds]] = {}
    runs = sorted(doc[benchmark]["runs"], key=lambda r: r["round"])
    for run in runs:
        for s in run["samples_ms"]:
            key = s["subject"] + (f" [{s['metric'].rstrip('_')}]" if s["metric"] else "")
            old, new = out.setdefault(key, ([], []))
            (old if run["side"] == "old" else new).append([float(x) for x in s["values"]])
    return out


def table(doc: dict[str, Any], benchmark: str, only: str = "", seed: int = 1) -> str:
    """The Markdown table of every subject (or those containing ``only``) of a RUNS file's benchmark."""
    lines = [
        "| subject | quantile | old (ms) | new (ms) | new/old | CI95 (rounds) | p |",
        "|---|---|---|---|---|---|---|",
    ]
    for subject, (old, new) in subjects(doc, benchmark).items():
        if only not in subject or not old or len(old) != len(new):
            continue
        for c in compare(old, new, seed):
            lines.append(
                f"| {subject} | {c.quantile} | {c.old:.1f} | {c.new:.1f} | {c.ratio:.2f} | "
                f"[{c.low:.2f}, {c.high:.2f}] | {c.p:.3f} |"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.gui_ab_stats", description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", type=Path, help="the PLTF_GUI_AB_RUNS file of a gui_ab run")
    ap.add_argument("--benchmark", default="edit", help="pan_zoom, status_latency or edit (default)")
    ap.add_argument("--subject", default="", help="only the subjects whose name contains this")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    try:
        doc = json.loads(args.runs.read_text())
    except (OSError, ValueError) as e:
        print(f"{args.runs}: not a runs file of bench_gui_ab ({e})", file=sys.stderr)
        return 2
    print(table(doc, args.benchmark, args.subject, args.seed))
    return 0


if __name__ == "__main__":
    sys.exit(main())
