"""bench_fuzz's ceiling: the ratio to boofuzz that what a case costs the target allows (figures of 2026-11-26)."""

from __future__ import annotations

import os

import pytest

from benchmarks.bench_fuzz import (
    BOOFUZZ,
    CEILING,
    CPU_PER_CASE,
    DIRECT,
    OURS,
    SHARE,
    TARGET_THREADS,
    TARGETS,
    _ceiling_rows,
    ceiling,
)


def test_one_thread_at_a_third_of_a_millisecond_a_case_allows_under_ten_times_boofuzz() -> None:
    # the reference server: 0.329 ms of its CPU per case of ours, boofuzz served 319.7 cases/s
    assert ceiling(0.329, 1, 319.7, cores=2) == pytest.approx(9.51, abs=0.01)


def test_a_relay_and_a_server_count_as_two_threads_but_never_more_than_the_cores() -> None:
    assert ceiling(0.664, 2, 318.1, cores=2) == pytest.approx(9.47, abs=0.01)
    assert ceiling(0.664, 2, 318.1, cores=1) == pytest.approx(ceiling(0.664, 1, 318.1, cores=2))


def test_the_rows_name_each_target_and_skip_one_without_cpu_figures() -> None:
    rates = {
        (DIRECT, f"{CPU_PER_CASE}, {OURS}"): 0.5,
        (DIRECT, BOOFUZZ): 200.0,
        ("zoo accept-once", BOOFUZZ): 300.0,  # no CPU figure (no /proc): no row
    }
    [row] = _ceiling_rows("fuzz.cases_per_second", rates)
    assert row["subject"] == f"{CEILING} ({DIRECT})"
    assert row["value"] == pytest.approx(1 / 0.0005 / 200.0)


def test_the_share_of_the_ceiling_is_the_measured_ratio_over_it() -> None:
    rates = {
        ("zoo fin-ends-session", f"{CPU_PER_CASE}, {OURS}"): 0.5,  # 2 threads, 2 cores: 4,000 cases/s at most
        ("zoo fin-ends-session", BOOFUZZ): 200.0,  # ceiling 20x
        ("zoo fin-ends-session", OURS): 1000.0,  # measured 5x: a quarter of what the target allows
    }
    ceiling_row, share = _ceiling_rows("fuzz.cases_per_second", rates)
    assert ceiling_row["value"] == pytest.approx(min(2, os.cpu_count() or 1) / 0.0005 / 200.0)
    assert share["subject"] == f"{SHARE} (zoo fin-ends-session)"
    assert share["value"] == pytest.approx(5.0 / ceiling_row["value"])


def test_every_target_says_how_many_threads_serve_it() -> None:
    assert set(TARGET_THREADS) == set(TARGETS)
    assert {"zoo fin-ends-session", "zoo slow-accept"} <= set(TARGETS)  # behaviour matrix rows 1 and 5
