"""proxy/replay.py: the plan (pairing, waits, timing, the order of connections) and the judgement, sans-IO; then
``pltf replay`` for real: client scenarios recorded through the proxy against the reference server replay
against a fresh one with no difference, and against a mutant of the conformance suite with the differences
named."""

from __future__ import annotations

import contextlib
import io
import time
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from pltf.cli.main import main as pltf
from pltf.conformance_tests.readings import canonical
from pltf.harness import launch
from pltf.proxy.capture import PcapngWriter
from pltf.proxy.recorder import Recorder
from pltf.proxy.replay import Outcome, Script, final_matches, judge, plan
from pltf.proxy.session import Route, Session, SessionWriter, read_session
from pltf.proxy.tap import CLOSE, OPEN, Record, Tap
from pltf.spec.codec import build, encode
from tests.proxy.helpers import ProxyThread
from tests.proxy.scenarios import all_scenarios
from tests.proxy.tshark import run_tshark, telegrams

TIME_SCALE = 10.0
STATUS: Any = canonical("CMD_GET_STATUS", {})


def rec(t: float, conn: int, direction: str, name: str, port: int = 10000, **fields: Any) -> Record:
    telegram = STATUS if name == "STATUS" else build(direction, name, **fields)  # type: ignore[arg-type]
    (r,) = Tap(direction, conn, port).feed(encode(telegram), t)  # type: ignore[arg-type]
    return r


def event(t: float, conn: int, kind: str, detail: str = "", port: int = 10000) -> Record:
    return Record(t, conn, port, kind, detail=detail)


def ipo_trans_vel(t: float = 2.0, conn: int = 1) -> tuple[Record, Record]:
    """CMD_GET_PLTF_PARAM IpoTransVel at ``t`` and its recorded reply 0.1 s later."""
    reply = {"value": "800", "category": 2, "data_type": 1, "minimum": 50, "maximum": 1500}
    return (
        rec(t, conn, "request", "CMD_GET_PLTF_PARAM", key="IpoTransVel"),
        rec(t + 0.1, conn, "reply", "CMD_GET_PLTF_PARAM", key="IpoTransVel", **reply),
    )


def session(*records: Record) -> Session:
    return Session(0.0, (Route("l:1", "h:10000"), Route("l:2", "h:10002")), records)


# ---------------------------------------------------------------------------------------------- the plan


def test_replies_pair_with_requests_by_identifier_and_timing_is_relative() -> None:
    s = session(
        event(1.0, 1, OPEN),
        rec(1.0, 1, "request", "CMD_GET_POSITION"),
        rec(1.0, 1, "request", "CMD_SET_MODE", mode=4),
        rec(1.1, 1, "request", "CMD_GET_STATUS"),
        rec(1.3, 1, "reply", "STATUS"),  # answers out of order: by identifier
        rec(1.4, 1, "reply", "CMD_GET_POSITION", x=1, y=2, angle=0.0, vel_trans=0.0, vel_rot=0.0),
        rec(1.5, 1, "reply", "CMD_GET_CAMERA", ip="x", camera_id="y"),  # nobody asked
        rec(2.0, 1, "request", "CMD_STOP"),
        event(2.5, 1, CLOSE, "by target (FIN)"),
    )
    (script,) = plan(s)
    names = [st.request.name for st in script.steps]
    assert names == ["CMD_GET_POSITION", "CMD_SET_MODE", "CMD_GET_STATUS", "CMD_STOP"]
    assert [st.reply.name if st.reply else None for st in script.steps] == [
        "CMD_GET_POSITION",
        None,
        "CMD_GET_STATUS",
        None,
    ]
    assert [st.answered for st in script.steps] == [True, False, True, False]
    assert [st.after_replies for st in script.steps] == [0, 0, 0, 3]
    assert script.steps[3].gap == pytest.approx(0.5)  # after the last reply, not after the previous request
    assert [u.name for u in script.unsolicited] == ["CMD_GET_CAMERA"]
    assert script.closed_by == "target" and script.close_gap == pytest.approx(0.5) and script.waits == {}


def test_a_run_of_the_same_request_is_a_wait() -> None:
    records = [event(0.0, 1, OPEN)]
    for k in range(4):
        records += [rec(1 + k * 0.1, 1, "request", "CMD_GET_STATUS"), rec(1.05 + k * 0.1, 1, "reply", "STATUS")]
    records += [
        rec(2.0, 1, "request", "CMD_GET_STATUS"),
        rec(2.1, 1, "request", "CMD_STOP"),
        rec(2.2, 1, "request", "CMD_GET_STATUS"),
        rec(2.3, 1, "reply", "STATUS"),
    ]
    (script,) = plan(session(*records))
    (wait,) = script.waits.values()
    assert wait.steps == [0, 1, 2, 3, 4] and wait.interval == pytest.approx(0.1) and wait.final == 4
    assert script.steps[5].wait is None and script.steps[6].wait is None


def test_a_connection_waits_for_the_ones_closed_before_it_opened() -> None:
    s = session(
        event(0.0, 1, OPEN),
        event(1.0, 1, CLOSE, "by client (FIN)"),
        event(1.2, 2, OPEN, port=10002),
        event(1.5, 3, OPEN),
        event(3.0, 2, CLOSE, "by client (FIN)", 10002),
        event(3.0, 3, CLOSE, "by client (FIN)"),
    )
    scripts = {sc.conn: sc for sc in plan(s)}
    assert scripts[3].after_closes == [1] and scripts[2].after_closes == [1] and scripts[2].route == 1


def test_on_one_port_a_connection_served_after_another_waits_for_it_though_the_close_was_stamped_late() -> None:
    # recorded in a clean-clone run (2026-11-26): the client closed #2 and opened #3 on the same port at once; the
    # proxy stamped #3's open 1.06 ms before #2's close; the target closed #3 (a malformed frame) after #2's close
    s = session(
        event(0.0, 1, OPEN),
        event(0.3, 1, CLOSE, "by client (FIN)"),
        event(0.300500, 2, OPEN, port=10002),
        event(0.329654, 3, OPEN, port=10002),
        event(0.330716, 2, CLOSE, "by client (FIN)", 10002),
        event(0.330832, 3, CLOSE, "by target (FIN)", 10002),
    )
    scripts = {sc.conn: sc for sc in plan(s)}
    assert scripts[3].after_closes == [1, 2] and scripts[2].after_closes == [1]


def test_a_newcomer_turned_away_while_the_port_was_taken_does_not_wait_for_it() -> None:
    s = session(
        event(0.0, 1, OPEN),
        event(0.5, 2, OPEN),
        event(0.6, 2, CLOSE, "by target (FIN)"),  # turned away unanswered: one client per port
        rec(1.0, 1, "request", "CMD_STOP"),  # while the first client goes on
        event(2.0, 1, CLOSE, "by client (FIN)"),
        event(2.5, 3, OPEN, port=10002),  # the other port, while #1 was there: both drive one platform
        event(2.8, 3, CLOSE, "by client (FIN)", 10002),
    )
    scripts = {sc.conn: sc for sc in plan(s)}
    assert scripts[2].after_closes == [] and scripts[3].after_closes == [1, 2]


# ---------------------------------------------------------------------------------------------- the judgement


def test_the_judgement_names_each_difference() -> None:
    s = session(
        event(0.0, 1, OPEN),
        rec(0.5, 1, "request", "CMD_STOP"),  # it drives: its replies are compared field by field
        rec(1.0, 1, "request", "CMD_GET_STATUS"),
        rec(1.1, 1, "reply", "STATUS"),
        *ipo_trans_vel(),
        rec(3.0, 1, "request", "CMD_GET_CAMERA"),
        event(4.0, 1, CLOSE, "by target (FIN)"),
    )
    (script,) = plan(s)
    assert not script.reads_only
    same = Outcome(
        1,
        replies={
            1: script.steps[1].reply,
            2: script.steps[2].reply,
            3: rec(3.1, 1, "reply", "CMD_GET_CAMERA", ip="a", camera_id="b"),
        },
        sent=4,
        closed_by_target_after=4,
    )  # type: ignore[dict-item]
    assert [d.path for d in judge([script], {1: same})] == ["(reply)"]  # the camera was never answered on record
    other = Outcome(1, replies={1: _with(rec(1.1, 1, "reply", "STATUS"), STATUS.replace(motion_mode=3))}, sent=4)
    diffs = judge([script], {1: other})
    assert [(d.telegram, d.path, d.recorded, d.replayed) for d in diffs] == [
        ("CMD_GET_STATUS", "motion_mode", f"{_mode(STATUS.motion_mode)}", "MODE_MOTION_VEL (3)"),
        ("CMD_GET_PLTF_PARAM", "(reply)", "CMD_GET_PLTF_PARAM", "no reply"),
        ("(connection)", "end", "closed by the target", "kept open by the target"),
    ]
    cut = judge([script], {1: Outcome(1, replies=same.replies, sent=2, closed_by_target_after=2)})
    assert any(d.path == "requests" and "before CMD_GET_PLTF_PARAM key='IpoTransVel'" in d.replayed for d in cut)


def _with(r: Record, telegram: Any) -> Record:
    return Record(**{**r.__dict__, "telegram": telegram})


def _mode(value: int) -> str:
    from pltf.spec.model import enum_classes

    return f"{enum_classes()['MotionMode'](value).name} ({value})"


# ---------------------------------------------------------------------------------------------- for real


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The client scenarios through the proxy (in a thread) against the reference server: session + pcapng."""
    out = tmp_path_factory.mktemp("recorded")
    with launch.reference(time_scale=TIME_SCALE) as server:
        writer = SessionWriter(out / "session.jsonl")
        recorder = Recorder([], PcapngWriter(out / "session.pcapng"), writer)
        with ProxyThread(server.ports, recorder) as proxy:
            writer.start(
                [Route(f"127.0.0.1:{p}", f"127.0.0.1:{q}") for p, q in zip(proxy.ports, server.ports, strict=True)],
                time.time(),
            )
            all_scenarios(proxy.ports)
    yield out / "session.jsonl"


def _replay(path: Path, ports: list[int], *extra: str) -> tuple[int, str]:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = pltf(
            [
                "replay",
                str(path),
                "--target",
                f"127.0.0.1:{ports[0]}",
                "--second-port",
                str(ports[1]),
                "--reply-timeout",
                "10",
                *extra,
            ]
        )
    return code, out.getvalue()


def test_the_recording_holds_every_exchange(recorded: Path) -> None:
    s = read_session(recorded)
    names = [r.name for r in s.records]
    assert names.count("open") == names.count("close") == 3
    assert {"CMD_MOVE_REL", "CMD_GET_PLTF_PARAM_VEC", "CMD_SET_PLTF_PARAM", "CMD_GET_MAP"} <= set(names)
    assert [r.error.split(":")[0] for r in s.records if r.error] == ["BadHeader"]
    (bad,) = [r.conn for r in s.records if r.error]
    (close,) = [r for r in s.records if r.kind == "close" and r.conn == bad]
    assert close.detail.startswith("by target")  # the bad header closed it


def test_the_pcapng_opens_in_tshark_with_the_dissector(recorded: Path) -> None:
    s = read_session(recorded)
    shown = telegrams(
        run_tshark(
            recorded.with_suffix(".pcapng"), "-d", f"tcp.port=={s.ports[0]},pltf", "-d", f"tcp.port=={s.ports[1]},pltf"
        )
    )
    in_session = [r for r in s.records if r.kind in ("frame", "raw")]
    assert len(shown) == len(in_session)
    for sh, r in zip(shown, in_session, strict=True):
        assert (r.name in sh.label) if r.telegram is not None else ("[BadHeader]" in sh.label), (sh.label, r.name)


def test_the_session_replays_against_the_reference_server_with_no_difference(recorded: Path, tmp_path: Path) -> None:
    with launch.reference(time_scale=TIME_SCALE) as server:
        code, out = _replay(recorded, server.ports, "--junit", str(tmp_path / "replay.xml"))
    assert code == 0, out
    assert out.endswith(": no difference\n") and " 0 of " not in out
    root = ET.parse(tmp_path / "replay.xml").getroot()
    assert root.get("failures") == "0" and len(root.findall(".//testcase")) >= 6


def test_against_a_mutant_the_differences_are_named(recorded: Path, tmp_path: Path) -> None:
    with launch.reference(time_scale=TIME_SCALE, mutant="set_mode_anywhere") as server:  # CMD_SET_MODE in Running
        code, out = _replay(recorded, server.ports, "--time-scale", "2", "--junit", str(tmp_path / "replay.xml"))
    assert code == 1, out
    assert "CMD_GET_STATUS: " in out
    assert "motion_mode: recorded MODE_MOTION_AUTOMATIC (4), replayed MODE_MOTION_VEL (3)" in out
    failed = [
        c.get("name")
        for c in ET.parse(tmp_path / "replay.xml").getroot().iter("testcase")
        if c.find("failure") is not None
    ]
    assert failed == ["CMD_GET_STATUS"], out


def test_replay_errors_are_one_line(tmp_path: Path, recorded: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.jsonl"
    bad.write_text("not a session\n")
    assert pltf(["replay", str(bad), "--target", "127.0.0.1:1"]) == 2
    assert pltf(["replay", str(recorded), "--target", "127.0.0.1:1"]) == 2  # two ports, --second-port missing
    assert pltf(["replay", str(recorded), "--target", "127.0.0.1:1", "--second-port", "2"]) == 2  # nothing there
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 3 and all(line.startswith("pltf replay: error: ") for line in err), err
    assert "--second-port" in err[1] and "cannot connect" in err[2]


# ---------------------------------------------------------------------------------------------- a watcher


def _watcher(*extra: Record) -> Script:
    """A connection that only reads: GET_STATUS, GET_POSITION, GET_STATUS polled, and a parameter."""
    position = {"x": 2000, "y": 10000, "angle": 0.0, "vel_trans": 0.0, "vel_rot": 0.0}
    (script,) = plan(
        session(
            event(0.0, 1, OPEN),
            rec(1.0, 1, "request", "CMD_GET_STATUS"),
            rec(1.1, 1, "reply", "STATUS"),
            rec(1.2, 1, "request", "CMD_GET_STATUS"),
            rec(1.3, 1, "reply", "STATUS"),
            rec(1.4, 1, "request", "CMD_GET_POSITION"),
            rec(1.5, 1, "reply", "CMD_GET_POSITION", **position),
            *ipo_trans_vel(),
            *extra,
            event(4.0, 1, CLOSE, "by client (FIN)"),
        )
    )
    return script


def _outcome(script: Script, **replaced: Any) -> Outcome:
    """The recorded replies as the replay's, with ``replaced`` (step index -> telegram, or None: no reply)."""
    replies = {i: st.reply for i, st in enumerate(script.steps) if st.reply is not None}
    for i, t in replaced.items():
        if t is None:
            del replies[int(i[1:])]
        else:
            replies[int(i[1:])] = _with(script.steps[int(i[1:])].reply, t)  # type: ignore[arg-type]
    return Outcome(script.conn, replies=replies, sent=len(script.steps))  # type: ignore[arg-type]


def test_a_watcher_is_judged_by_what_a_replay_can_reproduce_and_still_by_every_real_difference() -> None:
    script = _watcher()
    assert script.reads_only and script.waits == {}  # no wait: every poll is sent and judged
    moved = STATUS.replace(est_x=7017, est_y=5000, cmd_x=7000, vel_trans=400, motion_mode=4, operation_state=2)
    pos = script.steps[2].reply
    assert pos is not None and pos.telegram is not None
    elsewhere = pos.telegram.replace(x=9000, y=1000, angle=1.5)
    assert judge([script], {1: _outcome(script, s0=moved, s1=moved, s2=elsewhere)}) == []  # where and when it asked
    faulty = judge([script], {1: _outcome(script, s1=STATUS.replace(app_error=2, emergency_state=1))})
    assert sorted(d.path for d in faulty) == ["app_error", "emergency_state"]  # a fault is a fault, whenever it asked
    param = script.steps[3].reply
    assert param is not None and param.telegram is not None
    changed = judge([script], {1: _outcome(script, s3=param.telegram.replace(value="500"))})
    assert [(d.path, d.recorded, d.replayed) for d in changed] == [("value", "'800'", "'500'")]  # not motion
    missing = judge([script], {1: _outcome(script, s1=None)})
    assert [(d.telegram, d.path, d.replayed) for d in missing] == [("CMD_GET_STATUS", "(reply)", "no reply")]
    wrong = judge([script], {1: _outcome(script, s2=STATUS)})  # GET_STATUS's reply where GET_POSITION's was
    assert [(d.path, d.recorded, d.replayed) for d in wrong] == [("(telegram)", "CMD_GET_POSITION", "CMD_GET_STATUS")]


def test_a_connection_that_sends_one_command_is_a_driver_judged_field_by_field() -> None:
    script = _watcher(rec(3.0, 1, "request", "CMD_STOP"))
    assert not script.reads_only and len(script.waits) == 1  # the two GET_STATUS are a wait again
    moved = STATUS.replace(est_x=7017)
    outcome = _outcome(script)
    final = script.steps[1].reply
    assert final is not None
    outcome.wait_final = {0: _with(final, moved)}  # the wait ended on a reply with the platform elsewhere
    diffs = judge([script], {1: outcome})
    assert [(d.path, d.replayed) for d in diffs] == [("est_x", "7017")]


# ---------------------------------------------------------------------------------------------- where a recording ends


def test_what_the_recording_s_end_cut_is_not_held_against_the_target_and_the_rest_still_is() -> None:
    pos = {"x": 2000, "y": 10000, "angle": 0.0, "vel_trans": 0.0, "vel_rot": 0.0}
    s = session(
        event(0.0, 1, OPEN, port=10002),
        rec(0.1, 1, "request", "CMD_SET_MODE", port=10002, mode=4),  # a driver
        rec(0.2, 1, "request", "CMD_GET_STATUS", port=10002),
        rec(0.3, 1, "reply", "STATUS", port=10002),
        rec(0.4, 1, "request", "CMD_GET_STATUS", port=10002),
        rec(0.5, 1, "reply", "STATUS", port=10002),  # the platform still turning: see below
        event(0.6, 2, OPEN, port=10002),
        rec(0.61, 2, "request", "CMD_GET_POSITION", port=10002),
        event(0.62, 2, CLOSE, "by target (FIN)", port=10002),  # turned away, one client per port
        rec(0.7, 1, "request", "CMD_GET_POSITION", port=10002),
        event(0.75, 1, CLOSE, "by client (FIN)", port=10002),  # the client stopped, its last reply not come
    )
    scripts = {sc.conn: sc for sc in plan(s)}
    driver, newcomer = scripts[1], scripts[2]
    (wait,) = driver.waits.values()
    turning = _with(driver.steps[wait.final].reply, STATUS.replace(vel_rot=50, est_angle=30000))  # type: ignore[arg-type]
    driver.steps[wait.final].reply = turning
    last = driver.steps[3]
    assert last.cut and last.reply is None and not driver.steps[2].cut
    answered = rec(0.8, 1, "reply", "CMD_GET_POSITION", port=10002, **pos)
    rested = _with(turning, STATUS)
    ok = Outcome(1, replies={3: answered}, wait_final={0: rested}, sent=4)
    turned_again = Outcome(2, sent=0, closed_by_target_after=0)  # closed before its request went out
    # the last wait is not the connection's last request here: it is judged field by field (its vel_rot went from
    # 0 to 50 between the recorded last two polls, so 0 is within one poll's phase: E-REP-023)
    assert [d.path for d in judge([driver, newcomer], {1: ok, 2: turned_again})] == ["est_angle"]
    served = Outcome(2, replies={0: answered}, sent=1)  # the newcomer answered and kept: real differences
    assert {d.path for d in judge([newcomer], {2: served})} == {"(reply)", "end"}
    wrong = Outcome(1, replies={3: rec(0.8, 1, "reply", "STATUS", port=10002)}, wait_final={0: turning}, sent=4)
    assert [(d.path, d.replayed) for d in judge([driver], {1: wrong})] == [("(reply)", "CMD_GET_STATUS")]


def _two_polls() -> list[Record]:
    """A driver (it set the mode) whose wait is two CMD_GET_STATUS polls."""
    return [
        event(0.0, 1, OPEN),
        rec(0.1, 1, "request", "CMD_SET_MODE", mode=4),
        rec(0.2, 1, "request", "CMD_GET_STATUS"),
        rec(0.3, 1, "reply", "STATUS"),
        rec(0.4, 1, "request", "CMD_GET_STATUS"),
        rec(0.5, 1, "reply", "STATUS"),
    ]


def test_a_connection_s_last_wait_cut_while_the_platform_moved_is_judged_by_kind() -> None:
    (driver,) = plan(session(*_two_polls(), event(0.6, 1, CLOSE, "by client (FIN)")))
    (wait,) = driver.waits.values()
    final = driver.steps[wait.final]
    assert final.reply is not None
    final.reply = _with(final.reply, STATUS.replace(vel_rot=50, est_x=4000))  # stopped mid-drive
    elsewhere = _with(final.reply, STATUS.replace(est_x=9000))
    assert judge([driver], {1: Outcome(1, wait_final={0: elsewhere}, sent=3)}) == []
    fault = _with(final.reply, STATUS.replace(est_x=9000, app_error=3))
    assert [d.path for d in judge([driver], {1: Outcome(1, wait_final={0: fault}, sent=3)})] == ["app_error"]
    assert [d.path for d in judge([driver], {1: Outcome(1, sent=3)})] == ["(reply)"]  # no reply at all


def _wait_ending_on(before_vel_rot: int) -> Script:
    """A driver's wait of two CMD_GET_STATUS polls: the last but one turning at ``before_vel_rot`` mrad/s, the
    last with the target reached while still turning at 49 mrad/s (the soak's patrol), then a CMD_STOP."""
    stop = rec(0.6, 1, "request", "CMD_STOP")
    (driver,) = plan(session(*_two_polls(), stop, event(0.7, 1, CLOSE, "by client (FIN)")))
    (wait,) = driver.waits.values()
    final = driver.steps[wait.final]
    assert final.reply is not None and final.before is not None
    final.before = _with(final.before, STATUS.replace(vel_rot=before_vel_rot))
    final.reply = _with(final.reply, STATUS.replace(vel_rot=49, target_reached=1))
    return driver


def test_a_wait_s_final_velocity_may_differ_by_what_one_recorded_poll_period_changed_it() -> None:
    # E-REP-023: recorded 519 -> 49 mrad/s between the last two polls; the replay's poll fell later, at rest
    at_rest = STATUS.replace(vel_rot=0, target_reached=1)
    driver = _wait_ending_on(before_vel_rot=519)
    final = driver.steps[next(iter(driver.waits.values())).final]
    assert final_matches(final, _with(final.reply, at_rest))
    assert judge([driver], {1: Outcome(1, wait_final={0: _with(final.reply, at_rest)}, sent=4)}) == []
    # the slack is the velocities', not the reply's: a pose elsewhere is still a difference
    moving = _with(final.reply, STATUS.replace(vel_rot=0, target_reached=1, est_angle=30000))
    assert not final_matches(final, moving)
    # a velocity that stood still between the last two polls has only the table's 20 mrad/s
    steady = _wait_ending_on(before_vel_rot=49)
    final = steady.steps[next(iter(steady.waits.values())).final]
    assert not final_matches(final, _with(final.reply, at_rest))
    found = judge([steady], {1: Outcome(1, wait_final={0: _with(final.reply, at_rest)}, sent=4)})
    assert [(d.path, d.recorded, d.replayed) for d in found] == [("vel_rot", "49", "0")]


def test_a_wait_for_the_target_ends_only_when_the_replay_reaches_it_too() -> None:
    # E-REP-024: the recorded wait ended on target_reached 0 -> 1 (a field the table ignores); a replayed poll 10 mm
    # short of the pose, driving and not reached, is within the pose tolerance and the velocity slack but no end
    driver = _wait_ending_on(before_vel_rot=519)
    final = driver.steps[next(iter(driver.waits.values())).final]
    short = _with(final.reply, STATUS.replace(vel_rot=49, est_x=10, target_reached=0))
    assert not final_matches(final, short)
    found = judge([driver], {1: Outcome(1, wait_final={0: short}, sent=40)})
    assert [(d.path, d.recorded, d.replayed) for d in found] == [("target_reached", "ON (1)", "OFF (0)")]
    assert final_matches(final, _with(final.reply, STATUS.replace(vel_rot=49, est_x=10, target_reached=1)))
    # a wait during which it did not change (a stale "reached" from the move before) compares it as the table says
    final.before = _with(final.reply, STATUS.replace(vel_rot=519, target_reached=1))
    assert final_matches(final, short)


def _status(t: float, **changes: Any) -> Record:
    (r,) = Tap("reply", 1, 10000).feed(encode(STATUS.replace(**changes)), t)
    return r


def test_a_wait_s_final_velocity_slack_is_the_most_one_poll_period_changed_it_in_the_wait() -> None:
    # the 10-minute soak's wait at 414.6 s: 519 mrad/s, then 15, then 48 with the target reached; replayed at rest
    polls = [(0.2, 519), (0.4, 15), (0.6, 48)]
    records = [event(0.0, 1, OPEN), rec(0.1, 1, "request", "CMD_SET_MODE", mode=4)]
    for t, vel in polls:
        records += [rec(t, 1, "request", "CMD_GET_STATUS"), _status(t + 0.05, vel_rot=vel, target_reached=1)]
    (driver,) = plan(session(*records, rec(0.7, 1, "request", "CMD_STOP"), event(0.8, 1, CLOSE, "by client (FIN)")))
    (wait,) = driver.waits.values()
    final = driver.steps[wait.final]
    assert final.reply is not None
    at_rest = _with(final.reply, STATUS.replace(vel_rot=0, target_reached=1))
    assert final_matches(final, at_rest)
    assert judge([driver], {1: Outcome(1, wait_final={0: at_rest}, sent=5)}) == []
    spinning = _with(final.reply, STATUS.replace(vel_rot=600, target_reached=1))  # beyond 504, the widest change
    assert [d.path for d in judge([driver], {1: Outcome(1, wait_final={0: spinning}, sent=5)})] == ["vel_rot"]


def test_a_wait_whose_final_reply_the_recording_did_not_keep_is_judged_by_kind() -> None:
    # the recording stopped (or the client closed) while its last poll was owed its reply
    (driver,) = plan(session(*_two_polls(), rec(0.6, 1, "request", "CMD_GET_STATUS")))
    (wait,) = driver.waits.values()
    assert driver.steps[wait.final].reply is None
    answered = rec(0.7, 1, "reply", "STATUS")
    assert judge([driver], {1: Outcome(1, wait_final={0: answered}, sent=4)}) == []
    wrong = rec(0.7, 1, "reply", "CMD_GET_POSITION", x=1, y=2, angle=0.0, vel_trans=0.0, vel_rot=0.0)
    assert [d.path for d in judge([driver], {1: Outcome(1, wait_final={0: wrong}, sent=4)})] == ["(reply)"]
