"""The soak's run: start the parts, sample every ``interval`` s for ``duration`` s, stop, replay, judge, report.

    python -m benchmarks.soak --duration 3600 --interval 60 --out benchmarks/results/soak.md   # make soak
    python -m benchmarks.soak --minutes 10                                                   # a shorter one

Exit status 0 when every slope is within its bound, no part ended, nothing was lost (every frame of the recording
decodes again, every reply has its request, and the reconnecting client's connections are all in it) and ``pltf
replay`` of the recording against a fresh reference server passes (benchmarks/soak/replay.py: its peak RSS and
duration are reported; ``--no-replay`` leaves it out); 1 otherwise; 2 when a part cannot be started.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.soak import integrity, parts, report, sampling
from benchmarks.soak.replay import replay
from benchmarks.soak.report import Outcome
from pltf.harness.launch import LaunchError

REPLAY_TIMEOUT_PAD = 600.0  # s beyond twice the recorded duration over the replay's time scale


def options(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m benchmarks.soak", description=__doc__.split("\n\n")[0])
    p.add_argument("--duration", type=float, default=3600.0, help="seconds of wall time (default 3600)")
    p.add_argument("--minutes", type=float, help="minutes of wall time (instead of --duration)")
    p.add_argument("--interval", type=float, default=60.0, help="seconds between samples (default 60)")
    p.add_argument("--warmup", type=float, default=600.0, help="seconds left out of the slopes (default 600)")
    p.add_argument("--time-scale", type=float, default=10.0, help="the server's time scale (default 10)")
    p.add_argument("--reconnect-every", type=float, default=3.0, help="seconds between reconnects (default 3)")
    p.add_argument("--no-replay", dest="replay", action="store_false", help="leave out `pltf replay` of the recording")
    p.add_argument("--replay-scale", type=float, default=1.0, help="replay X times as fast (its server too)")
    p.add_argument("--workdir", type=Path, help="where the recording and the samples go (default: a new temp dir)")
    p.add_argument("--out", type=Path, help="append the results to this markdown file")
    args = p.parse_args(argv)
    if args.minutes is not None:
        args.duration = 60.0 * args.minutes
    if args.duration <= 0 or args.interval <= 0 or args.replay_scale <= 0:
        p.error("--duration, --minutes, --interval and --replay-scale must be positive")
    return args


def main(argv: list[str] | None = None) -> int:
    args = options(argv)
    workdir = args.workdir or Path(tempfile.mkdtemp(prefix="pltf-soak-"))
    workdir.mkdir(parents=True, exist_ok=True)
    print(f"soak: working in {workdir}", flush=True)
    try:
        outcome = soak(args, workdir)
    except LaunchError as exc:
        print(f"soak: error: {exc}", file=sys.stderr)
        return 2
    text = report.render(args, outcome, workdir)
    print(text)
    if args.out is not None:
        report.append_atomically(args.out, text)
    return 0 if report.passed(args, outcome) else 1


def soak(args: argparse.Namespace, workdir: Path) -> Outcome:
    samples_file = workdir / "samples.jsonl"
    samples: list[dict[str, Any]] = []
    with parts.started(workdir, args.time_scale, args.reconnect_every) as p:
        meter = sampling.RecordingMeter(p.record)
        start = time.monotonic()
        while True:
            t = time.monotonic() - start
            s = sampling.take(t, p.processes(), meter, p.dead())
            samples.append(s)
            sampling.append(samples_file, s)
            print(f"soak: {t:6.0f} s  load {s['load']:.1f}  {_brief(s)}", flush=True)
            if t >= args.duration or s["dead"]:
                break
            _wait(p.page, min(args.interval, args.duration - t))
        dead = p.dead()
        reconnect_log, patrol_log = p.reconnect, p.patrol
        p.reconnect.stop()
        reconnect = _last(reconnect_log.output, "reconnect:")
        patrol = _patrol_summary(patrol_log.whole_output())
    outcome = Outcome(samples, dead, reconnect=reconnect, patrol=patrol, second_port=p.server.ports[1])
    final = sampling.RecordingMeter(p.record).read()
    outcome.samples.append({**samples[-1], "recording": final, "t": samples[-1]["t"], "final": True})
    print("soak: checking the recording", flush=True)
    outcome.recording_check = integrity.check(p.record)
    if args.replay:
        print("soak: replaying the recording", flush=True)
        _replay(args, p.record, outcome)
    return outcome


def _brief(s: dict[str, Any]) -> str:
    rec = s["recording"]
    return f"{len(s['procs'])} processes, recording {rec['bytes'] / 1e6:.1f} MB, {rec['telegrams']} telegrams"


def _wait(page: Any, seconds: float) -> None:
    """Sleep while Playwright keeps reading the browser's events (a sync Playwright left alone lets its pipe fill)."""
    end = time.monotonic() + seconds
    while (left := end - time.monotonic()) > 0:
        page.wait_for_timeout(min(left, 5.0) * 1000)


def _last(lines: list[str], prefix: str) -> str:
    return next((line for line in reversed(lines) if line.startswith(prefix)), "")


def _patrol_summary(lines: list[str]) -> str:
    reached = sum(line.startswith("reached ") for line in lines)
    refused = sum(line.startswith("refused ") for line in lines)
    rounds = sum(line.startswith("round ") for line in lines)
    return f"{reached} stations reached, {refused} refusals, {rounds} rounds"


def _replay(args: argparse.Namespace, record: Path, outcome: Outcome) -> None:
    """``pltf replay`` of the recording against a fresh reference server (same seed, fixtures' data)."""
    recorded = outcome.samples[-1]["t"]
    timeout = 2 * recorded / args.replay_scale + REPLAY_TIMEOUT_PAD
    outcome.replayed = replay(record, args.time_scale, args.replay_scale, timeout)
    print(f"soak: replay: {outcome.replayed.summary()}", flush=True)


def samples_of(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]


__all__ = ["Outcome", "main", "samples_of"]
