"""benchmarks/proc_cpu.py reads what a process group spent from /proc, and bench_fuzz's TargetCpu turns two
readings into CPU per case served and the cores kept busy."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from benchmarks.bench_fuzz import TargetCpu
from benchmarks.proc_cpu import group_cpu, pgid_of

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
BURN = "import time\nend = time.process_time() + 0.5\nwhile time.process_time() < end: pass\ntime.sleep(30)"


def test_a_group_of_two_burning_processes_reads_as_their_cpu_and_a_gone_group_as_nothing() -> None:
    # a parent and its child, one process group of their own, each burning 0.5 s of CPU, then sleeping
    code = f"import subprocess, sys\nsubprocess.Popen([sys.executable, '-c', {BURN!r}])\nexec({BURN!r})"
    proc = subprocess.Popen([sys.executable, "-c", code], start_new_session=True)
    try:
        pgid = pgid_of(proc.pid)
        assert pgid == proc.pid
        deadline = time.monotonic() + 20
        while (cpu := group_cpu(pgid) or 0.0) < 1.0 and time.monotonic() < deadline:
            time.sleep(0.1)
        assert 1.0 <= cpu < 2.5, cpu  # both burns, and not the whole machine's
    finally:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    time.sleep(0.2)
    assert not group_cpu(proc.pid)  # the group is gone (its child was reaped by init)


def test_target_cpu_gives_cpu_per_case_and_busy_cores_between_its_readings() -> None:
    cpu = TargetCpu()
    cpu.first, cpu.last = (10.0, 2.0, 100), (12.0, 3.5, 1100)
    assert cpu.figures() == pytest.approx((1.5, 0.75))  # 1.5 s over 1,000 cases, in 2 s
    assert cpu.figures(cases=3000) == pytest.approx((0.5, 0.75))  # the cases counted elsewhere
    assert TargetCpu().figures() is None  # never read: nothing to say
    cpu.last = cpu.first
    assert cpu.figures() is None  # no case served between the readings
