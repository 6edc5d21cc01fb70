"""The conformance suite as a pytest plugin: each case of the catalogue becomes a pytest item.

Use it with ``-p`` (or ``pytest_plugins = ["pltf.conformance_tests.pytest_plugin"]`` in a conftest.py)::

    pytest -p conformance_tests.pytest_plugin --pltf-target HOST:PORT [--pltf-second-port P]
           [--pltf-time-scale X] [--pltf-profile strict|original] [--pltf-tier smoke|standard|exhaustive]
           [--pltf-allow-motion] [--pltf-simulator] [--pltf-allow-shutdown] [-k EXPR]

With ``--pltf-target`` the session runs the conformance cases only (they replace whatever else was collected);
``-k`` selects by case id. Verdicts map to outcomes: PASS and NON-STRICT pass (NON-STRICT cases are listed in the
terminal summary), FAIL fails, INCONCLUSIVE fails for a MUST case, N/A and SKIPPED skip, ERROR errors. Without
``--pltf-target`` the plugin does nothing.
"""

from __future__ import annotations

from typing import Any

import pytest

from pltf.conformance_tests.catalogue import Case, Level, Tier, Verdict, load_all, select
from pltf.conformance_tests.outcome import Unreachable
from pltf.conformance_tests.runner import CaseResult, Runner
from pltf.conformance_tests.target import Config
from pltf.conformance_tests.wire import NullObserver, WireLog

_RUNNER = pytest.StashKey[Runner]()
_RESULTS = pytest.StashKey[list[CaseResult]]()


def pytest_addoption(parser: pytest.Parser) -> None:
    g = parser.getgroup("pltf", "PlatformCtrl conformance suite")
    g.addoption("--pltf-target", metavar="HOST:PORT", help="run the conformance cases against this target")
    g.addoption("--pltf-second-port", type=int, metavar="PORT")
    g.addoption("--pltf-time-scale", type=float, default=1.0, metavar="X")
    g.addoption("--pltf-profile", choices=("strict", "original"), default="strict")
    g.addoption("--pltf-tier", choices=[t.name.lower() for t in Tier], default="standard")
    g.addoption("--pltf-allow-motion", action="store_true")
    g.addoption("--pltf-simulator", action="store_true", help="the target is a simulator (motion cases run)")
    g.addoption("--pltf-allow-shutdown", action="store_true")


def pytest_configure(config: pytest.Config) -> None:
    for level in Level:
        config.addinivalue_line("markers", f"{level.value.lower()}: a conformance case of level {level.value}")


def _config(config: pytest.Config) -> Config | None:
    target = config.getoption("--pltf-target")
    if not target:
        return None
    host, _, port = str(target).rpartition(":")
    return Config(
        host=host,
        port=int(port),
        second_port=config.getoption("--pltf-second-port"),
        time_scale=config.getoption("--pltf-time-scale"),
        profile=config.getoption("--pltf-profile"),
        tier=Tier[config.getoption("--pltf-tier").upper()],
        allow_motion=config.getoption("--pltf-allow-motion"),
        simulator=config.getoption("--pltf-simulator"),
        allow_shutdown=config.getoption("--pltf-allow-shutdown"),
    )


class Catalogue(pytest.Collector):
    def collect(self) -> list[pytest.Item]:
        return []


class CaseItem(pytest.Item):
    def __init__(self, *, case: Case, **kw: Any) -> None:
        super().__init__(**kw)
        self.case = case
        self.add_marker(case.level.value.lower())
        self.result: CaseResult | None = None

    def runtest(self) -> None:
        runner = self.config.stash[_RUNNER]
        last = getattr(runner, "_last_group", None)
        if last != self.case.group:
            runner._last_group = self.case.group  # type: ignore[attr-defined]
            runner.reset(self.case)
        r = self.result = runner.run_case(self.case)
        self.config.stash[_RESULTS].append(r)
        blocking = r.verdict is Verdict.FAIL or (r.verdict is Verdict.INCONCLUSIVE and self.case.level is Level.MUST)
        if r.verdict is Verdict.ERROR:
            raise RuntimeError(r.message)
        if blocking:
            pytest.fail(f"{r.verdict} ({self.case.level}): {r.message}", pytrace=False)
        if r.verdict in (Verdict.NA, Verdict.SKIPPED) or r.verdict is Verdict.INCONCLUSIVE:
            pytest.skip(f"{r.verdict}: {r.message}")

    def repr_failure(self, excinfo: Any, style: Any = None) -> str:
        lines = [str(excinfo.value), f"requirement: {self.case.requirement}"]
        if self.result is not None:
            lines += ["wire log (last 20 entries):"] + [
                f"  {e.t:8.4f} {e.port:>3} {e.direction} {e.note:<28} {e.hex()[:96]}" for e in self.result.wire[-20:]
            ]
        return "\n".join(lines)

    def reportinfo(self) -> tuple[str, int, str]:
        return str(self.path), 0, f"conformance case {self.case.id}"


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(session: pytest.Session, config: pytest.Config, items: list[pytest.Item]) -> None:
    cfg = _config(config)
    if cfg is None:
        return
    parent = Catalogue.from_parent(session, name="pltf-conformance")
    cases = select(load_all().values(), tier=cfg.tier)
    items[:] = [CaseItem.from_parent(parent, name=c.id, case=c) for c in cases]
    config.stash[_RESULTS] = []


def pytest_sessionstart(session: pytest.Session) -> None:
    cfg = _config(session.config)
    if cfg is None:
        return
    runner = Runner(cfg, [])
    try:
        runner.target.connect("A", WireLog(), NullObserver(), probe=False).close()
    except Unreachable as exc:
        pytest.exit(f"pltf conformance: {exc}", returncode=2)
    runner.prepare()  # the target's reply time scales the waits (pace.py)
    session.config.stash[_RUNNER] = runner


def pytest_sessionfinish(session: pytest.Session) -> None:
    runner = session.config.stash.get(_RUNNER, None)
    if runner is not None:
        runner.target.close()


def pytest_terminal_summary(terminalreporter: Any, config: pytest.Config) -> None:
    results = config.stash.get(_RESULTS, [])
    soft = [r for r in results if r.verdict is Verdict.NON_STRICT]
    if soft:
        terminalreporter.section("pltf conformance: NON-STRICT (SHOULD requirements not met)")
        for r in soft:
            terminalreporter.line(f"{r.case.id}: {r.message.splitlines()[0] if r.message else ''}")
