"""Smoke test of benchmarks/bench_motion.py: complete rows, and the loops it times do what they claim
(no timing asserted: --quick figures mean nothing)."""

from __future__ import annotations

from benchmarks.bench_motion import (
    GRID,
    HARDWARE,
    LOOP_CORNERS,
    OURS_SCAN,
    PYMUNK_SCAN,
    VECTOR_CORNERS,
    VISIBILITY,
    WORLD,
    WORLD_CAN,
    corners,
    planning,
    realtime_factor,
    run_world,
    run_world_can,
    scan,
)
from benchmarks.harness import ROW_KEYS, Config


def test_rows() -> None:
    config = Config.make(quick=True)
    rows = realtime_factor(config) + planning(config) + scan(config) + corners(config)
    assert all(tuple(r) == ROW_KEYS and r["value"] > 0 for r in rows)
    by = {(r["benchmark"], r["subject"], r["metric"]): r for r in rows}
    assert by["motion.realtime_factor", WORLD_CAN, "realtime_factor"]["baseline_subject"] == WORLD
    assert by["motion.planning", VISIBILITY, "p95_query_time"]["baseline_subject"] == GRID
    assert by["motion.scan", OURS_SCAN, "scan_time"]["baseline_subject"] == PYMUNK_SCAN
    assert by["motion.realtime_factor", HARDWARE, "realtime_factor"]["baseline_subject"] == WORLD_CAN
    assert [r["baseline_subject"] for r in rows if r["subject"] == VECTOR_CORNERS] == [LOOP_CORNERS]
    for key in [
        ("motion.realtime_factor", WORLD, "realtime_factor"),
        ("motion.planning", VISIBILITY, "p95_query_time"),
        ("motion.scan", OURS_SCAN, "scan_time"),
    ]:
        assert isinstance(by[key]["met"], bool)


def test_both_loops_drive_the_tour() -> None:
    assert run_world(4.0) > 1000.0  # mm driven
    assert run_world_can(4.0) > 1000.0  # the motor boards move the wheels, their encoders the estimate
