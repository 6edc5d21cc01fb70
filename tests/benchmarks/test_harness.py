"""benchmarks/harness.make_row: the ratio of a row to its baseline, and none where a divisor is 0."""

from __future__ import annotations

from benchmarks.harness import Target, make_row


def test_the_ratio_is_the_time_ratio_to_the_baseline() -> None:
    slower = make_row("b", "new", "p50", 30.0, "ms", higher_is_better=False, baseline_value=20.0)
    faster = make_row("b", "new", "rate", 200.0, "1/s", higher_is_better=True, baseline_value=50.0)
    assert (slower["ratio"], faster["ratio"]) == (1.5, 0.25)


def test_a_figure_of_zero_gives_no_ratio_and_no_crash() -> None:
    # a gui_ab round whose old build's p50 rounded to 0.0 ms ended the benchmark run in ZeroDivisionError
    row = make_row(
        "b", "new", "p50", 0.4, "ms", higher_is_better=False, baseline_value=0.0, target=Target("ratio", "<=", 1.1)
    )
    assert row["ratio"] is None and row["met"] is None
    assert make_row("b", "new", "rate", 0.0, "1/s", higher_is_better=True, baseline_value=5.0)["ratio"] is None
