"""The soak's run: start the parts, sample every ``interval`` s for ``duration`` s, stop, replay, judge, report.

    python -m benchmarks.soak --duration 3600 --interval 60 --out benchmarks/results/soak.md   # make soak

Exit status 0 when every slope is within its bound, no part ended and nothing was lost: every frame of the recording
decodes again, every reply has its request, and the reconnecting client's connections are all in it (and, with
``--replay``, ``pltf replay`` of the recording passes); 1 otherwise; 2 when a part cannot be started.

``pltf replay`` is an option, not the default: it keeps the whole session in memory (about 7 bytes of RSS per byte
of session file: 878 MB for the 127 MB of two minutes here) and takes longer than the recording (a GUI's polling is
one long wait), so an hour's recording of several GB is out of its reach on this machine.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from benchmarks.soak import integrity, parts, report, sampling
from pltf.zoo.launch import LaunchError, python, reference

REPLAY_TIMEOUT_PAD = 600.0  # s beyond the recorded duration over the replay's time scale


@dataclass
class Outcome:
    samples: list[dict[str, Any]]
    dead: list[str]
    replay_status: int | None = None
    replay_lines: list[str] = field(default_factory=list)
    reconnect: str = ""
    patrol: str = ""
    recording_check: integrity.Integrity | None = None
    second_port: int = 0


def options(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m benchmarks.soak", description=__doc__.split("\n\n")[0])
    p.add_argument("--duration", type=float, default=3600.0, help="seconds of wall time (default 3600)")
    p.add_argument("--interval", type=float, default=60.0, help="seconds between samples (default 60)")
    p.add_argument("--warmup", type=float, default=600.0, help="seconds left out of the slopes (default 600)")
    p.add_argument("--time-scale", type=float, default=10.0, help="the server's time scale (default 10)")
    p.add_argument("--reconnect-every", type=float, default=3.0, help="seconds between reconnects (default 3)")
    p.add_argument("--replay", action="store_true", help="also `pltf replay` the recording (short runs only)")
    p.add_argument("--replay-scale", type=float, default=1.0, help="replay X times as fast (its server too)")
    p.add_argument("--workdir", type=Path, help="where the recording and the samples go (default: a new temp dir)")
    p.add_argument("--out", type=Path, help="append the results to this markdown file")
    return p.parse_args(argv)


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
    scale = args.replay_scale
    server = reference(time_scale=args.time_scale * scale, seed=1)
    with server:
        p1, p2 = server.ports
        cmd = python("pltf.cli.main", "replay", str(record), "--target", f"127.0.0.1:{p1}", "--second-port", str(p2))
        cmd += ["--time-scale", f"{scale:g}"]
        recorded = outcome.samples[-1]["t"]
        try:
            done = subprocess.run(
                cmd, capture_output=True, text=True, timeout=recorded / scale + REPLAY_TIMEOUT_PAD, check=False
            )
        except subprocess.TimeoutExpired:
            outcome.replay_lines = ["the replay did not end in time"]
            return
    outcome.replay_status = done.returncode
    outcome.replay_lines = (done.stdout + done.stderr).splitlines()


def samples_of(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines() if line.strip()]


__all__ = ["Outcome", "main", "samples_of"]
