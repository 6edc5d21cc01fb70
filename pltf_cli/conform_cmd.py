"""``pltf conform``: run the conformance suite against a PlatformCtrl target over TCP (conformance_tests), or
against a fleet of them at once (``--targets FILE``, conformance_tests/fleet.py; ``--ray`` on a Ray cluster).

Exit status: 0 when every selected MUST case passes (and no baseline entry is stale, coverage is not below
``--coverage-threshold``), 1 when a case fails, 2 for a harness error (target unreachable, bad arguments); for a
fleet, the worst of its targets'.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console

from pltf.cli.options import USAGE, CommandError, count, exit_status, port, positive, target
from pltf.conformance_tests.baseline import Baseline, BaselineError
from pltf.conformance_tests.catalogue import Case, Tier, Verdict, load_all, select
from pltf.conformance_tests.outcome import Outcome, Unreachable
from pltf.conformance_tests.pace import run_budget
from pltf.conformance_tests.target import Config

if TYPE_CHECKING:
    from pltf.conformance_tests.reports.differential import Differential
    from pltf.conformance_tests.runner import RunResult


def add_conform_arguments(p: argparse.ArgumentParser) -> None:
    which = p.add_mutually_exclusive_group(required=True)
    which.add_argument("--target", type=target, metavar="HOST:PORT", help="the server to check")
    which.add_argument(
        "--targets",
        metavar="FILE",
        help="a fleet file (YAML: targets, each a name, target HOST:PORT, second_port, profile, time_scale, "
        "target_is_simulator, ...): the suite against every target at once, one report (--junit is then a directory)",
    )
    p.add_argument("--jobs", type=count, metavar="N", help="with --targets: at most N targets at once (default all)")
    p.add_argument(
        "--ray",
        metavar="ADDRESS",
        help="with --targets: run each target's suite as a Ray task on the cluster at ADDRESS (or 'auto'); "
        "needs pip install 'pltf-toolkit[ray]'",
    )
    p.add_argument("--second-port", type=port, metavar="PORT", help="the target's second port (guide 6.1: 10002)")
    p.add_argument(
        "--time-scale",
        type=positive,
        default=1.0,
        metavar="X",
        help="the target's simulated seconds per wall second (default 1: a real platform)",
    )
    p.add_argument(
        "--profile",
        choices=("strict", "original"),
        default="strict",
        help="original: accept the alternative readings the errata register marks 'accept'",
    )
    p.add_argument(
        "--tier",
        choices=[t.name.lower() for t in Tier],
        default="standard",
        help="how many cases: smoke < standard < exhaustive (default standard)",
    )
    p.add_argument("-k", dest="keyword", metavar="EXPR", help="select cases: and/or/not over id substrings or globs")
    p.add_argument("--junit", metavar="FILE", help="write a JUnit XML report (--targets: a directory, NAME.xml each)")
    p.add_argument("--json", metavar="FILE", help="write a JSON report (with wire logs and coverage)")
    p.add_argument("--html", metavar="FILE", help="write a self-contained HTML report (--targets: the matrix)")
    gate = p.add_argument_group("safety gate")
    gate.add_argument(
        "--allow-motion",
        action="store_true",
        help="run the cases that move the platform and switch outputs (real platform: keep clear)",
    )
    gate.add_argument(
        "--target-is-simulator", action="store_true", help="declare the target a simulator: motion and output cases run"
    )
    gate.add_argument("--allow-shutdown", action="store_true", help="end with CMD_EXIT (the target stops)")
    p.add_argument("--baseline", metavar="FILE", help="known failures; a stale entry fails the run")
    p.add_argument("--write-baseline", metavar="FILE", help="write the failures of this run as a baseline")
    p.add_argument(
        "--coverage-threshold",
        type=float,
        metavar="PCT",
        help="exit 1 when an enforced coverage metric is below PCT percent",
    )
    p.add_argument("--reruns", type=count, default=2, metavar="N", help="re-runs of an inconclusive case (default 2)")
    p.add_argument("--reply-timeout", type=positive, default=3.0, metavar="S", help="wall seconds per reply")
    p.add_argument(
        "--budget",
        type=positive,
        metavar="S",
        help="wall seconds for the whole run; the cases left then are INCONCLUSIVE 'not run' (default for "
        "the smoke and standard tiers: 280, or 80 + 600 / time scale when more; exhaustive: none)",
    )
    p.add_argument(
        "--case-budget",
        type=positive,
        metavar="S",
        help="wall seconds one case may take (default 30 + 240 / time scale); a case still running then "
        "is INCONCLUSIVE 'case budget spent'",
    )
    p.add_argument("--list", action="store_true", help="list the selected cases and exit")
    p.add_argument("--verbose", action="store_true", help="print every verdict, not only the non-PASS ones")
    p.add_argument(
        "--differential",
        action="store_true",
        help="also replay a session against a reference server started for it and diff the replies",
    )
    p.add_argument(
        "--stateful",
        type=count,
        default=0,
        metavar="N",
        help="also run N stateful (Hypothesis) examples; a failure is saved as a replay script",
    )
    p.add_argument(
        "--stateful-out",
        default="conform-failures",
        metavar="DIR",
        help="where stateful failures are saved (default conform-failures/)",
    )
    p.epilog = exit_status(
        ok="every selected MUST case passed (--list: listed)",
        failed="a case failed, a baseline entry is stale or coverage is below the threshold",
        usage="usage or connection error: bad arguments, an unreadable baseline, no case "
        "selected, the target unreachable, a harness error",
    )


def run_conform(args: argparse.Namespace) -> int:
    from pltf.conformance_tests.reports.console import ConsoleReporter
    from pltf.conformance_tests.runner import Runner

    if args.targets or args.ray or args.jobs:
        return _run_fleet(args)
    config = _config(args)
    try:
        cases = select(load_all().values(), tier=config.tier, keyword=config.keyword)
        baseline = Baseline.load(args.baseline) if args.baseline else Baseline()
    except (ValueError, BaselineError) as exc:
        raise CommandError(str(exc)) from None
    console = Console(width=None if sys.stdout.isatty() else 140)
    if args.list:
        return _list(cases, console)
    if not cases:
        raise CommandError("no case selected")
    run = Runner(config, cases, [ConsoleReporter(console, verbose=args.verbose)], baseline).run()
    differential = _differential(config, console) if args.differential and run.exit_code != USAGE else None
    _write_reports(args, run, console, differential)
    code = _after_run(args, config, run, console, differential)
    if run.harness_error:
        raise CommandError(f"target unreachable: {run.harness_error}")
    if code == USAGE:
        errors = sum(r.verdict is Verdict.ERROR for r in run.results)
        raise CommandError(f"{errors} case(s) ended in a harness ERROR (see above)")
    return code


def _config(args: argparse.Namespace) -> Config:
    host, number = args.target
    config = Config(
        host=host,
        port=number,
        second_port=args.second_port,
        time_scale=args.time_scale,
        profile=args.profile,
        tier=Tier[args.tier.upper()],
        keyword=args.keyword,
        allow_motion=args.allow_motion,
        simulator=args.target_is_simulator,
        allow_shutdown=args.allow_shutdown,
        reruns=max(0, args.reruns),
        reply_timeout=args.reply_timeout,
        case_budget=args.case_budget,
    )
    if args.budget is not None:
        config.run_budget = args.budget
    elif config.tier is not Tier.EXHAUSTIVE:  # a standard run ends within 5 minutes whatever the target does
        config.run_budget = run_budget(config)
    return config


def _list(cases: list[Case], console: Console) -> int:
    for c in cases:
        flags = " ".join(f for f in ("moves_platform", "switches_outputs", "destructive", "abuse") if getattr(c, f))
        console.print(f"{c.id}  [dim]{c.level} {c.tier.name.lower()} {flags}[/]", highlight=False)
    console.print(f"{len(cases)} cases")
    return 0


def _write_reports(
    args: argparse.Namespace, run: RunResult, console: Console, differential: Differential | None = None
) -> None:
    from pltf.conformance_tests.reports.files import write_json, write_junit
    from pltf.conformance_tests.reports.html import write_html

    for path, write in ((args.junit, write_junit), (args.json, write_json), (args.html, write_html)):
        if path:
            try:
                write(run, path, differential)
            except OSError as exc:
                raise CommandError(f"cannot write {path}: {exc.strerror or exc}") from None
            console.print(f"report written to {path}")
    if args.write_baseline:
        Path(args.write_baseline).write_text(Baseline.render(run.results), encoding="utf-8")


def _after_run(
    args: argparse.Namespace, config: Config, run: RunResult, console: Console, differential: Differential | None
) -> int:
    """The run's exit code, raised by the coverage threshold and the differential and stateful runs."""
    code = run.exit_code
    if code == USAGE:
        return code
    if args.coverage_threshold is not None:
        below = run.target.coverage.below(args.coverage_threshold)
        for m in below:
            console.print(
                f"[bold red]coverage below {args.coverage_threshold:g}%:[/] {m.name} {m.percent:.1f}% "
                f"(missing: {', '.join(m.missing[:5])})"
            )
        code = max(code, 1 if below else 0)
    if differential is not None:
        if differential.unreachable:
            raise CommandError(f"differential run: {differential.error}")
        code = max(code, differential.exit_code)
    if args.stateful:
        code = max(code, _stateful(config, args.stateful, args.stateful_out, console))
    return code


def _differential(config: Config, console: Console) -> Differential:
    """The differential session (its grouped fields go to the console now and into every report)."""
    from pltf.conformance_tests.differential import session
    from pltf.conformance_tests.reports.differential import print_differential

    result = session(config)
    print_differential(result, console)
    return result


def _stateful(config: Config, examples: int, out: str, console: Console) -> int:
    from pltf.conformance_tests.stateful import run_stateful

    return _guarded("stateful run", console, lambda: run_stateful(config, examples, Path(out), console))


def _guarded(what: str, console: Console, run: Callable[[], int]) -> int:
    """A target that closes, stalls or garbles mid-run fails the run (exit 1) with its reason, not a traceback;
    a target that cannot be reached is a usage problem (exit 2)."""
    try:
        return run()
    except Unreachable as exc:
        raise CommandError(f"{what}: target unreachable: {exc}") from None
    except (Outcome, OSError) as exc:
        console.print(f"[bold red]{what} aborted: FAIL[/] {exc}")
        return 1


# ---- a fleet (--targets FILE): conformance_tests/fleet.py, the matrix report in reports/matrix.py
_NOT_FOR_FLEET = {
    "baseline": "--baseline (give each target its own: 'baseline: FILE' in the fleet file)",
    "write_baseline": "--write-baseline",
    "stateful": "--stateful",
}


def _run_fleet(args: argparse.Namespace) -> int:
    from pltf.conformance_tests import fleet
    from pltf.conformance_tests.reports.fleet_console import FleetConsole

    if not args.targets:
        raise CommandError("--ray and --jobs run a fleet: give it with --targets FILE")
    refused = [what for key, what in _NOT_FOR_FLEET.items() if getattr(args, key)]
    if refused:
        raise CommandError(f"not with --targets: {', '.join(refused)}")
    targets = _fleet_targets(args)
    options = fleet.FleetOptions(
        tier=args.tier,
        keyword=args.keyword,
        allow_shutdown=args.allow_shutdown,
        reruns=args.reruns,
        budget=args.budget,
        case_budget=args.case_budget,
        coverage_threshold=args.coverage_threshold,
        differential=args.differential,
    )
    try:
        cases = select(load_all().values(), tier=Tier[args.tier.upper()], keyword=args.keyword)
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    console = Console(width=None if sys.stdout.isatty() else 140)
    if args.list:
        return _list(cases, console)
    if not cases:
        raise CommandError("no case selected")
    view = FleetConsole(console, verbose=args.verbose)
    at_once = min(args.jobs or len(targets), len(targets))
    view.on_start(targets, f"Ray at {args.ray}" if args.ray else f"{at_once} at once, threads")
    runs = _fleet_runs(args, targets, options, view)
    code = fleet.exit_code(runs)
    view.on_finish(runs, code)
    _write_fleet_reports(args, targets, runs, code, console)
    broken = [f"{r.name} ({r.error})" for r in runs if r.exit_code == USAGE]
    if broken:
        raise CommandError(f"{len(broken)} of {len(runs)} target(s) could not be checked: {'; '.join(broken)}")
    return code


def _fleet_targets(args: argparse.Namespace) -> list[Any]:
    from pltf.conformance_tests.fleet import FleetError, load_fleet

    defaults = {
        "profile": args.profile,
        "time_scale": args.time_scale,
        "target_is_simulator": args.target_is_simulator,
        "allow_motion": args.allow_motion,
        "reply_timeout": args.reply_timeout,
    }
    if args.second_port is not None:
        raise CommandError("--second-port belongs to each target of a fleet: 'second_port: PORT' in the fleet file")
    try:
        return load_fleet(args.targets, defaults)
    except FleetError as exc:
        raise CommandError(str(exc)) from None


def _fleet_runs(args: argparse.Namespace, targets: list[Any], options: Any, view: Any) -> list[Any]:
    from pltf.conformance_tests import fleet

    if not args.ray:
        return fleet.run_local(targets, options, view.on_case_end, args.jobs)
    from pltf.conformance_tests.fleet_ray import RayMissing, run_ray

    try:
        return run_ray(targets, options, args.ray, view.on_target_end)
    except RayMissing as exc:
        raise CommandError(str(exc)) from None


def _write_fleet_reports(
    args: argparse.Namespace, targets: list[Any], runs: list[Any], code: int, console: Console
) -> None:
    from pltf.conformance_tests.reports import matrix

    try:
        if args.junit:
            matrix.write_junit_dir(runs, args.junit)
            console.print(f"JUnit reports written to {args.junit}/ (one per target)")
        for path, write in ((args.json, matrix.write_json), (args.html, matrix.write_html)):
            if path:
                write(args.targets, targets, runs, code, path)
                console.print(f"report written to {path}")
    except OSError as exc:
        raise CommandError(f"cannot write a report: {exc}") from None
