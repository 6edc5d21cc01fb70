"""The fleet in one world (issue 30): real-time factor, CPU cost and memory of N platforms stepped together.

Subjects (each N in a fresh child process running ``child(N, SECONDS)``, so its memory is its own):
- "fleet of N": one process, one ``Fleet`` (reference_server/fleet/) as ``pltf serve --fleet N`` builds it, in the
  office fixture scaled to 64 x 40 m (the office itself has free places for 165 platforms), at full fidelity: every
  platform with the world, the seven fake CAN boards on a virtual bus of its own, the S300 on ``sim://`` at 10 Hz,
  the 541-beam laser and the 16 ultrasonic sensors every 0.1 s; each brought up through ``Platform.handle``
  (CONNECT, INIT and its self test, START_ULTRASONIC on all channels, Automatic, START) and then sent back and forth
  with CMD_MOVE_ABS between its free place and another platform's, so the platforms meet, see and block each
  other. Timed: ``Fleet.tick`` for SECONDS of simulated time (what the fleet's control loop does; the sockets are
  idle and not part of it).
- baseline "N processes of one platform": N child processes at once, each the same run with a fleet of 1 (what N
  separate ``pltf serve`` processes compute; no sockets either), for N up to ``BASELINE_MAX``. Their CPU seconds
  are summed; the wall time is that of the slowest on this machine's cores.
- memory: the child's resident set after building and bringing up its platforms; per added platform: (that of N -
  that of 1) / (N - 1); the baseline's is one ``pltf serve`` process's resident set after start-up (what each
  further platform costs when each is a process of its own).
Figures: real-time factor (simulated s per wall s), CPU seconds per platform per simulated second (what sizes a
machine or a cluster), MB per platform.
"""

from __future__ import annotations

import gc
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from benchmarks.harness import Config, Row, Target, benchmark, make_row

SIZES = (1, 10, 50, 100, 250)
QUICK_SIZES = (1, 2)
BASELINE_MAX = 10
DT = 0.02
RTF_TARGETS = {100: 1.0, 250: 0.5}
MB_TARGET = 15.0
HALL = 2.0  # the office fixture scaled by this
ROOT = Path(__file__).resolve().parents[1]


def _rss_mb() -> float:
    with open("/proc/self/statm", encoding="ascii") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6


def _scaled(data: bytes, factor: float) -> bytes:
    """A map or roadmap document with every coordinate and radius times ``factor``."""
    from lxml import etree

    tree = etree.fromstring(data)
    for el in tree.iter():
        for key in ("x", "y", "r"):
            if key in el.attrib:
                el.set(key, f"{float(el.get(key)) * factor:g}")
    return bytes(etree.tostring(tree, xml_declaration=True, encoding="UTF-8"))


def _hall(root: Path, names: list[str]) -> None:
    """Every platform's data dir with the office map and roadmap at twice their size (64 x 40 m): the office's
    free places hold 165 platforms, the hall's several hundred."""
    from pltf.fixtures import DIR
    from pltf.reference_server.storage import Storage

    hall = _scaled((DIR / "maps/office.map").read_bytes(), HALL)
    roads = _scaled((DIR / "roadmaps/office.rm").read_bytes(), HALL)
    for name in names:
        d = root / name
        Storage(d).seed_from_fixtures()
        (d / "Map/PltfMap.map").write_bytes(hall)
        (d / "Roadmap/PltfRoadmap.rm").write_bytes(roads)
        (d / "StartupPosition.dat").write_text("4000 20000 0\n", encoding="ascii")


def _fleet(count: int, root: Path) -> Any:
    import argparse

    from pltf.reference_server.fleet.cli import build_platforms
    from pltf.reference_server.fleet.config import of_count
    from pltf.reference_server.fleet.fleet import Fleet

    spec = of_count(count, [0, 0])
    _hall(root, [p.name for p in spec.platforms])
    args = argparse.Namespace(data_dir=str(root), seed=1, no_hardware=False, can_interface="virtual")
    return Fleet(spec, build_platforms(spec, args))


def _bring_up(fleet: Any, boot: bool = True) -> int:
    """Every platform Running in Automatic with the laser at 10 Hz and the ultrasonic on; the tick reached.
    ``boot``: boot the fleet first (a shard's fleet is booted when it is prepared)."""
    from pltf.reference_server.enums import MotionMode
    from pltf.spec.codec import REQUESTS as R

    if boot:
        fleet.boot(0.0)
    for m in fleet.members:
        for t in (R.CMD_CONNECT_TO_PLTF(), R.CMD_INIT_PLTF(), R.CMD_START_ULTRASONIC(active_channels=0xFFFF)):
            assert m.platform.handle(t, 0.0).refused is None, t
        m.platform.hardware.hw.scanner.period = 0.1
    k = 0
    while any(m.platform.chart.state.name != "READY" for m in fleet.members) and k < 200:
        k += 1
        fleet.tick(k * DT)
    for m in fleet.members:
        for t in (R.CMD_SET_MODE(mode=MotionMode.MODE_MOTION_AUTOMATIC), R.CMD_START()):
            m.platform.handle(t, k * DT)
        assert m.platform.chart.state.name == "RUNNING", (m.name, m.platform.chart.state)
    return k


def _drive(fleet: Any, first: int, seconds: float) -> None:
    """Each platform shuttles between its own place and that of the platform half the fleet away."""
    drive(fleet.members, [m.platform.motion.truth for m in fleet.members], fleet.tick, first, seconds)


def drive(members: Any, homes: list[Any], tick: Any, first: int, seconds: float) -> None:
    """``members`` (each with its global ``index`` into ``homes``, every platform's place) shuttle between their
    own place and that of the platform half the fleet away; ``tick(now)`` steps them."""
    from pltf.spec.codec import REQUESTS as R

    n = len(homes)
    legs = {m.index: 0 for m in members}
    for k in range(first + 1, first + round(seconds / DT) + 1):
        now = k * DT
        for m in members:
            if not m.platform.motion.active:
                i = m.index
                x, y, a = homes[(i + n // 2) % n] if legs[i] % 2 == 0 else homes[i]
                legs[i] += 1
                m.platform.handle(R.CMD_MOVE_ABS(x=round(x), y=round(y), angle=round(math.degrees(a) * 1000)), now)
        tick(now)


def child(count: int, seconds: float) -> dict[str, float]:
    """One run in this process: build, bring up, drive ``seconds``; the figures as a dict."""
    with tempfile.TemporaryDirectory() as tmp:
        gc.collect()
        rss0 = _rss_mb()
        fleet = _fleet(count, Path(tmp))
        first = _bring_up(fleet)
        gc.collect()
        rss1 = _rss_mb()
        gc.freeze()  # as pltf serve --fleet does once it has built its fleet
        cpu, wall = time.process_time(), time.perf_counter()
        _drive(fleet, first, seconds)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        fleet.close()
    return {"count": count, "seconds": seconds, "wall": wall, "cpu": cpu, "rss_before": rss0, "rss_built": rss1}


def _run_child(count: int, seconds: float) -> subprocess.Popen[str]:
    code = f"import json; from benchmarks.bench_fleet import child; print(json.dumps(child({count}, {seconds})))"
    cmd = [sys.executable, "-c", code]
    return subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, text=True)


def _result(proc: subprocess.Popen[str]) -> dict[str, float]:
    out, _ = proc.communicate(timeout=3600)
    if proc.returncode != 0:
        raise RuntimeError(f"fleet benchmark child exited with {proc.returncode}")
    return dict(json.loads(out.strip().splitlines()[-1]))


def fleet_run(count: int, seconds: float) -> dict[str, float]:
    return _result(_run_child(count, seconds))


def separate_runs(count: int, seconds: float) -> dict[str, float]:
    """``count`` one-platform processes at once: summed CPU, the slowest's wall time."""
    t0 = time.perf_counter()
    results = [_result(p) for p in [_run_child(1, seconds) for _ in range(count)]]
    return {
        "wall": time.perf_counter() - t0,
        "cpu": sum(r["cpu"] for r in results),
        "slowest": max(r["wall"] for r in results),
    }


def serve_rss_mb() -> float:
    """The resident set of one ``pltf serve`` (fake hardware on) once it has booted."""
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "log"
        with log.open("wb") as out:
            cmd = [sys.executable, "-m", "pltf.reference_server", "--ports", "0,0", "--data-dir", f"{tmp}/data"]
            proc = subprocess.Popen(cmd, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT)
            try:
                deadline = time.monotonic() + 60
                while "system state" not in log.read_text(errors="replace") and time.monotonic() < deadline:
                    time.sleep(0.1)
                time.sleep(1.0)
                status = Path(f"/proc/{proc.pid}/status").read_text()
                return int(re.search(r"VmRSS:\s+(\d+)", status).group(1)) / 1000  # type: ignore[union-attr]
            finally:
                proc.terminate()
                proc.wait(20)


@benchmark()
def scaling(config: Config) -> list[Row]:
    """Real-time factor, CPU per platform-second and memory per platform for fleets of N, beside N processes."""
    sizes = QUICK_SIZES if config.quick else SIZES
    seconds = 1.0 if config.quick else 5.0
    rows: list[Row] = []
    serve_mb = serve_rss_mb()
    one = 0.0  # the resident set a fleet of one built (the modules and one platform)
    for n in sizes:
        repeats = 1 if config.quick or n > BASELINE_MAX else max(1, min(config.repeats, 3))
        runs = [fleet_run(n, seconds) for _ in range(repeats)]
        wall = statistics.median(r["wall"] for r in runs)
        cpu = statistics.median(r["cpu"] for r in runs)
        built = statistics.median(r["rss_built"] for r in runs)
        one = one or built
        mb = (built - one) / (n - 1) if n > 1 else built  # per added platform; a fleet of one: the whole process
        base = separate_runs(n, seconds) if n <= BASELINE_MAX else None
        name, subject = "fleet.scaling", f"fleet of {n}"
        baseline = f"{n} processes of one platform" if base else None
        target = Target("value", ">=", RTF_TARGETS[n]) if n in RTF_TARGETS else None
        rows.append(
            make_row(
                name,
                subject,
                "realtime_factor",
                seconds / wall,
                "sim-s/s",
                higher_is_better=True,
                baseline_subject=baseline,
                baseline_value=None if base is None else seconds / base["wall"],
                target=target,
            )
        )
        rows.append(
            make_row(
                name,
                subject,
                "cpu_per_platform_second",
                cpu / (n * seconds),
                "cpu-s",
                higher_is_better=False,
                baseline_subject=baseline,
                baseline_value=None if base is None else base["cpu"] / (n * seconds),
            )
        )
        rows.append(
            make_row(
                name,
                subject,
                "mb_per_added_platform" if n > 1 else "mb_process",
                mb,
                "MB",
                higher_is_better=False,
                baseline_subject="one pltf serve process" if n > 1 else None,
                baseline_value=serve_mb if n > 1 else None,
                target=Target("value", "<=", MB_TARGET) if n > 1 else None,
            )
        )
    return rows
