"""The soak harness (benchmarks/soak/, `make soak`): its /proc readings, its slopes, its check of the recording,
and (slow tier) a short soak end to end.

The hour itself is `make soak`; its figures go to benchmarks/results/soak.md.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from benchmarks.soak import integrity, procs, slopes
from pltf.spec.codec import REQUESTS, build, encode

ROOT = Path(__file__).resolve().parents[2]
needs_proc = pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux /proc")

HOLD = """
import os, sys, threading, time, subprocess
files = [open(os.devnull) for _ in range(7)]
for _ in range(3):
    threading.Thread(target=time.sleep, args=(60,), daemon=True).start()
child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
print(child.pid, flush=True)
time.sleep(60)
"""


# ---------------------------------------------------------------------------------------------- /proc
@needs_proc
def test_usage_counts_a_process_s_descriptors_and_threads_and_descendants_finds_its_child() -> None:
    with subprocess.Popen([sys.executable, "-c", HOLD], stdout=subprocess.PIPE, text=True) as proc:
        try:
            assert proc.stdout is not None
            child = int(proc.stdout.readline())
            u = procs.usage(proc.pid)
            assert u is not None
            assert u.threads == 4  # the main thread and three sleepers
            assert u.fds >= 3 + 7  # stdin, stdout, stderr and the seven files
            assert u.rss_mb > 1
            assert procs.descendants(proc.pid) == [child]
        finally:
            with contextlib.suppress(NameError, ProcessLookupError):
                os.kill(child, signal.SIGKILL)
            proc.kill()
            proc.wait()
    assert procs.usage(proc.pid) is None  # gone


# ---------------------------------------------------------------------------------------------- slopes
def test_a_slope_is_per_hour_after_the_warm_up_and_judged_against_its_bound() -> None:
    # 100 MB in the warm-up, then 0.5 MB per hour: the warm-up does not count
    series = [(0.0, 0.0), (60.0, 100.0)] + [(600.0 + 60 * k, 100.0 + 0.5 * (600 + 60 * k) / 3600) for k in range(10)]
    s = slopes.slope("rss_mb", series, warmup=600.0)
    assert s is not None
    assert s.per_hour == pytest.approx(0.5)
    assert s.samples == 10 and s.within and s.unit == "MB/hour"
    growing = slopes.slope("fds", [(600.0 + 60 * k, 10.0 + k) for k in range(5)], warmup=600.0)
    assert growing is not None and growing.per_hour == pytest.approx(60.0) and not growing.within
    assert slopes.slope("threads", [(700.0, 1.0), (760.0, 2.0)], warmup=600.0) is None  # too few to judge


def test_least_squares_of_a_known_line() -> None:
    assert slopes.least_squares([(0, 1), (1, 3), (2, 5), (3, 7)]) == pytest.approx(2.0)
    assert slopes.least_squares([(1, 4), (1, 5)]) == 0.0


# ---------------------------------------------------------------------------------------------- the recording
def _line(conn: int, kind: str, **extra: object) -> str:
    return json.dumps({"time": 1.0, "conn": conn, "port": 10002, "kind": kind, **extra})


def _frame(conn: int, direction: str, raw: bytes, name: str) -> str:
    return _line(conn, "frame", direction=direction, hex=raw.hex(), telegram={"telegram": name})


def _session(tmp_path: Path, lines: list[str]) -> Path:
    path = tmp_path / "s.jsonl"
    header = {"format": "pltf-session", "version": 1, "started": 0, "routes": []}
    path.write_text("\n".join([json.dumps(header), *lines]) + "\n")
    return path


GET, STOP = encode(REQUESTS.CMD_GET_POSITION()), encode(REQUESTS.CMD_STOP())
REPLY = encode(build("reply", "CMD_GET_POSITION", x=1, y=2, angle=0.0, vel_trans=0.0, vel_rot=0.0))


def test_a_whole_recording_is_clean_and_a_turned_away_request_is_counted_not_a_problem(tmp_path: Path) -> None:
    lines = [
        _line(1, "open"),
        _frame(1, "request", STOP, "CMD_STOP"),  # not answered: owes nothing
        _frame(1, "request", GET, "CMD_GET_POSITION"),
        _frame(1, "reply", REPLY, "CMD_GET_POSITION"),
        _line(2, "open"),
        _frame(2, "request", GET, "CMD_GET_POSITION"),
        _line(2, "close", detail="by target (reset: Connection reset by peer)"),
        _line(1, "close", detail="by client (FIN)"),
    ]
    check = integrity.check(_session(tmp_path, lines))
    assert check.clean, check.problems
    assert check.frames == 4 and check.connections[10002] == 2 and check.answered_connections[10002] == 1
    assert check.unanswered == {(10002, "by target"): 1}


def test_what_a_lost_line_leaves_behind_is_named(tmp_path: Path) -> None:
    lines = [
        _line(1, "open"),
        _frame(1, "reply", REPLY, "CMD_GET_POSITION"),  # its request is not in the recording
        _frame(1, "request", GET, "CMD_GET_STATUS"),  # named as another telegram than its bytes
        _frame(1, "request", GET[:-1], "CMD_GET_POSITION"),  # bytes cut short
        '{"time": 1.0, "conn": 1, "port": 10002, "kind": "frame", "direction": "request", "hex": "ff0',  # cut off
        _line(3, "close", detail="by client (FIN)"),  # a close without its open
    ]  # and connection 1 never closes
    check = integrity.check(_session(tmp_path, lines))
    text = " | ".join(check.problems)
    assert "with no request owed" in text
    assert "names CMD_GET_STATUS, the bytes are CMD_GET_POSITION" in text
    assert "does not decode again" in text
    assert "line 6:" in text
    assert "connection 1: no close" in text and "connection 3: no open" in text
    assert not check.clean


# ---------------------------------------------------------------------------------------------- end to end
@pytest.mark.slow
@pytest.mark.timeout(900)
def test_a_short_soak_samples_every_process_and_finds_nothing_lost(tmp_path: Path) -> None:
    """Two minutes of the soak, every part real (the reference server at time scale 10, pltf proxy --record, the
    GUI in chromium, the patrol, the reconnecting client): every part sampled, the recording complete."""
    out = tmp_path / "soak.md"
    cmd = [sys.executable, "-m", "benchmarks.soak", "--duration", "120", "--interval", "20", "--warmup", "20"]
    cmd += ["--workdir", str(tmp_path / "work"), "--out", str(out)]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=840, check=False)
    assert done.returncode in (0, 1), done.stderr[-2000:]
    text = out.read_text()
    for name in ("reference server", "pltf proxy", "GUI gateway", "chromium renderer", "patrol", "reconnecting"):
        assert f"| {name}" in text, (name, text)
    assert "all of them are in the recording, nothing lost" in text, text
    assert "problems: none" in text, text
    samples = [json.loads(line) for line in (tmp_path / "work" / "samples.jsonl").read_text().splitlines()]
    assert len(samples) >= 6 and not any(s["dead"] for s in samples)
    assert samples[-1]["recording"]["telegrams"] > samples[0]["recording"]["telegrams"]


# ---------------------------------------------------------------------------------------------- the tracer
LEAKY = """
import os, pathlib, time
kept, end = [], time.monotonic() + 60
while len(list(pathlib.Path(os.environ["SNAPS"]).glob("snap-*"))) < 4 and time.monotonic() < end:
    kept.append(bytearray(50_000))  # the leak
    time.sleep(0.05)
"""  # leaks until the tracer has taken four snapshots, however slow the machine


def test_the_tracer_names_the_line_that_keeps_memory(tmp_path: Path) -> None:
    (tmp_path / "leaky.py").write_text(LEAKY)
    snaps = tmp_path / "snaps"
    env = {**os.environ, "PYTHONPATH": f"{tmp_path}{os.pathsep}{os.environ.get('PYTHONPATH', '')}", "SNAPS": str(snaps)}
    run = [sys.executable, "-m", "benchmarks.soak.trace", "run", "--out", str(snaps), "--every", "0.4"]
    done = subprocess.run([*run, "--", "-m", "leaky"], cwd=ROOT, env=env, timeout=120, check=False)
    assert done.returncode == 0
    assert len(list(snaps.glob("snap-*.tracemalloc"))) >= 4
    compare = [sys.executable, "-m", "benchmarks.soak.trace", "compare", str(snaps), "--top", "3"]
    out = subprocess.run(compare, cwd=ROOT, capture_output=True, text=True, timeout=120, check=True).stdout
    sites = re.findall(r"([+-][\d.]+) kB .*\n((?:      .*\n)+)", out)  # (growth, traceback) of the top three
    grew = [float(kb) for kb, traceback in sites if 'leaky.py", line 5' in traceback]
    assert grew and grew[0] >= 100, out  # at least two turns of the leak between the snapshots compared
    assert "bytearray" in out  # the gc's count by type grew too (bytearray is tracked)
