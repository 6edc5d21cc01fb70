"""How long the conformance suite's standard tier takes (the figure the old timed test asserted).

``conform.standard_tier``: the standard tier at time scale 10 (``pltf conform --allow-motion``'s case set, as
tests/conformance_tests/test_reference.py runs it) against the reference server, beside the same tier against
the Go emulator (the second implementation, issue 17) in the same run, repeat by repeat. Target (issue 23's
table, the README's "Time scale"): at most 60 s against the reference server. ``--quick`` runs the smoke tier
once: its figures mean nothing.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable

from benchmarks.harness import Config, Row, Target, benchmark, make_row
from pltf.conformance_tests.catalogue import Tier, load_all, select
from pltf.conformance_tests.runner import Runner
from pltf.conformance_tests.target import Config as SuiteConfig
from pltf.harness import launch

TIME_SCALE = 10.0
TARGET_S = 60.0
REFERENCE, EMULATOR = "reference server", "Go emulator"
REPEATS = 3


def _run(start: Callable[..., launch.Launched], tier: Tier, profile: str) -> float:
    """Seconds of one run of ``tier`` (the target started before the clock, stopped after it)."""
    with start(time_scale=TIME_SCALE) as target:
        config = SuiteConfig(
            "127.0.0.1",
            target.ports[0],
            target.ports[1],
            time_scale=TIME_SCALE,
            simulator=True,
            allow_shutdown=True,
            profile=profile,
        )
        cases = select(load_all().values(), tier=tier)
        t0 = time.perf_counter()
        Runner(config, cases).run()
        return time.perf_counter() - t0


@benchmark()
def standard_tier(config: Config) -> list[Row]:
    """The standard tier at time scale 10: the reference server beside the Go emulator (s per run)."""
    tier = Tier.SMOKE if config.quick else Tier.STANDARD
    subjects = {REFERENCE: (launch.reference, "strict"), EMULATOR: (launch.emulator, "original")}
    if launch.emulator_binary() is None:
        raise RuntimeError(f"the baseline needs the emulator: {launch.why_no_emulator()}")
    times: dict[str, list[float]] = {s: [] for s in subjects}
    for _ in range(1 if config.quick else REPEATS):
        for subject, (start, profile) in subjects.items():
            times[subject].append(_run(start, tier, profile))
    median = {s: statistics.median(t) for s, t in times.items()}
    return [
        make_row(
            "conform.standard_tier",
            REFERENCE,
            "duration",
            median[REFERENCE],
            "s",
            higher_is_better=False,
            baseline_subject=EMULATOR,
            baseline_value=median[EMULATOR],
            target=Target("value", "<=", TARGET_S),
        ),
        make_row("conform.standard_tier", EMULATOR, "duration", median[EMULATOR], "s", higher_is_better=False),
    ]
