"""A fleet of ten from a file: every platform's port pair passes the standard conformance tier, all ten at once,
with the verdicts a single platform gets (issue 30).

The fleet runs as ``python -m pltf.reference_server --fleet FILE`` (the fake CAN boards on, as ``pltf serve``), the
ten conformance runs in threads of this process at the same time. The default tier runs 14 cases (ports, framing,
the state chart); the slow tier the whole standard tier (minus the two cases that shut the platform down, as
``pltf conform`` without ``--allow-shutdown``).
"""

from __future__ import annotations

import re
import subprocess
import sys
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import yaml

from pltf.conformance_tests.catalogue import Tier, Verdict, load_all, select
from pltf.conformance_tests.mutants.matrix import NOT_ON_REFERENCE
from pltf.conformance_tests.runner import Runner
from pltf.conformance_tests.target import Config
from tests.reference_server.helpers import REPO, wait_for

# tests/conformance_tests/test_reference.py runs one platform at 5; ten at 5 are 50 platform-seconds a wall second,
# more than one loaded core of this machine simulates (the fleet holds its time back and the suite's waits run out
# first, as they do for one platform at 20). At 2, with make test's neighbours and a benchmark beside it (load 28),
# the fleet still answered too late for the suite's wall-clock windows in one run of three (second-client and
# no-header NON-STRICT on most platforms); at 1 the ten cost what one costs at 10
TIME_SCALE = 1.0
FLEET = 10
PLATFORM = re.compile(r"platform (\S+) at 127\.0\.0\.1:(\d+),127\.0\.0\.1:(\d+)")
# the default tier's filter: the ports (both serve, the same platform on both, one client each), two of the
# malformed frames, the state chart's cells of CMD_START: 14 cases
SMALL = "6.1/* or 6.2/framing/no-header or 6.2/framing/bad-header or 6.3/CMD_START/*"


class FleetProcess:
    def __init__(
        self,
        tmp: Path,
        count: int,
        platforms: list[dict[str, object]] | None = None,
        *extra: str,
        time_scale: float = TIME_SCALE,
    ) -> None:
        """``count`` platforms along the corridor 2.5 m apart, or those of ``platforms`` (the file's entries);
        ``extra``: more options of ``pltf serve``."""
        doc = {
            "platforms": platforms
            or [
                {"name": f"p{k:02d}", "ports": [0, 0], "pose": {"x": 2000 + 2500 * k, "y": 10000, "angle": 0}}
                for k in range(count)
            ]
        }
        path = tmp / "fleet.yaml"
        path.write_text(yaml.safe_dump(doc), encoding="utf-8")
        self.log_path = tmp / "fleet.log"
        self.log_file = self.log_path.open("wb")
        cmd = [sys.executable, "-m", "pltf.reference_server", "--fleet", str(path), "--data-dir", str(tmp / "data")]
        cmd += ["--time-scale", f"{time_scale:g}", *extra]
        self.proc = subprocess.Popen(cmd, cwd=REPO, stdout=self.log_file, stderr=subprocess.STDOUT)
        self.count = count
        try:
            self.ports = wait_for(self._ports, timeout=60)
        except BaseException:
            self.stop()
            raise

    def _ports(self) -> dict[str, tuple[int, int]] | None:
        if self.proc.poll() is not None:
            raise AssertionError(f"fleet exited with {self.proc.returncode}:\n{self.log()}")
        found = {name: (int(a), int(b)) for name, a, b in PLATFORM.findall(self.log())}
        return found if len(found) == self.count and "pose in the fleet" in self.log() else None

    def log(self) -> str:
        return self.log_path.read_text(encoding="utf-8", errors="replace")

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.log_file.close()


@pytest.fixture
def fleet(tmp_path: Path) -> Iterator[FleetProcess]:
    srv = FleetProcess(tmp_path, FLEET)
    try:
        yield srv
    finally:
        srv.stop()


def verdicts(ports: tuple[int, int], keyword: str | None) -> dict[str, tuple[Verdict, str]]:
    config = Config("127.0.0.1", ports[0], ports[1], time_scale=TIME_SCALE, simulator=True, reruns=5, keyword=keyword)
    cases = select(load_all().values(), tier=Tier.STANDARD, keyword=keyword)
    result = Runner(config, cases).run()
    return {r.case.id: (r.verdict, r.message) for r in result.results}


def run_all(fleet: FleetProcess, keyword: str | None) -> dict[str, dict[str, tuple[Verdict, str]]]:
    with ThreadPoolExecutor(len(fleet.ports)) as pool:
        futures = {name: pool.submit(verdicts, ports, keyword) for name, ports in fleet.ports.items()}
        return {name: f.result() for name, f in futures.items()}


def judge(runs: dict[str, dict[str, tuple[Verdict, str]]]) -> None:
    ok = (Verdict.PASS,)
    bad = [
        f"{name} {case}: {verdict} {message}"
        for name, results in runs.items()
        for case, (verdict, message) in results.items()
        if verdict not in ok
        and not (verdict is Verdict.NA and case in NOT_ON_REFERENCE)
        and not (verdict is Verdict.SKIPPED and "shutdown" in message.lower())
    ]
    assert not bad, "\n".join(bad)
    cases = {name: set(results) for name, results in runs.items()}
    assert len({frozenset(c) for c in cases.values()}) == 1, "the platforms ran different cases"


def test_ten_platforms_pass_the_port_framing_and_state_cases_at_once(fleet: FleetProcess) -> None:
    runs = run_all(fleet, SMALL)
    judge(runs)
    assert all(len(r) >= 14 for r in runs.values()), {n: len(r) for n, r in runs.items()}


@pytest.mark.slow
@pytest.mark.timeout(3600)  # ten standard tiers at once on two loaded cores: more than 17 minutes at load 20
def test_ten_platforms_pass_the_standard_tier_at_once(fleet: FleetProcess) -> None:
    runs = run_all(fleet, None)
    judge(runs)
    assert all(len(r) >= 180 for r in runs.values())
