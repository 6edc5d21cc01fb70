"""Scrubbing a recording in the GUI (issue 35, ``pltf gui --session FILE``): seek to a time and draw, p95 <= 100 ms.

The recording is bench_mcap's: an application polling CMD_GET_STATUS at 20 Hz for an hour, each reply with its
541-point scan (~1.5 GB of session file; ``write_recording``). The baseline, in the same run, is the same seeks in a
one-minute recording made the same way: what the hour costs beyond a short file. ``--quick``: a minute against
ten seconds, in seconds.

A seek is timed in the page, as a user's drag of the scrubber ends: from the timeline's ``seek(t)`` (the gateway's
"state at t" and the wire's frames before it, over HTTP, decoded with the codec and published on the session's
topics) until the next animation frame has been drawn (the map view draws on requestAnimationFrame; a task after
it runs once that frame is done). Times are uniform at random over the recording (seeded), SEEKS of them.
Rows: seek p50 and p95 of the hour beside the minute's; the gateway's start-up (indexing the file, from start to
"serving"), and the session file's size. The same hour exported with ``pltf export --mcap --compression C`` for each of
COMPRESSIONS (read in the page with @mcap/core, recorded_mcap.ts), in the same run: its seek p50/p95 beside the
session file's, and its opening (page load until the timeline is there: the summary and the first and last chunk).
"""

from __future__ import annotations

import contextlib
import math
import random
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from benchmarks.bench_mcap import write_recording
from benchmarks.harness import Config, Row, Target, benchmark, make_row
from pltf.gui.launch import GatewayProcess

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--no-first-run"]
VIEWPORT = {"width": 1400, "height": 900}
TARGET_MS = 100.0
SEEKS = 100
HOUR_S, MINUTE_S = 3600.0, 60.0
# pltf export --compression: each is seeked in the same run (zstd is smaller, lz4 decompresses ~9x faster in the page)
COMPRESSIONS = ("zstd", "lz4")

SEEK_JS = """async (times) => {
  const tl = window.pltf.timeline;
  const drawn = () => new Promise((r) => requestAnimationFrame(() => setTimeout(r, 0)));
  await drawn();
  const out = [];
  for (const t of times) {
    const t0 = performance.now();
    await tl.seek(t);
    await drawn();
    out.push(performance.now() - t0);
  }
  return out;
}"""


def _percentile(xs: list[float], q: float) -> float:
    s = sorted(xs)
    return s[min(len(s) - 1, max(0, math.ceil(q * len(s)) - 1))]


@contextlib.contextmanager
def _shown(session: Path) -> Iterator[tuple[Any, float]]:
    """The recording in chromium through ``pltf gui --session``; the page and the gateway's start-up seconds."""
    from playwright.sync_api import sync_playwright

    ini = session.parent / "Network.ini"
    t0 = time.perf_counter()
    with GatewayProcess(ini, target=None, args=("--session", str(session)), start_timeout=300.0) as gw:
        started = time.perf_counter() - t0
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            try:
                pg = browser.new_page(viewport=VIEWPORT)
                t1 = time.perf_counter()
                pg.goto(f"{gw.base}/?recording=1")
                pg.wait_for_function("() => window.pltf.timeline !== null", timeout=60_000)
                yield pg, started if session.suffix != ".mcap" else time.perf_counter() - t1
            finally:
                browser.close()


def _seeks(session: Path, seconds: float, seed: int) -> tuple[list[float], float]:
    rng = random.Random(seed)
    with _shown(session) as (pg, started):
        start = float(pg.get_by_role("region", name="Timeline").get_attribute("data-start"))
        times = [start + rng.uniform(0, seconds) for _ in range(SEEKS)]
        return list(pg.evaluate(SEEK_JS, times)), started


def _mcap_rows(
    config: Config, long_s: float, compression: str, size: int, ms: list[float], opening: float, session_ms: list[float]
) -> list[Row]:
    """The MCAP export's rows (one compression): seek p50/p95 beside the session file's, the worst, the opening."""
    name = f"scrub.seek_and_draw_mcap ({long_s / 60:g} min at 20 Hz, MCAP {compression} {size / 1e6:.0f} MB)"
    ours = f"{long_s:g} s recording, its MCAP export ({compression})"
    rows = [
        make_row(
            name,
            ours,
            f"seek_{metric}",
            _percentile(ms, q),
            "ms",
            higher_is_better=False,
            baseline_subject=f"{long_s:g} s recording, the session file",
            baseline_value=_percentile(session_ms, q),
            target=Target("value", "<=", TARGET_MS) if metric == "p95" and not config.quick else None,
        )
        for metric, q in (("p50", 0.5), ("p95", 0.95))
    ]
    rows.append(make_row(name, ours, "seek_max", max(ms), "ms", higher_is_better=False))
    opened = f"opening the MCAP ({compression}) in the page (until the timeline shows)"
    rows.append(make_row(name, opened, "seconds", opening, "s", higher_is_better=False))
    return rows


@benchmark()
def seek_and_draw(config: Config) -> list[Row]:
    """Seek a one-hour 20 Hz recording to random times and draw (p95 <= 100 ms), beside a one-minute one."""
    long_s, short_s = (MINUTE_S, 10.0) if config.quick else (HOUR_S, MINUTE_S)
    with tempfile.TemporaryDirectory(prefix="pltf-bench-scrub-") as tmp:
        long_file, short_file = Path(tmp) / "long.jsonl", Path(tmp) / "short.jsonl"
        write_recording(long_file, long_s)
        write_recording(short_file, short_s)
        size = long_file.stat().st_size
        short_ms, short_start = _seeks(short_file, short_s, 1)
        long_ms, long_start = _seeks(long_file, long_s, 1)
        mcaps = {}
        for compression in COMPRESSIONS:
            mcap = Path(tmp) / f"long_{compression}.mcap"
            export = [sys.executable, "-m", "pltf.cli.main", "export", str(long_file), "--mcap", str(mcap)]
            subprocess.run([*export, "--compression", compression], check=True, capture_output=True)
            mcaps[compression] = (mcap.stat().st_size, *_seeks(mcap, long_s, 1))
    name = f"scrub.seek_and_draw ({long_s / 60:g} min at 20 Hz, {size / 1e6:.0f} MB)"
    ours, base = f"{long_s:g} s recording", f"{short_s:g} s recording"
    rows = [
        make_row(
            name,
            ours,
            f"seek_{metric}",
            _percentile(long_ms, q),
            "ms",
            higher_is_better=False,
            baseline_subject=base,
            baseline_value=_percentile(short_ms, q),
            target=Target("value", "<=", TARGET_MS) if metric == "p95" and not config.quick else None,
        )
        for metric, q in (("p50", 0.5), ("p95", 0.95))
    ]
    rows.append(make_row(name, ours, "seek_max", max(long_ms), "ms", higher_is_better=False))
    rows.append(
        make_row(
            name,
            "pltf gui --session start-up (indexing)",
            "seconds",
            long_start,
            "s",
            higher_is_better=False,
            baseline_subject=f"the same, {base}",
            baseline_value=short_start,
        )
    )
    for compression, (mcap_size, mcap_ms, mcap_open) in mcaps.items():
        rows += _mcap_rows(config, long_s, compression, mcap_size, mcap_ms, mcap_open, long_ms)
    return rows
