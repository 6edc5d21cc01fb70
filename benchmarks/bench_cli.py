"""Start-up time of the command line and of the client library, beside ``python -c pass``.

Issue 18: ``pltf --help``, ``pltf decode`` and ``pltf encode`` start in <= 0.3 s; ``import pltf.client`` takes
under 100 ms. Every subject is a fresh process (``subprocess.run``) of this interpreter or of the ``pltf`` script
beside it, timed from start to exit, ``config.repeats`` times, interleaved with the others so a noisy spell hits
all of them; the median is reported. The baseline is ``python -c pass``: the interpreter's own start-up (with
this environment's site-packages and its editable-install hooks) that no command can go below.

Bytecode: the processes run with ``PYTHONPYCACHEPREFIX`` set to a fresh folder (and ``PYTHONDONTWRITEBYTECODE``
unset), and one untimed run of each subject writes its ``.pyc`` files there first: as after ``pip install``, which
compiles them. Nothing is written into the checkout.

Rows, per subject: ``wall_seconds`` (the target's metric) and ``cpu_seconds`` (user + system time of the process,
from ``os.wait4``: less sensitive to other processes on a busy machine). ``client.import_only`` is the
difference of the medians of ``import pltf.client`` and ``python -c pass``: the import's own cost.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.harness import Config, Row, Target, benchmark, make_row

FRAME = "ff01fe02000000050f00000003"  # CMD_SET_MODE(mode=3), the README's example
CLI_TARGET_S = 0.3
IMPORT_TARGET_S = 0.1
BASELINE = "python -c pass"
IMPORT = "python -c 'import pltf.client'"


def _pltf() -> list[str]:
    script = Path(sys.executable).with_name("pltf")
    return [str(script)] if script.exists() else [sys.executable, "-m", "pltf.cli.main"]


def subjects() -> dict[str, list[str]]:
    pltf = _pltf()
    return {
        BASELINE: [sys.executable, "-c", "pass"],
        IMPORT: [sys.executable, "-c", "import pltf.client"],
        "pltf --help": [*pltf, "--help"],
        "pltf decode": [*pltf, "decode", FRAME],
        "pltf encode": [*pltf, "encode", "CMD_SET_MODE", '{"mode": 3}'],
    }


def _run(argv: list[str], env: dict[str, str]) -> tuple[float, float]:
    """Wall and CPU seconds of one process, start to exit."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, cwd=tempfile.gettempdir())
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    err = proc.stderr.read() if proc.stderr is not None else b""
    if proc.stderr is not None:
        proc.stderr.close()
    if proc.returncode != 0:
        raise RuntimeError(f"{argv}: exit status {proc.returncode}: {err.decode(errors='replace')[-500:]}")
    return wall, usage.ru_utime + usage.ru_stime


def measure(config: Config) -> dict[str, tuple[float, float]]:
    """Median (wall, cpu) seconds of each subject."""
    cmds = subjects()
    with tempfile.TemporaryDirectory(prefix="pltf-bench-cli-") as cache:
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env["PYTHONPYCACHEPREFIX"] = cache
        for argv in cmds.values():
            _run(argv, env)  # untimed: writes the bytecode
        samples: dict[str, list[tuple[float, float]]] = {name: [] for name in cmds}
        for _ in range(config.repeats):
            for name, argv in cmds.items():
                samples[name].append(_run(argv, env))
    return {
        name: (statistics.median(w for w, _ in runs), statistics.median(c for _, c in runs))
        for name, runs in samples.items()
    }


@benchmark()
def startup(config: Config) -> list[Row]:
    """Start-up of pltf --help/decode/encode (<= 0.3 s) and import pltf.client (< 0.1 s), beside python -c pass."""
    got = measure(config)
    base_wall, base_cpu = got[BASELINE]
    rows = []
    for name, (wall, cpu) in got.items():
        target = Target("value", "<=", CLI_TARGET_S) if name.startswith("pltf ") else None
        baseline = None if name == BASELINE else BASELINE
        rows.append(
            make_row(
                "cli.startup",
                name,
                "wall_seconds",
                wall,
                "s",
                higher_is_better=False,
                baseline_subject=baseline,
                baseline_value=None if baseline is None else base_wall,
                target=target,
            )
        )
        rows.append(
            make_row(
                "cli.startup",
                name,
                "cpu_seconds",
                cpu,
                "s",
                higher_is_better=False,
                baseline_subject=baseline,
                baseline_value=None if baseline is None else base_cpu,
            )
        )
    wall, cpu = got[IMPORT]
    rows.append(
        make_row(
            "cli.startup",
            "import pltf.client, minus python -c pass",
            "wall_seconds",
            wall - base_wall,
            "s",
            higher_is_better=False,
            target=Target("value", "<=", IMPORT_TARGET_S),
        )
    )
    rows.append(
        make_row(
            "cli.startup",
            "import pltf.client, minus python -c pass",
            "cpu_seconds",
            cpu - base_cpu,
            "s",
            higher_is_better=False,
        )
    )
    return rows
