"""The soak's figures as markdown: machine, date, load; a slope per process and quantity against its bound; the
recording's size against its telegram count; the replay's verdict.

Rules:
- ``render`` is a pure function of the options, the outcome and the work directory's name; ``append_atomically``
  writes the results file through a temporary file and ``os.replace``.
- A process is judged only when it has at least three samples after the warm-up (``slopes.slope``).
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import os
import platform
import re
import statistics
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmarks.soak import integrity, sampling, slopes
from benchmarks.soak.replay import Replayed

QUANTITIES = ("rss_mb", "fds", "threads")
SHOWN_LINES = 20  # of pltf replay's output


@dataclass
class Outcome:
    """What a soak saw, for ``render``: the samples, the processes that died, and the checks after the run."""

    samples: list[dict[str, Any]]
    dead: list[str]
    replayed: Replayed | None = None  # None: not replayed (--no-replay)
    reconnect: str = ""
    patrol: str = ""
    recording_check: integrity.Integrity | None = None
    second_port: int = 0


def judged(args: argparse.Namespace, samples: list[dict[str, Any]]) -> list[tuple[str, str, list[slopes.Slope]]]:
    """Per process (pid, name) its slopes after the warm-up; processes with too few samples are left out."""
    out = []
    for pid, (name, by) in sampling.series([s for s in samples if not s.get("final")]).items():
        found = [s for q in QUANTITIES if (s := slopes.slope(q, by[q], args.warmup)) is not None]
        if found:
            out.append((pid, name, found))
    return sorted(out, key=lambda row: (row[1], int(row[0])))


def passed(args: argparse.Namespace, outcome: Outcome) -> bool:
    within = all(s.within for _, _, ss in judged(args, outcome.samples) for s in ss)
    replay_ok = outcome.replayed.status == 0 if outcome.replayed is not None else not args.replay
    return within and not outcome.dead and not lost(outcome) and replay_ok


def reconnects(outcome: Outcome) -> int | None:
    found = re.search(r"reconnect: (\d+) connections", outcome.reconnect)
    return int(found.group(1)) if found else None


def lost(outcome: Outcome) -> list[str]:
    """What the recording misses: its own problems, and the reconnecting client's connections not in it (the
    second port's connections are the patrol's one and the reconnecting client's)."""
    check = outcome.recording_check
    if check is None:
        return ["the recording was not checked"]
    out = list(check.problems[:5])
    n, recorded = reconnects(outcome), check.connections[outcome.second_port]
    if n is None:
        out.append("the reconnecting client printed no count")
    elif recorded != n + 1:
        out.append(f"the second port's recorded connections: {recorded}, the clients made {n + 1}")
    return out


def _machine() -> str:
    cpu = ""
    with contextlib.suppress(OSError, StopIteration):
        cpu = next(
            line.split(":", 1)[1].strip()
            for line in Path("/proc/cpuinfo").read_text().splitlines()
            if line.startswith("model name")
        )
    mem = ""
    try:
        kb = int(Path("/proc/meminfo").read_text().split()[1])
        mem = f", {kb / 1024 / 1024:.1f} GB RAM"
    except (OSError, ValueError, IndexError):
        pass
    return f"{platform.node()}: {os.cpu_count()} cores ({cpu}){mem}, {platform.system()} {platform.release()}"


def render(args: argparse.Namespace, outcome: Outcome, workdir: Path) -> str:
    samples = [s for s in outcome.samples if not s.get("final")]
    loads = [s["load"] for s in samples]
    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    verdict = "PASSED" if passed(args, outcome) else "FAILED"
    replay = f" --replay-scale {args.replay_scale:g}" if args.replay else " --no-replay"
    lines = [
        f"## {now}: {args.duration / 60:g} minutes at time scale {args.time_scale:g}: {verdict}",
        "",
        f"Machine: {_machine()}. Load average (1 minute) over the samples: min {min(loads):.1f}, "
        f"median {statistics.median(loads):.1f}, max {max(loads):.1f}.",
        "",
        f"`python -m benchmarks.soak --duration {args.duration:g} --interval {args.interval:g} --warmup "
        f"{args.warmup:g} --time-scale {args.time_scale:g} --reconnect-every {args.reconnect_every:g}{replay}`; "
        f"{len(samples)} samples; slopes: least squares over the samples "
        f"from {args.warmup / 60:g} minutes on, per hour of wall time. Bounds: "
        + ", ".join(f"{unit} <= {bound:g}" for unit, bound in slopes.BOUNDS.values())
        + ".",
        "",
        "| process | pid | RSS MB (first, last) | RSS MB/hour | fds (first, last) | fds/hour | threads (first, last) "
        "| threads/hour | within |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for pid, name, ss in judged(args, outcome.samples):
        by = {s.quantity: s for s in ss}
        cells = []
        for q in QUANTITIES:
            s = by.get(q)
            cells += ["", ""] if s is None else [f"{s.first:g}, {s.last:g}", f"{s.per_hour:+.2f}"]
        ok = "yes" if all(s.within for s in ss) else "**no**: " + ", ".join(s.unit for s in ss if not s.within)
        lines.append(f"| {name} | {pid} | " + " | ".join(cells) + f" | {ok} |")
    lines += ["", *_recording(args, outcome), "", *_clients(outcome), ""]
    lines.append(f"Samples: `{workdir / 'samples.jsonl'}` (not kept in the repository).")
    return "\n".join(lines) + "\n"


def _recording(args: argparse.Namespace, outcome: Outcome) -> list[str]:
    samples = [s for s in outcome.samples if not s.get("final")]
    final = outcome.samples[-1]["recording"]
    kept = [s for s in samples if s["t"] >= args.warmup] or samples
    rate = [(s["t"], float(s["recording"]["telegrams"])) for s in kept]
    size = [(s["t"], float(s["recording"]["bytes"])) for s in kept]
    per = [s["recording"]["bytes"] / s["recording"]["telegrams"] for s in kept if s["recording"]["telegrams"]]
    out = [
        f"Recording (session file and pcapng): {final['bytes'] / 1e6:.1f} MB for {final['telegrams']:,} telegrams "
        f"at the end ({final['bytes'] / max(1, final['telegrams']):.0f} bytes a telegram)."
    ]
    if len(rate) >= 2:
        out.append(
            f"After the warm-up: {slopes.least_squares(rate) * 60:.0f} telegrams/minute, "
            f"{slopes.least_squares(size) * 60 / 1e6:.2f} MB/minute; "
            f"bytes a telegram from {per[0]:.0f} to {per[-1]:.0f}."
        )
    check = outcome.recording_check
    out += ["", f"Nothing lost? The recording, read again: {check.summary() if check else 'not checked'}."]
    missing = lost(outcome)
    out.append(
        f"The reconnecting client made {reconnects(outcome)} connections, the patrol 1: "
        + ("all of them are in the recording, nothing lost." if not missing else "**" + "; ".join(missing) + "**.")
    )
    r = outcome.replayed
    if r is not None:
        out += [
            "",
            f"`pltf replay` of the recording against a fresh reference server (benchmarks/soak/replay.py): "
            f"{r.summary()}.",
        ]
        if r.lines:
            out += ["", "```", *r.lines[:SHOWN_LINES], "```"]
    else:
        out += ["", "`pltf replay` not run (`--no-replay`)."]
    return out


def _clients(outcome: Outcome) -> list[str]:
    dead = ", ".join(outcome.dead) if outcome.dead else "none"
    return [
        f"Patrol: {outcome.patrol}. Reconnecting client: {outcome.reconnect or 'no summary'}.",
        f"Parts that ended during the soak: {dead}.",
    ]


def append_atomically(path: Path, text: str) -> None:
    old = path.read_text(encoding="utf-8") if path.exists() else HEADER
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    with os.fdopen(fd, "w", encoding="utf-8") as fh:
        fh.write(old.rstrip("\n") + "\n\n" + text)
    os.replace(tmp, path)


HEADER = """# Soak: the toolkit for an hour

`make soak` (`python -m benchmarks.soak`, benchmarks/soak/): the reference server at time scale 10, `pltf proxy
--record` in front of it, the GUI open in Debian's chromium on the first port, the patrol example on the second
and a client that connects to the second port every few seconds (turned away while the patrol holds it, guide 6.1).
Every minute the RSS, open descriptors and threads of every process (/proc) and the recording's size and
telegram count; at the end the slopes after the warm-up against their bounds and a check that nothing was lost
(every frame decodes again, every reply has its request, every connection the clients made is in the recording)
and `pltf replay` of the recording against a fresh reference server, with its peak RSS and duration. Newest run
last.
"""
