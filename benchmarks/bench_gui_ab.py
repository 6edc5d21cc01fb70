"""The GUI benchmarks as an A/B of two builds of gui/web in ONE run (issue 31: "the GUI benchmarks (pan/zoom, status
to screen, editor edits) do not get slower than in the same run before the change").

Usage (build each side with ``npx vite build --outDir DIR --emptyOutDir`` in a checkout of its commit)::

    PLTF_GUI_AB_OLD=/tmp/static_old PLTF_GUI_AB_NEW=/tmp/static_new PLTF_GUI_AB_ROUNDS=4 \\
        .venv/bin/python -m benchmarks --only gui_ab --json F

Rules:
- Each benchmark runs bench_gui's or bench_editors' own measurement (the same page scripts, the same platform, the
  same actions) once per build and round, each time in a fresh gateway serving that build (``PLTF_GUI_STATIC``,
  checked: the page served is that build's index.html) and a fresh chromium. The rounds alternate the order, old
  then new, then new then old (ABBA ABBA ...), so a spell of load on the shared machine hits both sides.
- A row is one figure of the new build (the median over its rounds of each round's figure) with the old build's
  median as its baseline: ``ratio`` is new/old. ``pooled_p50``/``pooled_p95`` rows take the quantile of all rounds'
  samples of a side together (the p95 of an action's 15 samples in a round is its slowest one). Every round's
  figure, the load average at its start and the two builds' bundles are printed and, with ``PLTF_GUI_AB_RUNS=FILE``,
  written to FILE as JSON with the samples (the spread a reading needs; rows hold medians only).
- ``PLTF_GUI_AB_OLD`` unset: the benchmarks say so and give no rows (``make bench`` runs every group).
  ``PLTF_GUI_AB_NEW`` defaults to gui/static. ``PLTF_GUI_AB_ROUNDS`` (default 4; ``--quick``: 1) is the number of
  old/new pairs.
- Sizes: bench_gui.pan_zoom's 300 pan frames, status_latency's 60 changes without its back-to-back baseline (not a
  property of the build) and 10 s of watching, bench_editors.edit's 15 cycles; ``--quick``: 30 / 8 and 2 s / 2.

Benchmarks: ``gui_ab.pan_zoom``, ``gui_ab.status_latency``, ``gui_ab.edit`` (the figures of gui.pan_zoom,
gui.status_latency and editors.edit, with the page-side figures those print beside: the on-page baseline's
frames, the layer worker's time, the stages of a status change, the page's main thread, the no-edit redraw).
"""

from __future__ import annotations

import json
import os
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from benchmarks.bench_editors import edit_times
from benchmarks.bench_gui import STAGES, _percentile, pan_zoom_frames, status_to_screen
from benchmarks.harness import Config, Row, benchmark, make_row

ROOT = Path(__file__).resolve().parents[1]
OLD_ENV, NEW_ENV, ROUNDS_ENV, RUNS_ENV = "PLTF_GUI_AB_OLD", "PLTF_GUI_AB_NEW", "PLTF_GUI_AB_ROUNDS", "PLTF_GUI_AB_RUNS"
ROUNDS = 4
SIDES = ("old", "new")
QUANTILES = (("p50", 0.5), ("p95", 0.95))

Key = tuple[str, str, str]  # subject, metric, unit
Figures = dict[Key, float]


@dataclass
class Measured:
    """One side's round: its figures, and the samples (ms) behind each quantile, by subject and metric prefix."""

    figures: Figures = field(default_factory=dict)
    samples: dict[tuple[str, str], list[float]] = field(default_factory=dict)


@dataclass(frozen=True)
class Builds:
    dirs: dict[str, Path]  # "old"/"new" -> a vite build (index.html, assets/)
    rounds: int

    def order(self) -> list[str]:
        """old, new, new, old, old, new, ...: ``rounds`` pairs, alternating which side goes first."""
        return [side for r in range(self.rounds) for side in (SIDES if r % 2 == 0 else SIDES[::-1])]


@dataclass
class Run:
    side: str
    round: int
    started: str
    loadavg: str
    seconds: float
    measured: Measured = field(default_factory=Measured)


def _build_dir(var: str, default: Path | None) -> Path:
    given = os.environ.get(var)
    path = Path(given) if given else default
    if path is None or not (path / "index.html").is_file():
        raise SystemExit(
            f"{var}={given or path}: no index.html there (a build of gui/web: npx vite build --outDir DIR)"
        )
    return path.resolve()


def builds(config: Config) -> Builds | None:
    """The two builds and the rounds from the environment; None without ``PLTF_GUI_AB_OLD``."""
    if not os.environ.get(OLD_ENV):
        return None
    dirs = {"old": _build_dir(OLD_ENV, None), "new": _build_dir(NEW_ENV, ROOT / "gui" / "static")}
    raw = os.environ.get(ROUNDS_ENV, "1" if config.quick else str(ROUNDS))
    if not raw.isdigit() or int(raw) < 1:
        raise SystemExit(f"{ROUNDS_ENV}={raw}: a number of old/new pairs, 1 or more")
    return Builds(dirs, int(raw))


def _bundles(static: Path) -> list[str]:
    """A build's hashed bundles (what tells two builds apart): the page's and the layer worker's."""
    return sorted(p.name for p in (static / "assets").glob("*.js"))


def _loadavg() -> str:
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "?"


def _quantiles(m: Measured, subject: str, metric: str, xs: list[float]) -> None:
    if xs:
        m.samples[(subject, metric)] = list(xs)
        for name, q in QUANTILES:
            m.figures[(subject, f"{metric}{name}", "ms")] = _percentile(xs, q)


# ---------------------------------------------------------------------------------------------- the sides' figures
def _pan_zoom(config: Config, static: Path) -> Measured:
    ours, plain = pan_zoom_frames(30 if config.quick else 300, static)
    out = Measured()
    for kind in ("pan", "zoom"):
        _quantiles(out, f"{kind}: layer worker + culling", "frame_", ours[kind])
        _quantiles(out, f"{kind}: drawn on the page per frame", "frame_", plain[kind])
    _quantiles(out, "layer worker (off the page's thread)", "layer_", ours["layer"])
    # of the on-page frame, the static layer's drawing alone (drawStatic; the rest: the canvas, copying the layer)
    _quantiles(out, "static layer drawn on the page (drawStatic alone)", "layer_", plain["layer"])
    return out


def _status(config: Config, static: Path) -> Measured:
    m = status_to_screen(8 if config.quick else 60, 2.0 if config.quick else 10.0, baseline=False, static=static)
    out = Measured()
    _quantiles(out, "status change to screen, GET_STATUS at 20 Hz", "", m.gui)
    for name, ms in zip(STAGES, m.stages, strict=True):
        _quantiles(out, f"stage: {name}", "", ms)
    for what, v in m.busy.items():
        out.figures[(f"page main thread, watching: {what}", "busy", "ms/s")] = v
    return out


def _edit(config: Config, static: Path) -> Measured:
    acts, redraw = edit_times(2 if config.quick else 15, static)
    out = Measured()
    for subject, xs in (*acts.items(), ("all edits", acts["trim"] + acts["undo"] + acts["move"])):
        _quantiles(out, f"{subject}, 50,000 lines, to screen", "", xs)
    _quantiles(out, "view redraw of the same scene, no edit", "", redraw)
    return out


# ---------------------------------------------------------------------------------------------- the A/B
def _say(line: str) -> None:
    print(f"  gui_ab {line}", flush=True)


def _measure(name: str, config: Config, measure: Callable[[Config, Path], Measured]) -> list[Row]:
    ab = builds(config)
    if ab is None:
        _say(f"{name}: skipped ({OLD_ENV} names no build of gui/web to compare with)")
        return []
    for side in SIDES:
        _say(f"{side}: {ab.dirs[side]} ({', '.join(_bundles(ab.dirs[side]))})")
    runs: list[Run] = []
    for k, side in enumerate(ab.order()):
        run = Run(side, k // 2 + 1, time.strftime("%H:%M:%S", time.gmtime()), _loadavg(), 0.0)
        t0 = time.monotonic()
        run.measured = measure(config, ab.dirs[side])
        run.seconds = time.monotonic() - t0
        runs.append(run)
        _say(f"{name} round {run.round} {side}: {run.started} UTC, load {run.loadavg}, {run.seconds:.0f} s")
    _record(name, ab, runs)
    return _rows(name, runs)


def _rows(name: str, runs: list[Run]) -> list[Row]:
    """Per figure: the median of each side's rounds; per sampled subject: the quantiles of all rounds' samples pooled
    (``pooled_p50``, ``pooled_p95``: a p95 of 15 samples in a round is its slowest one, pooled it is more)."""
    rows = []
    for key in dict.fromkeys(key for run in runs for key in run.measured.figures):
        subject, metric, unit = key
        per = {s: [r.measured.figures[key] for r in runs if r.side == s and key in r.measured.figures] for s in SIDES}
        if per["old"] and per["new"]:
            rows.append(
                _ab_row(name, subject, metric, unit, statistics.median(per["new"]), statistics.median(per["old"]))
            )
            _say(f"{name} {subject} {metric}: old {_runs(per['old'])} / new {_runs(per['new'])} {unit}")
    for subject, prefix in dict.fromkeys(k for run in runs for k in run.measured.samples):
        pooled = {
            s: [x for r in runs if r.side == s for x in r.measured.samples.get((subject, prefix), [])] for s in SIDES
        }
        if pooled["old"] and pooled["new"]:
            for q_name, q in QUANTILES:
                new, old = _percentile(pooled["new"], q), _percentile(pooled["old"], q)
                rows.append(_ab_row(name, subject, f"{prefix}pooled_{q_name}", "ms", new, old))
    return rows


def _ab_row(name: str, subject: str, metric: str, unit: str, new: float, old: float) -> Row:
    return make_row(
        f"gui_ab.{name}",
        f"{subject} (new build)",
        metric,
        new,
        unit,
        higher_is_better=False,
        baseline_subject=f"{subject} (old build)",
        baseline_value=old,
    )


def _runs(xs: list[float]) -> str:
    return ", ".join(f"{x:.1f}" for x in xs)


def _record(name: str, ab: Builds, runs: list[Run]) -> None:
    """Every round's figures into ``PLTF_GUI_AB_RUNS`` (one JSON object per benchmark name, merged into the file)."""
    path = os.environ.get(RUNS_ENV)
    if not path:
        return
    file = Path(path)
    doc: dict[str, Any] = json.loads(file.read_text()) if file.is_file() else {}
    doc[name] = {
        "builds": {side: {"dir": str(d), "bundles": _bundles(d)} for side, d in ab.dirs.items()},
        "runs": [
            {
                "side": r.side,
                "round": r.round,
                "started_utc": r.started,
                "loadavg": r.loadavg,
                "seconds": round(r.seconds, 1),
                "figures": [
                    {"subject": s, "metric": m, "unit": u, "value": v} for (s, m, u), v in r.measured.figures.items()
                ],
                "samples_ms": [
                    {"subject": s, "metric": m, "values": [round(x, 3) for x in xs]}
                    for (s, m), xs in r.measured.samples.items()
                ],
            }
            for r in runs
        ],
    }
    file.write_text(json.dumps(doc, indent=2) + "\n")


@benchmark()
def pan_zoom(config: Config) -> list[Row]:
    """gui.pan_zoom's frames in the old and the new build of gui/web, interleaved (PLTF_GUI_AB_OLD, _NEW)."""
    return _measure("pan_zoom", config, _pan_zoom)


@benchmark()
def status_latency(config: Config) -> list[Row]:
    """gui.status_latency's status change to screen in the old and the new build, interleaved."""
    return _measure("status_latency", config, _status)


@benchmark()
def edit(config: Config) -> list[Row]:
    """editors.edit's move, trim and undo to screen in the old and the new build, interleaved."""
    return _measure("edit", config, _edit)
