"""Smoke test of benchmarks/bench_hardware.py: the rows are complete and the two loops agree (no timing asserted)."""

from __future__ import annotations

from benchmarks.bench_hardware import (
    BOARDS_OFF,
    BOARDS_ON,
    PLAIN_BUS,
    SIM_BUS,
    can_throughput,
    realtime_factor,
    run_boards_off,
    run_boards_on,
)
from benchmarks.harness import ROW_KEYS, Config


def test_rows() -> None:
    config = Config.make(quick=True)
    rows = can_throughput(config) + realtime_factor(config)
    assert all(tuple(r) == ROW_KEYS and r["value"] > 0 for r in rows)
    subjects = {(r["benchmark"], r["subject"]): r for r in rows}
    assert subjects["hardware.can_throughput", SIM_BUS]["baseline_subject"] == PLAIN_BUS
    assert subjects["hardware.realtime_factor", BOARDS_ON]["baseline_subject"] == BOARDS_OFF
    assert isinstance(subjects["hardware.realtime_factor", BOARDS_ON]["met"], bool)


def test_the_loops_simulate_the_same_time() -> None:
    frames = run_boards_on(1.0)
    assert 300 <= frames <= 360  # about 320 frames per simulated second reach the controller
    assert run_boards_on(1.0, plain_bus=True) == frames
    assert run_boards_off(1.0) == 50
