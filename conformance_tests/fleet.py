"""A fleet of targets (``pltf conform --targets FILE``): the suite against every target at once, one report.

Rules:
- A fleet file is YAML: ``targets`` (a list; each a ``name`` and a ``target`` HOST:PORT, and whatever else that
  target needs: ``second_port``, ``profile``, ``time_scale``, ``target_is_simulator``, ``allow_motion``,
  ``reply_timeout``, ``baseline``) and optionally ``defaults`` (the same keys, for every target). The command line
  gives the defaults of the defaults: a target's own key wins over the file's ``defaults``, which win over the
  command line. A key the file does not know, a duplicate name, a bad address: ``FleetError`` naming the entry.
- Each target's run is exactly a single run against it (``run_target``: the same Config, cases, baseline, budget,
  Runner), so its verdicts are those ``pltf conform --target`` would give; only the reports are combined. Its
  result (``TargetRun``) is plain data: the JSON report's dict and the JUnit text, so it crosses a process or a
  Ray node (fleet_ray.py) as it is.
- Locally the runs are threads, one per target (``--jobs`` caps them): a run mostly waits on its target's replies.
- Exit status as a single run's, over the fleet: the worst of the targets' (2 when a target could not be reached).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import yaml

from pltf.cli.options import parse_host_port
from pltf.conformance_tests.baseline import Baseline, BaselineError
from pltf.conformance_tests.catalogue import Tier, Verdict, load_all, select
from pltf.conformance_tests.pace import run_budget
from pltf.conformance_tests.target import Config

NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")  # a report file is named after it


class FleetError(ValueError):
    """The fleet file cannot be used (one line: the file, the entry and what is wrong)."""


@dataclass(frozen=True)
class FleetTarget:
    """One target of the fleet: where it is and what the suite must know about it."""

    name: str
    host: str
    port: int
    second_port: int | None = None
    profile: str = "strict"
    time_scale: float = 1.0
    target_is_simulator: bool = False
    allow_motion: bool = False
    reply_timeout: float = 3.0
    baseline: str | None = None  # the text of its baseline file (read by the driver, which has the file)

    @property
    def address(self) -> str:
        return f"[{self.host}]:{self.port}" if ":" in self.host else f"{self.host}:{self.port}"


@dataclass(frozen=True)
class FleetOptions:
    """What the command line sets for every target's run (plain data: it travels to Ray workers)."""

    tier: str = "standard"
    keyword: str | None = None
    allow_shutdown: bool = False
    reruns: int = 2
    budget: float | None = None
    case_budget: float | None = None
    coverage_threshold: float | None = None
    differential: bool = False


@dataclass
class TargetRun:
    """One target's run as plain data: the JSON report (``pltf conform --json``'s dict, with its differential
    section) and the JUnit text, its exit status and, when it could not be run, why."""

    name: str
    address: str
    exit_code: int
    report: dict[str, Any] = field(default_factory=dict)
    junit: str = ""
    error: str = ""

    def verdicts(self) -> dict[str, str]:
        return {c["id"]: c["verdict"] for c in self.report.get("cases", [])}


# ---- the fleet file
_KEYS = {f.name for f in fields(FleetTarget)}
_TYPES: dict[str, tuple[type, ...]] = {
    "second_port": (int,),
    "profile": (str,),
    "time_scale": (int, float),
    "target_is_simulator": (bool,),
    "allow_motion": (bool,),
    "reply_timeout": (int, float),
    "baseline": (str,),
    "name": (str,),
    "target": (str,),
}
_PROFILES = ("strict", "original")


def load_fleet(path: str | Path, defaults: Mapping[str, Any] | None = None) -> list[FleetTarget]:
    """The targets of a fleet file; ``defaults`` (from the command line) under the file's own."""
    p = Path(path)
    try:
        raw = yaml.safe_load(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise FleetError(f"cannot read the fleet file {p}: {getattr(exc, 'strerror', None) or exc}") from None
    except yaml.YAMLError as exc:
        raise FleetError(f"{p}: not YAML: {' '.join(str(exc).split())}") from None
    if isinstance(raw, list):
        raw = {"targets": raw}
    if not isinstance(raw, dict) or not isinstance(raw.get("targets"), list) or not raw["targets"]:
        raise FleetError(f"{p}: expected 'targets:', a list of targets (name, target HOST:PORT, ...)")
    unknown = set(raw) - {"targets", "defaults"}
    if unknown:
        raise FleetError(f"{p}: unknown top-level key(s) {', '.join(sorted(unknown))} (targets, defaults)")
    base = {**(defaults or {}), **_entry(p, "defaults", raw.get("defaults") or {}, partial=True)}
    targets = [_target(p, i, {**base, **_entry(p, f"target {i + 1}", e)}) for i, e in enumerate(raw["targets"])]
    seen: set[str] = set()
    for t in targets:
        if t.name in seen:
            raise FleetError(f"{p}: two targets are named {t.name!r}")
        seen.add(t.name)
    return targets


def _entry(path: Path, where: str, entry: object, *, partial: bool = False) -> dict[str, Any]:
    if not isinstance(entry, dict):
        raise FleetError(f"{path}: {where}: expected a mapping of keys ({', '.join(sorted(_TYPES))})")
    for key, value in entry.items():
        if key not in _TYPES:
            raise FleetError(f"{path}: {where}: unknown key {key!r} (known: {', '.join(sorted(_TYPES))})")
        if partial and key in ("name", "target"):
            raise FleetError(f"{path}: {where}: {key!r} belongs to each target, not to the defaults")
        ok = isinstance(value, _TYPES[key]) and not (isinstance(value, bool) and bool not in _TYPES[key])
        if not ok:
            raise FleetError(f"{path}: {where}: {key} must be {' or '.join(t.__name__ for t in _TYPES[key])}")
    return dict(entry)


def _target(path: Path, i: int, e: dict[str, Any]) -> FleetTarget:
    where = f"{path}: target {i + 1}" + (f" ({e['name']})" if "name" in e else "")
    for key in ("name", "target"):
        if key not in e:
            raise FleetError(f"{where}: {key!r} is missing")
    if not NAME.match(e["name"]):
        raise FleetError(f"{where}: a name is 1-64 letters, digits, '.', '_' or '-', starting with a letter or digit")
    if e.get("profile", "strict") not in _PROFILES:
        raise FleetError(f"{where}: profile must be strict or original")
    try:
        host, port = parse_host_port(e["target"])
    except ValueError as exc:
        raise FleetError(f"{where}: {exc}") from None
    second = e.get("second_port")
    if second is not None and not 0 < second < 65536:
        raise FleetError(f"{where}: second_port must be 1..65535")
    for key in ("time_scale", "reply_timeout"):
        if key in e and not 0 < e[key] < float("inf"):
            raise FleetError(f"{where}: {key} must be a number > 0")
    baseline = e.get("baseline")
    if baseline is not None:
        file = (path.parent / baseline).resolve()
        try:
            baseline = file.read_text(encoding="utf-8")
            Baseline.parse(baseline, str(file))
        except (OSError, BaselineError) as exc:
            raise FleetError(f"{where}: baseline {file}: {getattr(exc, 'strerror', None) or exc}") from None
    known = {k: v for k, v in e.items() if k in _KEYS and k not in ("target", "baseline")}
    return FleetTarget(host=host, port=port, baseline=baseline, **known)


# ---- one target's run: a single run's Config, cases, budget and exit status
def config_of(target: FleetTarget, options: FleetOptions) -> Config:
    """The Config ``pltf conform --target`` builds from the same arguments (pltf_cli/conform_cmd.py)."""
    config = Config(
        host=target.host,
        port=target.port,
        second_port=target.second_port,
        time_scale=float(target.time_scale),
        profile=target.profile,
        tier=Tier[options.tier.upper()],
        keyword=options.keyword,
        allow_motion=target.allow_motion,
        simulator=target.target_is_simulator,
        allow_shutdown=options.allow_shutdown,
        reruns=max(0, options.reruns),
        reply_timeout=float(target.reply_timeout),
        case_budget=options.case_budget,
    )
    if options.budget is not None:
        config.run_budget = options.budget
    elif config.tier is not Tier.EXHAUSTIVE:
        config.run_budget = run_budget(config)
    return config


Progress = Callable[[str, Any], None]  # (target name, CaseResult) as each case ends


class _Tagged:
    """A Runner reporter that hands each finished case to ``progress`` with the target's name."""

    def __init__(self, name: str, progress: Progress | None) -> None:
        self.name, self.progress = name, progress

    def on_start(self, *args: object) -> None: ...
    def on_case_start(self, *args: object) -> None: ...
    def on_finish(self, *args: object) -> None: ...

    def on_case_end(self, result: Any) -> None:
        if self.progress is not None:
            self.progress(self.name, result)


def run_target(target: FleetTarget, options: FleetOptions, progress: Progress | None = None) -> TargetRun:
    """The suite against one target of the fleet: a single run, its reports as plain data."""
    from pltf.conformance_tests.reports.files import junit_text, run_dict
    from pltf.conformance_tests.runner import Runner

    config = config_of(target, options)
    cases = select(load_all().values(), tier=config.tier, keyword=config.keyword)
    baseline = Baseline.parse(target.baseline, target.name) if target.baseline else Baseline()
    run = Runner(config, cases, [_Tagged(target.name, progress)], baseline).run()
    differential = None
    if options.differential and run.exit_code != 2:
        from pltf.conformance_tests.differential import session

        differential = session(config)
    code = run.exit_code
    if code != 2 and options.coverage_threshold is not None and run.target.coverage.below(options.coverage_threshold):
        code = 1
    if differential is not None:
        code = max(code, differential.exit_code)
    error = run.harness_error or (differential.error if differential is not None and differential.unreachable else "")
    if not error and any(r.verdict is Verdict.ERROR for r in run.results):
        error = "a case ended in a harness ERROR"
    return TargetRun(
        target.name,
        target.address,
        code,
        run_dict(run, differential),
        junit_text(run, differential, title=f"pltf conform {target.name}"),
        error or "",
    )


def failed_run(target: FleetTarget, exc: BaseException) -> TargetRun:
    """A run that raised instead of ending (a harness bug, a lost Ray worker): reported, exit status 2."""
    return TargetRun(target.name, target.address, 2, error=f"the run did not end: {type(exc).__name__}: {exc}")


def run_local(
    targets: Sequence[FleetTarget], options: FleetOptions, progress: Progress | None = None, jobs: int | None = None
) -> list[TargetRun]:
    """Every target's run in a thread of its own (at most ``jobs`` at once), in the fleet file's order."""

    def one(t: FleetTarget) -> TargetRun:
        try:
            return run_target(t, options, progress)
        except Exception as exc:  # one target's harness problem must not lose the others' reports
            return failed_run(t, exc)

    with ThreadPoolExecutor(max_workers=jobs or len(targets), thread_name_prefix="pltf-fleet") as pool:
        return list(pool.map(one, targets))


def exit_code(runs: Sequence[TargetRun]) -> int:
    return max((r.exit_code for r in runs), default=0)


def as_plain(target: FleetTarget) -> dict[str, Any]:
    """A target as the combined JSON report names it (its baseline's text left out)."""
    return {k: v for k, v in asdict(target).items() if k != "baseline"} | {"baseline": target.baseline is not None}
