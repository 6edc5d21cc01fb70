"""A fleet run against the same four targets checked one after another (issue 34).

``conform_fleet.four_targets``: the reference server, the Go emulator and the zoo members faithful (in front of a
reference server of its own) and slow-release-rst (in front of an emulator of its own), all at time scale 10,
started fresh for each repeat before the clock. In the same repeat: the standard tier against each alone, one after
another (the sum of the four wall times: what a user does by hand today), and the fleet - the same four runs at
once in threads (``conformance_tests.fleet.run_local``, what ``pltf conform --targets`` runs). The order
alternates between repeats. Rows: the fleet's wall time against the sum (ratio: fleet / sum, lower is better),
each target's single run, and the cases whose fleet verdict is not the single run's (should be 0; timing cases
on a loaded machine may be INCONCLUSIVE in one and PASS in the other). ``--quick`` runs the smoke tier once: its
figures mean nothing.
"""

from __future__ import annotations

import contextlib
import statistics
import time
from collections.abc import Callable

from benchmarks.harness import Config, Row, benchmark, make_row
from pltf.conformance_tests.catalogue import Tier, load_all, select
from pltf.conformance_tests.fleet import FleetOptions, FleetTarget, run_local, run_target
from pltf.harness import launch

TIME_SCALE = 10.0
REPEATS = 3
FLEET, SUM = "fleet of 4 (threads)", "4 single runs, one after another"
TARGETS: dict[str, tuple[Callable[..., launch.Launched], str]] = {
    "reference": (lambda: launch.reference(time_scale=TIME_SCALE, log_level="WARNING"), "strict"),
    "emulator": (lambda: launch.emulator(time_scale=TIME_SCALE), "original"),
    "faithful": (lambda: launch.zoo("faithful", time_scale=TIME_SCALE), "strict"),
    "slow-release-rst": (
        lambda: launch.zoo("slow-release-rst", upstream="emulator", time_scale=TIME_SCALE),
        "original",
    ),
}


def _fleet(started: dict[str, launch.Launched]) -> list[FleetTarget]:
    return [
        FleetTarget(
            name,
            "127.0.0.1",
            t.ports[0],
            t.ports[1],
            profile=TARGETS[name][1],
            time_scale=TIME_SCALE,
            target_is_simulator=True,
        )
        for name, t in started.items()
    ]


def _repeat(options: FleetOptions, fleet_first: bool) -> tuple[float, dict[str, float], int]:
    """(fleet wall s, each single run's wall s, cases whose verdicts differ) against fresh targets."""
    with contextlib.ExitStack() as stack:
        started = {name: stack.enter_context(start()) for name, (start, _) in TARGETS.items()}
        targets = _fleet(started)

        def fleet() -> tuple[float, dict[str, dict[str, str]]]:
            t0 = time.perf_counter()
            runs = run_local(targets, options)
            return time.perf_counter() - t0, {r.name: r.verdicts() for r in runs}

        def singles() -> tuple[dict[str, float], dict[str, dict[str, str]]]:
            times, verdicts = {}, {}
            for t in targets:
                t0 = time.perf_counter()
                verdicts[t.name] = run_target(t, options).verdicts()
                times[t.name] = time.perf_counter() - t0
            return times, verdicts

        if fleet_first:
            (wall, together), (times, alone) = fleet(), singles()
        else:
            (times, alone), (wall, together) = singles(), fleet()
    mismatches = sum(together[n].get(case) != v for n in alone for case, v in alone[n].items())
    return wall, times, mismatches


@benchmark()
def four_targets(config: Config) -> list[Row]:
    """The standard tier against a fleet of 4 at once vs the same 4 one after another (wall s, same run)."""
    if launch.emulator_binary() is None:
        raise RuntimeError(f"the fleet needs the emulator: {launch.why_no_emulator()}")
    tier = Tier.SMOKE if config.quick else Tier.STANDARD
    assert select(load_all().values(), tier=tier)
    options = FleetOptions(tier=tier.name.lower())
    walls, sums, mismatches = [], [], []
    times: dict[str, list[float]] = {n: [] for n in TARGETS}
    for i in range(1 if config.quick else REPEATS):
        wall, single, mismatch = _repeat(options, fleet_first=i % 2 == 1)
        walls.append(wall)
        sums.append(sum(single.values()))
        mismatches.append(mismatch)
        for n, s in single.items():
            times[n].append(s)
    name = "conform_fleet.four_targets"
    rows = [
        make_row(
            name,
            FLEET,
            "wall time",
            statistics.median(walls),
            "s",
            higher_is_better=False,
            baseline_subject=SUM,
            baseline_value=statistics.median(sums),
        ),
        make_row(name, SUM, "wall time", statistics.median(sums), "s", higher_is_better=False),
    ]
    rows += [
        make_row(name, f"single run: {n}", "wall time", statistics.median(t), "s", higher_is_better=False)
        for n, t in times.items()
    ]
    rows.append(
        make_row(
            name,
            FLEET,
            "verdicts unlike the single run (max over repeats)",
            max(mismatches),
            "cases",
            higher_is_better=False,
        )
    )
    return rows
