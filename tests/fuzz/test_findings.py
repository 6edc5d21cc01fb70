"""findings: how a replay on a fresh instance names a failure, on a machine whose load delays every answer.

The sockets are replaced by a fake ``play_admitted`` that answers as a loaded fresh instance of the fragile
server does: its replies come ``LATE`` seconds after the request, later than the campaign's deadline (0.5 s) but
within the patient deadline of a stall replay (``pltf.fuzz.verdict.patient``). Issue 17: with two pytest workers
(load 3-5) the stall of id 77 was not reproduced at the first replay on a fresh instance."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from pltf.fuzz import findings
from pltf.fuzz.findings import FRESH_TRIES, AtFailure, FindingContext, FindingWriter, prelude_session
from pltf.fuzz.target import LEAD, Outcome, Session, session_reply_ids
from pltf.fuzz.verdict import patient

PORT, SECOND = 4100, 4101
DEADLINE = 0.5
LATE = 0.8  # s a loaded fresh instance takes to answer: over the deadline, within patient(DEADLINE)
STALL = b"\x00\x00\x00\x00\x00\x00\x00\x01\x4d"  # a frame of id 77 (the fragile server's stall-id)


class FakeLauncher:
    def __init__(self, unserved_starts: int = 0) -> None:
        self.starts = 0
        self.unserved_starts = unserved_starts  # the first instances never serve the probe port

    def start(self) -> tuple[int, int]:
        self.starts += 1
        return PORT, SECOND

    def alive(self) -> bool:
        return True


def writer(launcher: FakeLauncher) -> FindingWriter:
    fresh: Any = launcher  # the launcher's start and alive, without processes
    return FindingWriter(FindingContext("127.0.0.1", DEADLINE, launcher=fresh), set())


class SlowTarget:
    """A loaded fresh instance: every reply comes LATE; a session with id 77 stalls (its lead is answered). The
    deadlines asked for are recorded."""

    def __init__(self, launcher: FakeLauncher) -> None:
        self.launcher = launcher
        self.asked: list[float] = []

    def play_admitted(
        self, host: str, port: int, session: Session, deadline_s: float, patience: float, *rest: object
    ) -> tuple[Outcome, bool]:
        self.asked.append(deadline_s)
        if port == SECOND and self.launcher.starts <= self.launcher.unserved_starts:
            return Outcome(timed_out=True), False  # the machine did not let the fresh instance serve in time
        if deadline_s < LATE:
            return Outcome(timed_out=True), False  # nothing back within the deadline
        if STALL in session.frames:
            return Outcome(timed_out=True, replies=[object()], got=41), True  # type: ignore[list-item]
        n = len(session_reply_ids(session)) + session.sync  # every reply owed
        return Outcome(closed=True, replies=[object()] * n, got=41 * n), True  # type: ignore[list-item]


def slow(monkeypatch: pytest.MonkeyPatch, unserved_starts: int = 0) -> SlowTarget:
    target = SlowTarget(FakeLauncher(unserved_starts))
    monkeypatch.setattr(findings, "play_admitted", target.play_admitted)
    monkeypatch.setattr(findings.time, "sleep", lambda s: None)
    return target


def stall_sessions() -> list[Session]:
    return [Session([LEAD, STALL], half_close=True, led=True)]


def test_the_stall_reproduces_on_a_fresh_instance_that_answers_late(monkeypatch: pytest.MonkeyPatch) -> None:
    target = slow(monkeypatch)
    kind, outcomes = writer(target.launcher).reproduce(stall_sessions())
    assert kind == "stall" and outcomes[-1].timed_out
    assert min(target.asked) >= patient(DEADLINE) > LATE > DEADLINE  # every wait the campaign's patient one


def test_a_slow_conforming_instance_is_not_a_stall(monkeypatch: pytest.MonkeyPatch) -> None:
    """The same late answers, no id 77: nothing reproduced (the patience is not a looser stall)."""
    target = slow(monkeypatch)
    sessions = [prelude_session(("ready", 0)), Session([LEAD, LEAD], half_close=True, led=True)]
    assert writer(target.launcher).reproduce(sessions)[0] is None


def test_a_replay_the_machine_left_inconclusive_runs_again_on_another_fresh_instance(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    target = slow(monkeypatch, unserved_starts=FRESH_TRIES - 1)
    assert writer(target.launcher).reproduce(stall_sessions())[0] == "stall"
    assert target.launcher.starts == FRESH_TRIES


def test_an_instance_that_never_serves_the_probe_port_reproduces_nothing(monkeypatch: pytest.MonkeyPatch) -> None:
    target = slow(monkeypatch, unserved_starts=FRESH_TRIES)
    assert writer(target.launcher).reproduce(stall_sessions())[0] is None
    assert target.launcher.starts == FRESH_TRIES


def test_a_writer_without_a_campaign_writes_what_the_failure_says(tmp_path: Path) -> None:
    """No campaign and no launcher: a frozen context and where the campaign stood are all it reads. A failure not
    believed goes under unconfirmed/ with the index, state and time given; the same failure believed is a finding,
    and again a duplicate (None)."""
    writer = FindingWriter(FindingContext("127.0.0.1", DEADLINE, out=tmp_path, seed=7, command="pltf fuzz -x"), set())
    at = AtFailure(index=41, state=("ready", 0), operation_state=2, motion_mode=1, elapsed=12.34, port=PORT)
    doubt = writer.handle("dead", "it died", [], [], False, {"why": "test"}, at)
    assert doubt is not None and not doubt["confirmed"] and doubt["found_after_s"] == 12.3
    assert Path(doubt["dir"]).parent == tmp_path / "unconfirmed"
    described = json.loads((Path(doubt["dir"]) / "finding.json").read_text())
    assert (described["case_index_before"], described["seed"], described["command"]) == (41, 7, "pltf fuzz -x")
    assert described["state"] == {"target": ["ready", 0], "operation_state": 2, "motion_mode": 1}
    assert described["target_profile"] is None and described["target_output_tail"] == []
    found = writer.handle("dead", "it died", [], [], True, {}, at)
    assert found is not None and found["confirmed"] and Path(found["dir"]).parent == tmp_path
    assert writer.handle("dead", "it died", [], [], True, {}, at) is None  # the same signature: a duplicate
    assert not writer.used_launcher
