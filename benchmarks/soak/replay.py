"""The soak's last step: ``pltf replay`` of the recording against a fresh reference server (the soak's seed and
time scale), with the replay's peak RSS, its duration and the differences it found.

    python -m benchmarks.soak.replay SESSION [--time-scale 10] [--replay-scale 1]

Rules:
- ``pltf replay`` runs as a process of its own; its peak RSS is the kernel's high-water mark of that process
  (VmHWM in /proc, read every ``POLL`` s until it exits; not wait4's ``ru_maxrss``, which counts the pages of the
  harness it was forked from: 90.8 MB for a replay whose own mark was 56 MB), its duration the wall time from
  its start to its exit.
- ``--replay-scale X`` replays X times as fast and runs the server X times as fast too, so that the platform
  moves as far between two requests as it did when they were recorded.
- Its output goes to a file beside the recording (never a pipe: an hour's differences would fill it).
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.soak.procs import peak_rss_mb
from pltf.harness.launch import LaunchError, python, reference

POLL = 0.2  # s between looks at the replay process
COUNT = re.compile(r"^(\d+) differences? in \d+ telegram")


@dataclass
class Replayed:
    status: int | None  # pltf replay's exit status; None: it did not end in time
    peak_rss_mb: float
    seconds: float
    lines: list[str] = field(default_factory=list)  # what it printed

    @property
    def differences(self) -> int | None:
        """How many differences it reported (0: none; None: it printed no count)."""
        if any(line.endswith(": no difference") for line in self.lines):
            return 0
        found = next((m for line in reversed(self.lines) if (m := COUNT.match(line))), None)
        return int(found.group(1)) if found else None

    def summary(self) -> str:
        status = "did not end in time" if self.status is None else f"exit status {self.status}"
        count = self.differences
        found = "no count printed" if count is None else f"{count} difference{'s' if count != 1 else ''}"
        return f"{status}, {found}, {self.seconds:.0f} s, peak RSS {self.peak_rss_mb:.1f} MB"


def replay(record: Path, time_scale: float, scale: float = 1.0, timeout: float = 86400.0) -> Replayed:
    """Replay ``record`` against a fresh reference server at ``time_scale * scale``, ``scale`` times as fast."""
    out = record.with_suffix(".replay.txt")
    with reference(time_scale=time_scale * scale, seed=1) as server:
        p1, p2 = server.ports
        cmd = python("pltf.cli.main", "replay", str(record), "--target", f"127.0.0.1:{p1}", "--second-port", str(p2))
        cmd += ["--time-scale", f"{scale:g}"]
        with out.open("w", encoding="utf-8") as fh:
            start = time.monotonic()
            proc = subprocess.Popen(cmd, stdout=fh, stderr=subprocess.STDOUT)
            status, peak = _wait(proc, start + timeout)
            seconds = time.monotonic() - start
    lines = out.read_text(encoding="utf-8", errors="replace").splitlines()
    return Replayed(status, peak, seconds, lines)


def _wait(proc: subprocess.Popen[bytes], deadline: float) -> tuple[int | None, float]:
    """Its exit status (None: killed at ``deadline``) and its peak RSS in MB (the last VmHWM read before it ended)."""
    peak = 0.0
    while proc.poll() is None:
        peak = max(peak, peak_rss_mb(proc.pid) or 0.0)
        if time.monotonic() >= deadline:
            proc.kill()
            proc.wait()
            return None, peak
        time.sleep(POLL)
    return proc.returncode, peak


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks.soak.replay", description=__doc__.split("\n\n")[0])
    p.add_argument("session", type=Path, help="a session file written by the soak's pltf proxy --record")
    p.add_argument("--time-scale", type=float, default=10.0, help="the recorded server's time scale (default 10)")
    p.add_argument("--replay-scale", type=float, default=1.0, help="replay X times as fast (its server too)")
    args = p.parse_args(argv)
    if not args.session.is_file():
        print(f"soak replay: error: {args.session}: no such file", file=sys.stderr)
        return 2
    try:
        r = replay(args.session, args.time_scale, args.replay_scale)
    except LaunchError as exc:
        print(f"soak replay: error: {exc}", file=sys.stderr)
        return 2
    size = args.session.stat().st_size / 1e6
    print(f"soak replay of {args.session} ({size:.1f} MB): {r.summary()}")
    print("\n".join(r.lines[-25:]))
    return 0 if r.status == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
