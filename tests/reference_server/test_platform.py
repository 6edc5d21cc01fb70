"""The sans-IO platform model: handle(telegram, now) and tick(now), no sockets."""

from __future__ import annotations

import dataclasses
import logging
import math
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pltf.reference_server.platform import Platform, handler_names
from pltf.reference_server.state_chart import EmergencyState, OperationState, State
from pltf.reference_server.status import ABSENT
from pltf.reference_server.storage import Storage
from pltf.spec.codec import REQUESTS, decode_frame, encode
from pltf.spec.model import enum_classes
from pltf.spec.parameters import load_parameters
from pltf.spec.strategies import any_telegram
from tests.reference_server.helpers import REPO, sample
from tests.reference_server.test_state_chart import GUIDE_TRANSITIONS

MotionMode: Any = enum_classes()["MotionMode"]
R = REQUESTS
DT = 0.02
INVALID = REPO / "fixtures" / "invalid"


class Sim:
    """A platform and a simulated clock."""

    def __init__(self, root: Path) -> None:
        storage = Storage(root)
        storage.seed_from_fixtures()
        self.p = Platform(storage, seed=3)
        self.p.boot(0.0)
        self.now = 0.0

    def __call__(self, telegram: Any) -> Any:
        outcome = self.p.handle(telegram, self.now)
        if outcome.reply is not None:  # every reply must survive the codec; the tests see the decoded one
            decoded = decode_frame(encode(outcome.reply), "reply")
            assert decoded == outcome.reply
            outcome = dataclasses.replace(outcome, reply=decoded)
        return outcome

    def run(self, seconds: float) -> None:
        for _ in range(round(seconds / DT)):
            self.now += DT
            self.p.tick(self.now)

    def status(self) -> Any:
        return self(R.CMD_GET_STATUS()).reply

    def to_running(self, mode: int) -> None:
        for t in (R.CMD_CONNECT_TO_PLTF(), R.CMD_INIT_PLTF(), R.CMD_SET_MODE(mode=mode), R.CMD_START()):
            assert self(t).refused is None


@pytest.fixture
def sim(tmp_path: Path) -> Sim:
    return Sim(tmp_path / "data")


def test_every_telegram_has_a_handler() -> None:
    assert handler_names() == {cls.NAME for cls in REQUESTS}


def test_boot_logs_like_the_original(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.INFO, logger="pltf.server"):
        sim = Sim(tmp_path)
    text = caplog.text
    for line in ("init pose read from", "load map: ", "load roadmap: ", "load program: ", "system state: "):
        assert line in text
    st_ = sim.status()
    assert (st_.est_x, st_.est_y, st_.est_angle) == (2000, 10000, 0)
    assert st_.operation_state == OperationState.ST_OP_NOT_INITIALIZED and st_.initialized == 0


def test_only_get_requests_are_answered(sim: Sim) -> None:
    for cls in REQUESTS:
        outcome = sim(sample(cls))
        assert (outcome.reply is not None) == cls.DEF.answered, cls.NAME


def test_absent_boards_are_reported_absent_never_invented(sim: Sim) -> None:
    s = sim.status()
    for name in (
        "relay_status",
        "io_status",
        "motor_right_status",
        "motor_left_status",
        "us_status",
        "radar_status",
        "gyro_status",
    ):
        assert getattr(s, name) == ABSENT
    assert set(s.us_distance) == {0} and set(s.io_analog_in) == {0} and s.io_battery_voltage == 0
    assert s.scan == () and s.joystick_buttons == ()


def test_state_and_motion_through_status(sim: Sim) -> None:
    sim.to_running(MotionMode.MODE_MOTION_AUTOMATIC)
    assert sim(R.CMD_MOVE_REL(x=1000, y=0, angle=90_000)).refused is None
    sim.run(0.5)
    moving = sim.status()
    assert moving.operation_state == OperationState.ST_OP_RUNNING and moving.vel_trans > 0
    assert (moving.cmd_x, moving.cmd_y) == (3000, 10000) and moving.target_reached == 0
    sim.run(10)
    done = sim.status()
    assert done.target_reached == 1
    assert abs(done.est_x - 3000) <= 20 and abs(done.est_y - 10000) <= 20
    assert abs(done.est_angle - 90_000) <= 2_000
    pos = sim(R.CMD_GET_POSITION()).reply
    assert pos.angle == pytest.approx(math.pi / 2, abs=0.04) and pos.vel_trans == 0


def test_status_between_ticks_is_the_same_picture_and_any_command_refreshes_it(sim: Sim) -> None:
    """Platform.epoch: GET_STATUS twice between two control periods answers the same fields (only the timestamp
    moves); a command, a tick or a pure query changes it or not, as it changes the platform or not."""
    sim.to_running(MotionMode.MODE_MOTION_AUTOMATIC)
    sim(R.CMD_MOVE_REL(x=1000, y=0, angle=0))
    sim.run(0.5)
    first = sim.status()
    sim(R.CMD_GET_POSITION())
    sim.now += 0.005
    again = sim.status()
    assert again == first.replace(timestamp=again.timestamp) and again.timestamp == first.timestamp + 5
    epoch = sim.p.epoch
    assert sim(R.CMD_CONNECT_TO_PLTF()).refused  # refused by the state chart in Running: nothing changed
    assert sim.p.epoch == epoch and sim.status() == again
    sim(R.CMD_BREAK())  # not a query: seen at once, before the next period
    assert sim.status().operation_state == OperationState.ST_OP_BREAKED
    sim(R.CMD_CONTINUE())
    sim.run(DT)
    assert sim.status().est_x > first.est_x  # a tick: the platform moved on


def test_move_to_station_and_its_refusals(sim: Sim) -> None:
    sim.to_running(MotionMode.MODE_MOTION_AUTOMATIC)
    assert "no station" in sim(R.CMD_MOVE_TO_STATION(station="Nowhere")).refused
    assert sim(R.CMD_MOVE_TO_STATION(station="Kitchen")).refused is None
    sim.run(40)
    s = sim.status()
    assert s.target_reached == 1 and abs(s.est_x - 5000) <= 20 and abs(s.est_y - 12200) <= 20


def test_moves_have_no_effect_in_the_wrong_mode(sim: Sim) -> None:
    sim.to_running(MotionMode.MODE_MOTION_NO)
    for t in (
        R.CMD_MOVE_REL(x=500, y=0, angle=0),
        R.CMD_MOVE_VEL(vel_trans=300, vel_rot=0),
        R.CMD_MOVE_VEL_WHEEL(vel_right=300, vel_left=300),
        R.CMD_MOVE_TO_STATION(station="Kitchen"),
    ):
        outcome = sim(t)
        assert outcome.refused is None and "no effect" in outcome.ignored
    sim.run(1)
    assert sim.status().est_x == 2000


def test_joysoft_takes_move_vel_only(sim: Sim) -> None:
    sim.to_running(MotionMode.MODE_MOTION_JOYSOFT)
    assert sim(R.CMD_MOVE_VEL_WHEEL(vel_right=300, vel_left=300)).ignored
    assert sim(R.CMD_MOVE_VEL(vel_trans=300, vel_rot=0)).ignored is None
    sim.run(1)
    assert sim.status().est_x > 2100


def test_break_continue_stop(sim: Sim) -> None:
    sim.to_running(MotionMode.MODE_MOTION_AUTOMATIC)
    sim(R.CMD_MOVE_REL(x=3000, y=0, angle=0))
    sim.run(1)
    sim(R.CMD_BREAK())
    sim.run(2)
    held = sim.status()
    assert held.operation_state == OperationState.ST_OP_BREAKED and held.vel_trans == 0
    sim.run(1)
    assert sim.status().est_x == held.est_x
    sim(R.CMD_CONTINUE())
    sim.run(1)
    assert sim.status().est_x > held.est_x
    sim(R.CMD_STOP())
    sim.run(2)
    stopped = sim.status()
    assert stopped.operation_state == OperationState.ST_OP_READY and stopped.vel_trans == 0 and stopped.path == ()


def test_shutdown_stops_motion_first(sim: Sim) -> None:
    sim.to_running(MotionMode.MODE_MOTION_VEL)
    sim(R.CMD_MOVE_VEL(vel_trans=500, vel_rot=0))
    sim.run(0.3)
    assert sim.status().vel_trans > 0
    sim(R.CMD_SHUTDOWN_PLTF())
    s = sim.status()
    assert s.vel_trans == 0 and s.operation_state == OperationState.ST_OP_NOT_INITIALIZED and s.initialized == 0


def test_emergency_stop(sim: Sim) -> None:
    sim.to_running(MotionMode.MODE_MOTION_VEL)
    sim(R.CMD_MOVE_VEL(vel_trans=500, vel_rot=0))
    sim.run(0.3)
    sim.p.set_emergency(True, sim.now)
    s = sim.status()
    assert s.emergency_state == EmergencyState.ST_EM_ACTIVE
    assert s.operation_state == OperationState.ST_OP_READY and s.vel_trans == 0
    assert "emergency" in sim(R.CMD_START()).refused
    sim.p.set_emergency(False, sim.now)
    assert sim.status().emergency_state == EmergencyState.ST_EM_RESET
    sim.run(1.1)
    assert sim.status().emergency_state == EmergencyState.ST_EM_NOT_ACTIVE
    assert sim(R.CMD_START()).refused is None


def test_documents_round_trip_and_refusal(sim: Sim) -> None:
    original = sim(R.CMD_GET_MAP()).reply
    assert original.name == "PltfMap.map" and original.xml.startswith("<?xml")
    small = '<map Version="1.0"><layer index="0"><line><point x="0" y="0"/><point x="1" y="1"/></line></layer></map>'
    assert sim(R.CMD_SET_MAP(name="small", xml=small)).refused is None
    assert tuple(sim(R.CMD_GET_MAP()).reply) == (small, "small")
    bad = (INVALID / "missing_point.map").read_text()
    assert "refused" in sim(R.CMD_SET_MAP(name="bad", xml=bad)).refused
    assert tuple(sim(R.CMD_GET_MAP()).reply) == (small, "small")
    assert sim(R.CMD_LOAD_MAP()).refused is None
    assert sim(R.CMD_GET_MAP()).reply == original
    sim(R.CMD_SET_MAP(name="small", xml=small))
    assert sim(R.CMD_SAVE_MAP()).refused is None
    assert sim.p.storage.path(sim.p.documents.get("map").kind).read_text() == small  # type: ignore[union-attr]


def test_roadmap_change_reaches_the_router(sim: Sim) -> None:
    xml = '<roadmap><stations><station id="s" name="Solo"><point x="0" y="0"/></station></stations><edges/></roadmap>'
    sim(R.CMD_SET_ROADMAP(name="solo", xml=xml))
    sim.to_running(MotionMode.MODE_MOTION_AUTOMATIC)
    assert "no station" in sim(R.CMD_MOVE_TO_STATION(station="Kitchen")).refused
    assert sim(R.CMD_MOVE_TO_STATION(station="Solo")).refused is None


def test_load_refusals_keep_the_active_document(sim: Sim) -> None:
    active = sim(R.CMD_GET_ROADMAP()).reply
    path = sim.p.storage.root / "Roadmap" / "PltfRoadmap.rm"
    path.write_bytes((INVALID / "dangling_edge.rm").read_bytes())
    assert "load refused" in sim(R.CMD_LOAD_ROADMAP()).refused
    path.unlink()
    assert "no such file" in sim(R.CMD_LOAD_ROADMAP()).refused
    assert sim(R.CMD_GET_ROADMAP()).reply == active


def test_program_has_no_name(sim: Sim) -> None:
    program = (REPO / "fixtures" / "programs" / "every_element.xml").read_text()
    assert sim(R.CMD_SET_PROGRAM(xml=program)).refused is None
    assert sim(R.CMD_GET_PROGRAM()).reply.xml == program


def test_save_without_active_document_is_refused(tmp_path: Path) -> None:
    p = Platform(Storage(tmp_path))  # empty data dir, nothing loaded
    p.boot(0.0)
    assert "no active program" in (p.handle(R.CMD_SAVE_PROGRAM(), 0.0).refused or "")
    assert p.handle(R.CMD_GET_PROGRAM(), 0.0).reply.xml == ""  # type: ignore[union-attr]


def test_parameters(sim: Sim) -> None:
    rows = load_parameters()
    vec = sim(R.CMD_GET_PLTF_PARAM_VEC()).reply.parameters
    assert [e.key for e in vec] == list(rows)
    assert sim(R.CMD_SET_PLTF_PARAM(key="IpoTransVel", value="600")).refused is None
    got = sim(R.CMD_GET_PLTF_PARAM(key="IpoTransVel")).reply
    assert (got.key, got.value, got.minimum, got.maximum) == ("IpoTransVel", "600", 50, 1500)
    for key, value in (("IpoTransVel", "99999"), ("IpoTransVel", "fast"), ("NoSuchKey", "1"), ("VelWatchdogTime", "9")):
        assert "refused" in sim(R.CMD_SET_PLTF_PARAM(key=key, value=value)).refused
    assert sim(R.CMD_GET_PLTF_PARAM(key="IpoTransVel")).reply.value == "600"
    assert tuple(sim(R.CMD_GET_PLTF_PARAM(key="NoSuchKey")).reply) == ("NoSuchKey", "", 0, 0, 0, 0)
    sim(R.CMD_SET_PLTF_PARAM(key="SirenEnabled", value="true"))
    assert sim.status().siren == 1


def test_set_frame_and_debug_queue(sim: Sim) -> None:
    sim(R.CMD_SET_FRM_PLTF(x=-500, y=700, angle=-45_000))
    s = sim.status()
    assert (s.est_x, s.est_y, s.est_angle) == (-500, 700, -45_000)
    debug = sim(R.CMD_GET_DEBUG_DATA()).reply
    assert any("estimated frame set" in e.entry for e in debug.protocol_queue)
    camera = sim(R.CMD_GET_CAMERA()).reply
    assert (camera.ip, camera.camera_id) == ("", "")  # no camera fitted: empty strings (E-REP-020)


def test_exit_and_close_socket_outcomes(sim: Sim) -> None:
    assert sim(R.CMD_CLOSE_SOCKET()).close_connection
    sim.to_running(MotionMode.MODE_MOTION_NO)
    outcome = sim(R.CMD_EXIT())
    assert outcome.exit_server and sim.p.chart.state is State.NOT_CONNECTED


@settings(max_examples=60, suppress_health_check=[HealthCheck.function_scoped_fixture], deadline=None)
@given(telegrams=st.lists(any_telegram("request", max_items=3), max_size=40))
def test_any_request_sequence_keeps_the_invariants(
    tmp_path_factory: pytest.TempPathFactory, telegrams: list[Any]
) -> None:
    """Fuzz invariant: handle never raises; only answered telegrams get a reply, and it encodes; the state
    changes only along the guide's transitions."""
    sim = Sim(tmp_path_factory.mktemp("fuzz"))
    for t in telegrams:
        before = sim.p.chart.state
        outcome = sim(t)
        after = sim.p.chart.state
        assert (outcome.reply is not None) == t.DEF.answered
        if t.NAME == "CMD_EXIT":
            assert after is State.NOT_CONNECTED
        elif before is not after:
            assert GUIDE_TRANSITIONS[(t.NAME, before)] is after
        sim.run(0.1)
