"""The Python client library (clients/pltf_client), blocking client and sans-IO parts.

Most tests talk over real TCP to ``FakePlatform``: a tiny stand-in in a thread that answers GET_STATUS and
GET_POSITION with frames built by spec.codec, follows the state chart's main transitions and can be told
to misbehave (hold replies back, answer in reverse order, hang up, send garbage). The ``live`` tests run
the same scenarios against ``python -m pltf.reference_server`` when it is there. The frames of the field
capture (field-evidence.md) are the independent oracle for what the methods put on the wire.
"""

from __future__ import annotations

import inspect
import math
import socket
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from client_fakes import (
    AUTOMATIC,
    BREAKED,
    CAPTURED,
    NOT_INIT,
    READY,
    RUNNING,
    VEL,
    FakePlatform,
    LiveServer,
    status_telegram,
)
from hypothesis import given, settings
from hypothesis import strategies as st

from pltf.client import (
    AsyncPlatformClient,
    ClientCore,
    CommandRejected,
    ConnectionClosed,
    EmergencyState,
    InvalidArgument,
    MotionMode,
    OperationState,
    ParamDataType,
    PlannerState,
    PlatformClient,
    PlatformError,
    Position,
    ProtocolError,
    Status,
    Timeout,
    _generate,
    format_param_value,
    parse_param_value,
    typed_reply,
)
from pltf.client.waits import StateWait, TargetWait
from pltf.spec import errors as codec_errors
from pltf.spec.codec import REPLIES, REQUESTS, build, encode
from pltf.spec.model import load_telegrams
from pltf.spec.strategies import telegram_strategy
from pltf.spec.telegram import user_fields
from pltf.stubgen.pltf_client.names import UNIT_ALREADY_NAMED, py_name, reply_class_name


# ---------------------------------------------------------------------------------------------- fixtures
@pytest.fixture
def client(fake: FakePlatform) -> Iterator[PlatformClient]:
    with PlatformClient("127.0.0.1", fake.port, timeout=2.0) as c:
        yield c


def wait_for(predicate: Any, timeout: float = 5.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.01)


# ---------------------------------------------------------------------------------------------- generated code
def test_generated_modules_are_fresh() -> None:
    assert _generate.main(["--check"]) == 0, "run `python -m pltf.client._generate`"


def test_generate_check_fails_on_a_stale_file(tmp_path: Path) -> None:
    assert _generate.main(["--out", str(tmp_path)]) == 0
    assert _generate.main(["--check", "--out", str(tmp_path)]) == 0
    (tmp_path / "_commands.py").write_text("# edited by hand\n", encoding="utf-8")
    assert _generate.main(["--check", "--out", str(tmp_path)]) == 1


@pytest.mark.parametrize("tdef", load_telegrams(), ids=lambda d: d.name)
def test_one_method_per_command(tdef: Any) -> None:
    method = tdef.name.removeprefix("CMD_").lower()
    method = method + "_" if method in ("break", "continue") else method
    sync, aio = getattr(PlatformClient, method), getattr(AsyncPlatformClient, method)
    assert not inspect.iscoroutinefunction(sync)
    assert inspect.iscoroutinefunction(aio)
    params = list(inspect.signature(sync).parameters)[1:]
    assert params == list(inspect.signature(aio).parameters)[1:]
    assert tdef.name in (sync.__doc__ or "") and tdef.section in " ".join((sync.__doc__ or "").split())
    if not tdef.layout_known:
        assert params == ["payload"]
        return
    fields = user_fields(tdef.request)
    expected = [py_name(f) for f in fields] + (["timeout"] if tdef.answered else [])  # a FieldDef reads as a Field
    assert params == expected
    for f, p in zip(fields, params, strict=False):
        if f.unit:  # the guide's unit is in the name and in the docstring
            assert p != f.name or f.name.endswith(UNIT_ALREADY_NAMED.get(f.unit, ("-",)))
            assert f"[{f.unit}]" in (sync.__doc__ or "")
    returns = inspect.signature(sync).return_annotation
    assert returns == (reply_class_name(tdef.name) if tdef.answered else "None")


def test_reply_names_carry_units() -> None:
    names = {f.name for f in Status.__dataclass_fields__.values()}
    assert {"est_x_mm", "est_angle_mdeg", "vel_rot_mrad_s", "us_distance_mm", "timestamp_ms"} <= names
    assert list(Position.__dataclass_fields__) == ["x_mm", "y_mm", "angle_rad", "vel_trans_mm_s", "vel_rot_rad_s"]


@settings(max_examples=30)
@given(st.data())
def test_every_answered_reply_converts_to_its_typed_object(data: st.DataObject) -> None:
    cls = data.draw(st.sampled_from([c for c in REPLIES if c.DEF.answered]))
    telegram = data.draw(telegram_strategy(cls, max_items=3))
    typed = typed_reply(telegram)
    assert type(typed).__name__ == reply_class_name(cls.DEF.name)
    assert len(typed.__dataclass_fields__) == len(telegram)
    assert type(typed).from_telegram(telegram) == typed


def test_typed_reply_refuses_other_telegrams() -> None:
    with pytest.raises(InvalidArgument):
        typed_reply(REPLIES.CMD_DEBUG1(payload=b""))
    with pytest.raises(InvalidArgument):
        Status.from_telegram(build("reply", "CMD_GET_POSITION", x=0, y=0, angle=0.0, vel_trans=0.0, vel_rot=0.0))


# ---------------------------------------------------------------------------------------------- wire
def test_methods_send_the_captured_frames(fake: FakePlatform) -> None:
    log: list[tuple[str, bytes]] = []
    with PlatformClient("127.0.0.1", fake.port, wire_log=lambda d, b: log.append((d, b))) as c:
        for method, args, _ in CAPTURED:
            getattr(c, method)(*args)
        c.get_position()
    sent = [b.hex() for d, b in log if d == "send"]
    assert sent[: len(CAPTURED)] == [h.replace(" ", "") for _, _, h in CAPTURED]
    assert b"".join(b for d, b in log if d == "recv")[:5] == bytes.fromhex("ff01fe0200")
    wait_for(lambda: len(fake.received) == len(CAPTURED) + 1)


def test_string_xml_and_group_arguments(client: PlatformClient, fake: FakePlatform) -> None:
    client.set_map("office", "<map>ü</map>")  # str XML goes out UTF-8 encoded
    client.set_program(b"<?xml version='1.0' encoding='ISO-8859-1'?><program>\xfc</program>")
    client.move_path([(0, 0, 0), (1000, 0, 90000)])
    client.send_can_message(0x123, b"\x01\x02\x03\x04\x05\x06\x07\x08")
    client.get_status()
    set_map, set_program, move_path, can = fake.received[:4]
    assert set_map.xml.encode("latin-1") == "<map>ü</map>".encode()
    assert set_program.xml.encode("latin-1").endswith(b"<program>\xfc</program>")
    assert move_path.frames == ((0, 0, 0), (1000, 0, 90000))
    assert can.data == (1, 2, 3, 4, 5, 6, 7, 8)


def test_invalid_arguments_raise_and_send_nothing(client: PlatformClient, fake: FakePlatform) -> None:
    with pytest.raises(InvalidArgument, match="does not fit INT"):
        client.move_abs(2**31, 0, 0)
    with pytest.raises(ValueError, match="MotionMode"):  # InvalidArgument is a ValueError
        client.set_mode(9)  # type: ignore[arg-type]
    with pytest.raises(InvalidArgument, match="Latin-1"):
        client.speak_text("€")
    with pytest.raises(InvalidArgument, match="not answered"):
        client.request(REQUESTS.CMD_STOP())
    client.get_status()
    assert fake.names() == ["CMD_GET_STATUS"]
    assert client.core.seq == 1


# ---------------------------------------------------------------------------------------------- replies
def test_typed_status_and_position(client: PlatformClient, fake: FakePlatform) -> None:
    fake.pose = (1500, -250, 90000)
    status = client.get_status()
    assert isinstance(status, Status)
    assert status.operation_state is NOT_INIT and isinstance(status.operation_state, OperationState)
    assert status.emergency_state is EmergencyState.ST_EM_NOT_ACTIVE
    assert status.initialized is False and status.ir_active == (False, True, False, True)
    assert status.scan[1].x_mm == 30 and tuple(status.scan[0]) == (10, -20)
    assert status.pose == (1500.0, -250.0, 90.0) and status.pose.angle_deg == 90.0
    assert not status.is_ready and not status.is_running and not status.emergency_stop_active
    position = client.get_position(timeout=1.0)
    assert (position.x_mm, position.y_mm) == (1500, -250)
    assert position.angle_deg == pytest.approx(90.0) and position.pose.x_mm == 1500.0


def test_param_value_text() -> None:
    assert parse_param_value(ParamDataType.BOOLEAN, "true") is True
    assert parse_param_value(ParamDataType.BOOLEAN, "0") is False
    assert parse_param_value(ParamDataType.INTEGER, " 42 ") == 42
    assert parse_param_value(ParamDataType.DOUBLE, "0.25") == 0.25
    with pytest.raises(ValueError):
        parse_param_value(ParamDataType.BOOLEAN, "yes")
    assert [format_param_value(v) for v in (True, 3, 0.1, "x")] == ["true", "3", "0.1", "x"]


# ---------------------------------------------------------------------------------------------- waits
def test_bring_up_modes_and_states(client: PlatformClient) -> None:
    assert client.bring_up(timeout=2).operation_state is READY
    assert client.bring_up(timeout=2).is_ready  # already up: nothing sent but a status request
    client.set_mode(AUTOMATIC)
    assert client.wait_mode(AUTOMATIC, timeout=1).motion_mode is AUTOMATIC
    client.start()
    assert client.wait_state(RUNNING, timeout=1).is_running
    client.break_()
    client.wait_state(BREAKED, timeout=1)
    client.continue_()
    client.wait_state(RUNNING, timeout=1)
    client.stop()
    client.wait_state(READY, timeout=1)


def test_move_and_wait_target_reached(client: PlatformClient, fake: FakePlatform) -> None:
    client.bring_up(timeout=2)
    client.set_mode(AUTOMATIC)
    client.start()
    client.move_abs(x_mm=1000, y_mm=500, angle_mdeg=45000)
    status = client.wait_target_reached(timeout=2, poll=0.01)
    assert status.target_reached and status.pose == (1000, 500, 45)
    assert fake.names().count("CMD_GET_STATUS") >= fake.arrive_after + 1
    client.move_rel(x_mm=-1000, y_mm=0, angle_mdeg=0)  # target_reached is still set from the last move
    assert client.wait_target_reached(timeout=2, poll=0.01).pose.x_mm == 0


def test_wait_state_names_the_rejected_command(client: PlatformClient) -> None:
    client.start()  # not initialized: CMD_START needs Ready
    t0 = time.monotonic()
    with pytest.raises(CommandRejected, match=r"CMD_START .*still ST_OP_NOT_INITIALIZED.*Ready") as info:
        client.wait_state(RUNNING, timeout=0.3)
    assert info.value.command == "CMD_START" and 0.3 <= time.monotonic() - t0 < 1.5


def test_wait_state_without_command_times_out(client: PlatformClient) -> None:
    with pytest.raises(Timeout, match=r"ST_OP_RUNNING not reached within 0.2 s: it is ST_OP_NOT_INITIALIZED"):
        client.wait_state(RUNNING, timeout=0.2)
    client.bring_up(timeout=1)
    client.start()
    with pytest.raises(Timeout) as info:  # CMD_START leads to Running, not to Breaked: a plain timeout
        client.wait_state(BREAKED, timeout=0.1)
    assert not isinstance(info.value, CommandRejected)


def test_wait_mode_rejected_outside_ready(client: PlatformClient) -> None:
    client.bring_up(timeout=1)
    client.start()
    client.set_mode(VEL)
    with pytest.raises(CommandRejected, match=r"CMD_SET_MODE.*state Ready.*ST_OP_RUNNING"):
        client.wait_mode(VEL, timeout=0.2)


@pytest.mark.parametrize(
    ("setup", "message"),
    [
        (["mode VEL", "start"], "MODE_MOTION_VEL: move commands with a target run in mode MODE_MOTION_AUTOMATIC"),
        (["mode AUTOMATIC"], "operation state is ST_OP_READY: the platform moves only in state Running"),
        (["mode AUTOMATIC", "start", "no path"], "planner found no path"),
    ],
)
def test_move_that_cannot_run_is_rejected_at_once(
    client: PlatformClient, fake: FakePlatform, setup: list[str], message: str
) -> None:
    client.bring_up(timeout=1)
    fake.target_reached = True  # stale flag from an earlier move must not pass for success
    for step in setup:
        if step.startswith("mode"):
            client.set_mode(MotionMode[f"MODE_MOTION_{step.split()[1]}"])
        elif step == "start":
            client.start()
        else:
            fake.plan = PlannerState.PLANNER_NO_PATH
    client.move_abs(1000, 0, 0)
    t0 = time.monotonic()
    with pytest.raises(CommandRejected, match=message) as info:
        client.wait_target_reached(timeout=5)
    assert info.value.command == "CMD_MOVE_ABS" and time.monotonic() - t0 < 1


def test_a_retried_goal_after_a_refusal_is_driven_to(client: PlatformClient, fake: FakePlatform) -> None:
    # issue 22, bug 1: the platform takes a move up a control period later (FakePlatform), so the first status
    # after the retry still shows the refusal before it (erratum E-CLI-001)
    client.bring_up(timeout=1)
    client.set_mode(AUTOMATIC)
    client.start()
    fake.plan = PlannerState.PLANNER_COLLISION_TARGET
    client.move_abs(9000, 9000, 0)
    with pytest.raises(CommandRejected, match="PLANNER_COLLISION_TARGET"):
        client.wait_target_reached(timeout=5, poll=0.01)
    fake.plan = PlannerState.PLANNER_PATH_FOUND
    client.move_abs(3000, 200, 0)
    status = client.wait_target_reached(timeout=5, poll=0.01)
    assert status.target_reached and status.pose == (3000, 200, 0)


def test_a_goal_after_a_reached_one_is_not_judged_by_the_old_flag(client: PlatformClient, fake: FakePlatform) -> None:
    client.bring_up(timeout=1)
    client.set_mode(AUTOMATIC)
    client.start()
    client.move_abs(1000, 0, 0)
    client.wait_target_reached(timeout=5, poll=0.01)
    client.move_abs(2000, 0, 0)  # the first status after it still says "reached" (at 1000)
    assert client.wait_target_reached(timeout=5, poll=0.01).pose.x_mm == 2000


def test_target_timeout_says_where_the_platform_is(client: PlatformClient, fake: FakePlatform) -> None:
    client.bring_up(timeout=1)
    client.set_mode(AUTOMATIC)
    client.start()
    fake.arrive_after = 10**6
    client.move_abs(5000, 0, 0)
    with pytest.raises(Timeout, match=r"target not reached within 0.2 s after CMD_MOVE_ABS: .* x=0 mm"):
        client.wait_target_reached(timeout=0.2)


def test_wait_until(client: PlatformClient) -> None:
    assert client.wait_until(lambda s: s.motion_mode is MotionMode.MODE_MOTION_NO, timeout=1).timestamp_ms == 20
    with pytest.raises(Timeout, match="docked not reached"):
        client.wait_until(lambda s: s.docked, timeout=0.1, what="docked")


# ---------------------------------------------------------------------------------------------- connection
def test_pipelined_replies_are_routed_by_id(client: PlatformClient, fake: FakePlatform) -> None:
    fake.reverse = True  # the GET_POSITION reply comes before the GET_STATUS reply
    status_req = client.send(REQUESTS.CMD_GET_STATUS())
    position_req = client.send(REQUESTS.CMD_GET_POSITION())
    assert status_req is not None and position_req is not None
    assert client.wait_reply(status_req).NAME == "CMD_GET_STATUS"
    assert position_req.done  # it came first and was kept for its request
    assert client.wait_reply(position_req).NAME == "CMD_GET_POSITION"


def test_timeout_then_the_late_reply_is_dropped(client: PlatformClient, fake: FakePlatform) -> None:
    fake.reply_delay = 0.3
    with pytest.raises(Timeout, match=r"no reply to CMD_GET_POSITION within 0.05 s"):
        client.get_position(timeout=0.05)
    fake.pose = (7, 8, 0)
    fake.reply_delay = 0.0
    assert client.get_position().x_mm == 7  # not the late reply (which said x=0)
    assert isinstance(client.get_status(), Status)
    assert not client.core.unsolicited


def test_context_manager_closes_the_socket(fake: FakePlatform) -> None:
    with PlatformClient("127.0.0.1", fake.port) as c:
        sock = c._sock
        c.get_status()
    assert c.closed and sock.fileno() == -1
    wait_for(lambda: fake.disconnects == 1)
    with pytest.raises(ConnectionClosed, match="closed by the client"):
        c.get_status()
    c.close()  # idempotent


def test_peer_hang_up_raises_connection_closed(client: PlatformClient, fake: FakePlatform) -> None:
    fake.hang_up_on = "CMD_GET_STATUS"
    with pytest.raises(ConnectionClosed, match="platform closed the connection"):
        client.get_status()
    assert client.closed
    with pytest.raises(ConnectionClosed):
        client.stop()


def test_bad_reply_bytes_raise_protocol_error(client: PlatformClient, fake: FakePlatform) -> None:
    fake.garbage = bytes.fromhex("00010203 00000001 12".replace(" ", ""))
    with pytest.raises(ProtocolError, match="BadHeader") as info:
        client.get_status()
    assert isinstance(info.value.__cause__, codec_errors.BadHeader)
    assert isinstance(info.value, PlatformError) and client.closed
    with pytest.raises(ConnectionClosed, match="BadHeader"):
        client.get_status()


def test_connect_refused() -> None:
    with socket.create_server(("127.0.0.1", 0)) as s:
        port = s.getsockname()[1]
    with pytest.raises(ConnectionClosed, match=f"cannot connect to 127.0.0.1:{port}") as info:
        PlatformClient("127.0.0.1", port, connect_timeout=1)
    assert isinstance(info.value.__cause__, OSError)


# ---------------------------------------------------------------------------------------------- core (sans-IO)
def test_core_routes_replies_by_id_in_any_order() -> None:
    core = ClientCore()
    _, a = core.send(REQUESTS.CMD_GET_STATUS())
    _, b = core.send(REQUESTS.CMD_GET_POSITION())
    _, c = core.send(REQUESTS.CMD_GET_STATUS())
    frame, none = core.send(REQUESTS.CMD_START())
    assert none is None and frame == bytes.fromhex("ff01fe02000000010b")
    assert a is not None and b is not None and c is not None
    position = build("reply", "CMD_GET_POSITION", x=1, y=2, angle=0.5, vel_trans=0.0, vel_rot=0.0)
    stream = encode(position) + encode(status_telegram(est_x=1)) + encode(status_telegram(est_x=2))
    done = []
    for i in range(len(stream)):  # byte by byte
        done += core.receive_data(stream[i : i + 1])
    assert done == [b, a, c]
    assert (a.result().est_x, c.result().est_x, b.result().x) == (1, 2, 1)
    assert core.last_sent == {"CMD_GET_STATUS": 3, "CMD_GET_POSITION": 2, "CMD_START": 4}


def test_core_drops_abandoned_and_keeps_unsolicited() -> None:
    core = ClientCore()
    _, late = core.send(REQUESTS.CMD_GET_STATUS())
    _, fresh = core.send(REQUESTS.CMD_GET_STATUS())
    assert late is not None and fresh is not None
    core.abandon(late)
    core.receive_data(encode(status_telegram(est_x=1)) + encode(status_telegram(est_x=2)))
    assert late.reply is None and fresh.result().est_x == 2
    stray = build("reply", "CMD_GET_CAMERA", ip="10.0.0.1", camera_id="cam")
    assert core.receive_data(encode(stray)) == []
    assert list(core.unsolicited) == [stray]


def test_core_protocol_error_fails_every_pending_request() -> None:
    core = ClientCore(max_length=100)
    _, a = core.send(REQUESTS.CMD_GET_STATUS())
    assert a is not None
    with pytest.raises(ProtocolError, match="FrameTooLarge"):
        core.receive_data(bytes.fromhex("ff01fe02 00010000".replace(" ", "")))
    assert core.closed and isinstance(a.error, ProtocolError)
    with pytest.raises(ProtocolError):
        a.result()
    with pytest.raises(ConnectionClosed, match="FrameTooLarge"):
        core.send(REQUESTS.CMD_GET_STATUS())


def test_core_end_of_stream_fails_pending_requests() -> None:
    core = ClientCore()
    _, a = core.send(REQUESTS.CMD_GET_POSITION())
    assert a is not None and not a.done
    with pytest.raises(RuntimeError, match="no reply"):
        a.result()
    assert core.receive_data(b"") == [a]
    with pytest.raises(ConnectionClosed, match="platform closed"):
        a.result()


def test_wait_judges_ignore_statuses_from_before_the_command() -> None:
    ready = Status.from_telegram(status_telegram(operation_state=int(READY), target_reached=1, motion_mode=4))
    judge = StateWait(RUNNING, {"CMD_START": 5}, now=100.0, timeout=1.0)
    assert judge.observe(ready, now=100.1, seq=4) is False  # requested before CMD_START: no verdict
    assert judge.observe(ready, now=100.2, seq=6) is False
    with pytest.raises(CommandRejected, match="CMD_START"):
        judge.observe(ready, now=101.0, seq=7)
    target = TargetWait({"CMD_MOVE_REL": 3, "CMD_MOVE_ABS": 8}, now=0.0, timeout=5.0)
    assert target.command == ("CMD_MOVE_ABS", 8)
    assert target.observe(ready, now=0.1, seq=7) is False  # the stale "reached" of the move before
    with pytest.raises(CommandRejected, match=r"CMD_MOVE_ABS.*ST_OP_READY"):
        target.observe(ready, now=0.2, seq=9)
    with pytest.raises(ValueError, match="timeout"):
        StateWait(READY, {}, now=0.0, timeout=-1)


# ---------------------------------------------------------------------------------------------- live server
def test_live_bring_up_move_and_read_back(live: LiveServer) -> None:
    with PlatformClient("127.0.0.1", live.ports[1], timeout=5) as pltf:
        assert pltf.bring_up(timeout=10).is_ready
        pltf.set_mode(AUTOMATIC)
        pltf.wait_mode(AUTOMATIC, timeout=5)
        pltf.start()
        pltf.wait_state(RUNNING, timeout=5)
        start = pltf.get_position()
        pltf.move_rel(x_mm=500, y_mm=0, angle_mdeg=0)
        status = pltf.wait_target_reached(timeout=20)
        position = pltf.get_position()
        assert status.target_reached and status.operation_state is RUNNING
        assert math.hypot(position.x_mm - start.x_mm, position.y_mm - start.y_mm) == pytest.approx(500, abs=50)
        pltf.stop()
        pltf.wait_state(READY, timeout=5)


def test_live_rejected_command_and_parameters(live: LiveServer) -> None:
    with PlatformClient("127.0.0.1", live.ports[0], timeout=5) as pltf:
        pltf.start()  # not initialized
        with pytest.raises(CommandRejected, match="CMD_START"):
            pltf.wait_state(RUNNING, timeout=0.5)
        entries = pltf.get_pltf_param_vec().parameters
        assert entries
        first = entries[0]
        param = pltf.get_pltf_param(first.key)
        assert (param.key, param.category, param.data_type) == (first.key, first.category, first.data_type)
        assert isinstance(param.typed_value, bool | int | float)
