"""The fuzzer must find each deliberate bug of tests/fuzz/fragile_server.py within a small budget, and the
reproducer it writes must kill (or hang) a fresh instance."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pltf.fuzz.engine import Campaign, Options
from pltf.harness.launch import Launcher

SERVER = Path(__file__).with_name("fragile_server.py")
LAUNCH = f"{sys.executable} {SERVER} --ports {{ports}} --bug {{bug}}"
BUDGET = 30.0  # seconds of fuzzing at most; each bug is found in a few


def campaign(tmp_path: Path, bug: str, **changes: object) -> Campaign:
    opts = Options(
        host="127.0.0.1",
        port=0,
        second_port=0,
        duration=BUDGET,
        seed=1,
        out=tmp_path / "out",
        allow_motion=True,
        launch=LAUNCH.replace("{bug}", bug),
        max_findings=1,
        deadline=0.5,
        minimize_seconds=20,
    )
    for k, v in changes.items():
        setattr(opts, k, v)
    return Campaign(opts)


_FOUND: dict[str, Campaign] = {}


def found(tmp_path_factory: pytest.TempPathFactory, bug: str) -> Campaign:
    """The campaign that found ``bug``, run once per test session."""
    if bug not in _FOUND:
        c = campaign(tmp_path_factory.mktemp(bug), bug)
        t0 = time.monotonic()
        assert c.run() == 1
        assert time.monotonic() - t0 < BUDGET + 60
        _FOUND[bug] = c
    return _FOUND[bug]


def fresh(bug: str) -> Launcher:
    launcher = Launcher(LAUNCH.replace("{bug}", bug), "127.0.0.1", 0, 0)
    launcher.start()
    return launcher


@pytest.mark.parametrize(
    ("bug", "kind", "telegram"),
    [
        ("negative-repeat", "dead", "CMD_MOVE_PATH"),
        ("doctype", "dead", None),
        ("huge-length", "dead", None),
        ("hang-id", "hang", "id 66"),
        # found only if the fuzzer keeps running singles (fuzz.trial); reproduced on a loaded machine only with the
        # campaign's patient waits on the fresh instance (fuzz.findings, issue 17)
        ("stall-id", "stall", "id 77"),
        ("bad-reply", "bad-reply", "CMD_GET_CAMERA"),
    ],
)
def test_fuzzer_finds_the_bug_and_the_reproducer_replays_it(
    tmp_path: Path, bug: str, kind: str, telegram: str | None
) -> None:
    c = campaign(tmp_path, bug)
    t0 = time.monotonic()
    assert c.run() == 1
    assert time.monotonic() - t0 < BUDGET + 60
    [finding] = c.stats.findings
    assert finding["kind"] == kind and finding["confirmed"]
    assert finding["found_after_s"] <= BUDGET  # seen within the budget, not in the units run out after it
    d = Path(finding["dir"])
    desc = json.loads((d / "finding.json").read_text())
    assert desc["minimized"] and desc["frames"] <= 3, desc["telegrams"]
    if telegram is not None:
        assert any(telegram in t for t in desc["telegrams"]), desc["telegrams"]
    assert (d / "exchange.pcapng").read_bytes()[:4] == b"\x0a\x0d\x0d\x0a"
    assert (d / "sequence.hex").read_text().strip()
    target = fresh(bug)
    try:
        port, second = target.ports
        run = subprocess.run(
            [
                sys.executable,
                str(d / "repro.py"),
                "--target",
                f"127.0.0.1:{port}",
                "--second-port",
                str(second),
                "--deadline",
                "0.5",
            ],
            check=False,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert run.returncode == 1, run.stdout + run.stderr
        assert f"reproduced: {kind}" in run.stdout
        if kind == "dead":
            assert target.proc is not None and target.proc.wait(5) == 134  # the fresh instance died
    finally:
        target.cleanup()


def test_reproducer_leaves_a_healthy_server_alive(tmp_path_factory: pytest.TempPathFactory) -> None:
    c = found(tmp_path_factory, "doctype")
    d = Path(c.stats.findings[0]["dir"])
    healthy = fresh("none")
    try:
        port, second = healthy.ports
        run = subprocess.run(
            [sys.executable, str(d / "repro.py"), "--target", f"127.0.0.1:{port}", "--second-port", str(second)],
            check=False,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert run.returncode == 0, run.stdout
        assert healthy.alive()
    finally:
        healthy.cleanup()


def test_no_false_positive_on_a_well_behaved_server(tmp_path: Path) -> None:
    c = campaign(tmp_path, "none", duration=4.0, max_findings=None)
    assert c.run() == 0
    assert not c.stats.findings and not c.stats.unconfirmed
    assert c.stats.cases > 1000
    assert c.stats.batches and c.stats.singles and c.stats.probes
    assert c.plan.index >= 1  # the state plan moved on; the fragile server always reports Ready, mode 0
    assert c.stats.states <= {("ready", 0)}


def test_a_target_that_turns_back_to_back_clients_away_is_not_pipelined(tmp_path: Path) -> None:
    """The fragile server turns a client away while the port's previous one is still being handled, even if
    that one has sent its end-of-stream: pipelined units are turned away (never served: each runs again, no
    finding, counted once), and pipelining stops on both ports."""
    c = campaign(tmp_path, "none", duration=3.0, max_findings=None)
    assert c.run() == 0
    assert not c.stats.findings and not c.stats.unconfirmed
    assert c.stats.not_admitted > 0 and c.stats.turn_aways == 2 and c.stats.turned_away
    assert c.lanes is not None and not any(g.pipelining for g in c.lanes.gates)
    assert c.stats.cases <= c.index  # a unit that ran again is counted once: no more cases than were drawn


def test_turn_aways_that_start_late_stop_pipelining_without_a_false_finding(tmp_path: Path) -> None:
    """With --admit-first the target takes pipelined clients at first and turns them away later: the units it
    turned away run again (not counted twice, no finding), and pipelining stops."""
    launch = LAUNCH.replace("{bug}", "none") + " --admit-first 60"
    c = campaign(tmp_path, "none", duration=4.0, max_findings=None, launch=launch)
    assert c.run() == 0
    assert not c.stats.findings and not c.stats.unconfirmed
    assert c.stats.pipelined > 0 and c.stats.not_admitted > 0
    assert c.stats.turn_aways >= 1 and c.stats.turned_away  # the unit that showed it
    assert c.stats.cases <= c.index


def test_one_lane_runs_every_unit_on_the_target_port_one_at_a_time(tmp_path: Path) -> None:
    """--lanes 1: every unit on --target's port, one at a time (the other port is only asked when one seems stuck)."""
    c = campaign(tmp_path, "none", duration=2.0, max_findings=None, lanes=1, deadline=3.0)
    assert c.run() == 0
    assert not c.stats.findings
    # a unit the loaded machine kept past the deadline once, and that replayed clean, is not the target's doing
    # (a clean-clone run beside a CPU hog, load 10: CMD_MAPPING_START at the 0.5 s deadline)
    load = [u for u in c.stats.unconfirmed if u["kind"] == "stall" and set(u["evidence"]["replays"]) == {"ok"}]
    assert load == c.stats.unconfirmed, c.stats.unconfirmed
    assert c.stats.batches and c.stats.singles and c.stats.probes and c.stats.pipelined == 0
    assert c.stats.cases > 300


def test_without_motion_no_motion_telegram_is_sent(tmp_path: Path) -> None:
    from pltf.fuzz.safety import MOTION

    c = campaign(tmp_path, "none", duration=2.0, max_findings=None, allow_motion=False)
    assert c.run() == 0
    names = set(c.stats.telegrams)
    from pltf.spec.codec import REQUESTS

    assert not names & {REQUESTS.by_id[i].NAME for i in MOTION}
    assert all(s not in ("running", "breaked") for s, _ in c.stats.states)
