"""The fuzzer against targets we did not write (tests/fuzz/foreign.py: the reference server behind a proxy that
frees a port only 5-50 ms after its client left, or leaves newcomers in its listen backlog; planted bugs).

- Against a conforming target a campaign finds nothing and exits 0: no finding, and nothing unconfirmed either
  (a newcomer turned away or waiting in a backlog is never a suspicion). Default tier: 10 s; slow tier: 60 s.
- Against a planted bug the finding comes within 60 s of fuzzing, and its repro.py kills (or hangs) a fresh
  instance, through the same proxy.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from pltf.fuzz.engine import Campaign, Options
from pltf.fuzz.launch import Launcher

FOREIGN = Path(__file__).with_name("foreign.py")
REFERENCE = (f"{sys.executable} -m pltf.reference_server --ports {{ports}} --data-dir {{tmpdir}} --seed 1 "
             "--log-level INFO")
EMULATOR = Path(__file__).resolve().parents[2] / "emulator" / "bin" / "emulator"
CONFORMING = {
    "slow-release, turned away with FIN": "--release 5-50 --turn-away fin",
    "slow-release, turned away with RST": "--release 5-50 --turn-away rst",
    "slow-release, connection refused": "--release 5-50 --turn-away refuse",
    "accept-once, newcomers in the backlog": "--accept-once",
}
PLANTED = {
    # bug: (kind, the telegram that kills, frames a fresh target needs before it)
    "move-crash": ("dead", "CMD_MOVE_REL", ("CMD_CONNECT_TO_PLTF", "CMD_INIT_PLTF", "CMD_START")),
    "vel-crash": ("dead", "CMD_MOVE_VEL_WHEEL", ("CMD_INIT_PLTF", "CMD_SET_MODE(mode=3)", "CMD_START")),
    "hang": ("hang", "CMD_SET_PLTF_PARAM", ()),
    "leak": ("dead", "CMD_SET_", ()),  # a document, repeated: the leak piles up
}
BUDGET = 60.0  # s of fuzzing in which a planted bug must be found


def foreign(args: str) -> str:
    return f"{sys.executable} {FOREIGN} --ports {{ports}} {args}"


def campaign(tmp_path: Path, launch: str, duration: float, **changes: object) -> Campaign:
    opts = Options(host="127.0.0.1", port=0, second_port=0, duration=duration, seed=1, out=tmp_path / "out",
                   allow_motion=True, launch=launch, deadline=3.0)  # fmt: skip
    for k, v in changes.items():
        setattr(opts, k, v)
    return Campaign(opts)


def finds_nothing(tmp_path: Path, launch: str, duration: float) -> Campaign:
    c = campaign(tmp_path, launch, duration)
    assert c.run() == 0, c.stats.findings
    assert not c.stats.findings and not c.stats.unconfirmed, c.stats.unconfirmed
    assert c.stats.cases > 300
    return c


@pytest.mark.parametrize("behaviour", list(CONFORMING))
def test_a_short_campaign_against_a_conforming_foreign_target_finds_nothing(tmp_path: Path, behaviour: str) -> None:
    c = finds_nothing(tmp_path, foreign(CONFORMING[behaviour]), 10.0)
    if "slow-release" in behaviour:  # every fresh connection right after our last one is turned away at first
        assert c.stats.not_admitted > 10 and c.stats.dear
        assert c.stats.skipped > 0 and c.stats.batches > 10  # batches on a kept connection
    else:  # pipelined newcomers wait their turn in the backlog and are served
        assert c.stats.pipelined > 100 and not c.stats.dear and c.stats.not_admitted == 0


@pytest.mark.slow
@pytest.mark.timeout(600)
@pytest.mark.parametrize("behaviour", [*CONFORMING, "the reference server itself", "the Go emulator"])
def test_a_minute_against_a_conforming_target_finds_nothing(tmp_path: Path, behaviour: str) -> None:
    if behaviour == "the Go emulator":
        if not EMULATOR.exists():
            pytest.skip("emulator/bin/emulator is not built (make emulator)")
        launch = f"{EMULATOR} --ports {{ports}}"
    elif behaviour == "the reference server itself":
        launch = REFERENCE
    else:
        launch = foreign(CONFORMING[behaviour])
    finds_nothing(tmp_path, launch, 60.0)


def found(tmp_path: Path, bug: str, minimize_seconds: float, minimal: bool = True) -> dict[str, object]:
    c = campaign(tmp_path, foreign(f"--release 5-50 --bug {bug}"), BUDGET, max_findings=1, deadline=2.0,
                 minimize_seconds=minimize_seconds)  # fmt: skip
    assert c.run() == 1
    [finding] = c.stats.findings
    kind, telegram, needs = PLANTED[bug]
    assert finding["kind"] == kind and finding["confirmed"] and finding["reproduced"], finding
    assert float(finding["found_after_s"]) <= BUDGET  # type: ignore[arg-type]
    d = Path(str(finding["dir"]))
    desc = json.loads((d / "finding.json").read_text())
    telegrams = desc["telegrams"]
    assert any(telegram in t for t in (telegrams[-1:] if minimal else telegrams)), telegrams  # the culprit ...
    for name in needs:  # ... behind the state prelude a fresh target needs
        assert any(name in t for t in telegrams), (name, telegrams)
    return desc | {"dir": str(d)}


def kills_a_fresh_instance(bug: str, directory: str, kind: str) -> None:
    target = Launcher(foreign(f"--release 5-50 --bug {bug}"), "127.0.0.1", 0, 0)
    port, second = target.start()
    try:
        run = subprocess.run([sys.executable, str(Path(directory) / "repro.py"), "--target", f"127.0.0.1:{port}",
                              "--second-port", str(second), "--deadline", "2"], check=False, capture_output=True,
                             text=True, timeout=300)  # fmt: skip
        assert run.returncode == 1, run.stdout + run.stderr
        assert f"reproduced: {kind}" in run.stdout
        if kind == "dead":
            assert target.proc is not None and target.proc.wait(10) in (134, 137)  # the fresh instance died
    finally:
        target.cleanup()


@pytest.mark.timeout(600)
def test_a_crash_behind_a_state_is_found_and_its_reproducer_kills_a_fresh_instance(tmp_path: Path) -> None:
    """Initialised, started, then a CMD_MOVE_REL far out: the target dies. One finding (not one per unit after
    the death), reproduced on a fresh instance behind the prelude it needs (minimised as far as 20 s allow; the
    slow tier gives it the time to end with the move)."""
    desc = found(tmp_path, "move-crash", minimize_seconds=20.0, minimal=False)
    kills_a_fresh_instance("move-crash", str(desc["dir"]), "dead")


@pytest.mark.slow
@pytest.mark.timeout(900)
@pytest.mark.parametrize("bug", list(PLANTED))
def test_each_planted_bug_is_found_within_a_minute_and_its_reproducer_works(tmp_path: Path, bug: str) -> None:
    desc = found(tmp_path, bug, minimize_seconds=120.0)
    if bug == "leak":
        assert int(desc["repeat"]) > 1  # one document does not kill it: repeated, they do
    kills_a_fresh_instance(bug, str(desc["dir"]), PLANTED[bug][0])
