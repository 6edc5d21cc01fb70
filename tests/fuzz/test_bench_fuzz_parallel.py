"""benchmarks/bench_fuzz_parallel.py: the figures it derives (aggregate rate, scaling efficiency, time to the first
finding, the rows beside their baselines) from summaries shaped as ``pltf fuzz --jobs`` writes them."""

from __future__ import annotations

import math

from benchmarks.bench_fuzz_parallel import BOOFUZZ_N, LOCAL, aggregate, efficiency, first_found, scaling_rows
from pltf.fuzz.parallel_view import CampaignView


def test_the_aggregate_is_the_sum_of_the_workers_own_rates() -> None:
    view = CampaignView([1, 2], 5, started=0.0)
    for k, rate in enumerate((1200.0, 800.0)):
        view.take({"kind": "figures", "worker": k, "figures": {"cases": 10, "cases_per_second": rate}}, now=5.0)
    assert aggregate(view.summary()) == 2000.0
    assert efficiency(2000.0, 2, 1250.0) == 0.8
    assert efficiency(10.0, 2, 0.0) == 0.0


def test_the_first_finding_is_the_earliest_of_any_worker() -> None:
    assert first_found({"findings": [{"found_after_s": 7.5}, {"found_after_s": 3.25}]}) == 3.25
    assert first_found({"findings": []}) is None


def test_each_rate_is_set_beside_boofuzz_with_as_many_processes() -> None:
    rows = scaling_rows({(LOCAL, 1): 3000.0, (LOCAL, 2): 4500.0, (BOOFUZZ_N, 1): 600.0, (BOOFUZZ_N, 2): 900.0})
    by = {(r["subject"], r["metric"]): r for r in rows}
    assert by[f"{LOCAL} 2", "cases_per_second"]["baseline_value"] == 900.0
    assert math.isclose(by[f"{LOCAL} 2", "cases_per_second"]["ratio"], 0.2)  # a time ratio: 900 / 4500
    assert by[f"{LOCAL} 2", "scaling_efficiency"]["value"] == 0.75
    assert by[f"{BOOFUZZ_N} 2", "scaling_efficiency"]["value"] == 0.75
    assert by[f"{BOOFUZZ_N} 1", "cases_per_second"]["baseline_value"] is None
