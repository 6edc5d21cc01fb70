"""pltf.fake_hardware.controller: connect/init transactions, the absent status, raw CAN and the status snapshot."""

from __future__ import annotations

from typing import Any

import can
import pytest

from pltf.fake_hardware import ALL_NODES, ControllerError, Hardware, Node, St
from pltf.fake_hardware.board_status import BoardStatus, assemble
from pltf.fake_hardware.boards import MotorBoard
from pltf.fake_hardware.controller import CAN_ERR_BUSOFF, CAN_ERR_RESTARTED, LISTEN_BUFFER
from pltf.spec.codec import REPLIES, decode_frame, encode
from pltf.spec.model import load_telegrams
from tests.fake_hardware.conftest import Sniffer, run

STATUS = next(t for t in load_telegrams() if t.name == "CMD_GET_STATUS")
SECTIONS = ("relay", "io", "motor", "us", "radar", "gyro")
BOARD_FIELDS = [f for f in STATUS.reply or () if f.name.split("_")[0] in SECTIONS]


def test_board_status_has_exactly_the_board_fields_of_the_status_telegram() -> None:
    fields = BoardStatus().as_fields()
    assert list(fields) == [f.name for f in BOARD_FIELDS]
    for f in BOARD_FIELDS:
        value = fields[f.name]
        assert (len(value) if isinstance(value, tuple) else None) == f.repeat, f.name


def _status_telegram(board: BoardStatus) -> bytes:
    values: dict[str, Any] = {}
    for f in STATUS.reply or ():
        if f.is_group:
            values[f.name] = ()
        elif f.type in ("DOUBLE", "DOUB"):
            values[f.name] = 0.0
        else:
            values[f.name] = (0,) * f.repeat if f.repeat else 0
    values.update(board.as_fields())
    return encode(REPLIES.CMD_GET_STATUS(**values))


def test_the_snapshot_goes_into_a_real_status_telegram(hw: Hardware) -> None:
    run(hw, 0.0, 0.3)
    board = hw.controller.board_status()
    decoded = decode_frame(_status_telegram(board), "reply")
    for name, value in board.as_fields().items():
        got = getattr(decoded, name)
        assert (tuple(got) if isinstance(value, tuple) else got) == value, name
    assert decode_frame(_status_telegram(BoardStatus()), "reply").gyro_status == -1


def test_everything_is_absent_before_the_connect(make_hw: Any) -> None:
    hw = make_hw()
    run(hw, 0.0, 0.5)
    status = hw.controller.board_status()
    assert status == BoardStatus()
    assert all(status.as_fields()[f] == St.ABSENT for f in status.as_fields() if f.endswith("_status"))
    assert hw.controller.drive_fault() == "CAN bus not connected"
    with pytest.raises(ControllerError):
        hw.controller.init(0.5)
    with pytest.raises(ControllerError):
        hw.controller.set_digout(0, 1, True, 0.5)


def test_a_missing_node_is_reported_not_faked(make_hw: Any) -> None:
    fitted = [n for n in ALL_NODES if n != Node.GYROBOARD]
    hw = make_hw(nodes=fitted, expected=ALL_NODES)
    txn = hw.connect(0.0)
    assert not txn.done  # waits for the gyro until the probe deadline
    t, events = run(hw, 0.0, 0.2)
    assert txn.done and not txn.ok and txn.missing == (Node.GYROBOARD,)
    assert [e.text for e in events if e.kind == "connect_done"] == ["CAN nodes missing: GYROBOARD"]
    assert hw.controller.connected == set(fitted)
    init = hw.init(t)
    assert init.done and init.ok  # only the connected nodes are tested
    t, _ = run(hw, t, t + 1.0)
    s = hw.controller.board_status()
    assert (s.gyro_status, s.gyro_accel, s.gyro_angle, s.gyro_temp) == (St.ABSENT, (0, 0, 0), 0, 0)
    assert s.radar_status == 0 and s.motor_right_status == 0


def test_the_events_of_connect_and_init_come_out_of_the_next_step(make_hw: Any) -> None:
    hw = make_hw()
    hw.connect(0.0)
    hw.init(0.0)
    kinds = [e.kind for e in hw.step(0.02)]
    assert kinds == ["connect_done", "init_done"] and hw.step(0.04) == []


def test_init_results_and_a_failing_self_test(make_hw: Any) -> None:
    hw = make_hw()
    hw.connect(0.0)
    hw.circuit.press()
    txn = hw.init(0.0)
    assert txn.done and not txn.ok
    results = txn.results
    assert results[Node.RELAYBOARD].errors == 0x01 and not results[Node.RELAYBOARD].passed
    assert results[Node.MOTOR_LEFT].errors == 0x04
    assert results[Node.IOBOARD].passed and results[Node.IOBOARD].status == 0
    t, _ = run(hw, 0.0, 0.2)
    assert hw.controller.board_status().motor_left_status & (St.SELFTEST_FAILED | St.NOT_INITIALIZED)
    hw.circuit.release()
    assert hw.init(t).ok


def test_init_releases_the_brakes(make_hw: Any) -> None:
    hw = make_hw()
    right = hw.boards[Node.MOTOR_RIGHT]
    assert isinstance(right, MotorBoard)
    hw.connect(0.0)
    run(hw, 0.0, 0.1)
    assert right.brake_engaged
    hw.init(0.1)
    run(hw, 0.1, 0.2)
    assert not right.brake_engaged  # erratum E-HW-005


def test_listening_ids_keep_and_delete(hw: Hardware) -> None:
    c = hw.controller
    c.add_listening_id(0x120)  # right encoder
    c.add_listening_id(0x700)
    t, _ = run(hw, 0.0, 0.1)
    kept = c.get_can_messages(delete=False)
    assert [r.can_id for r in kept] == [0x120] * 5
    assert [r.timestamp for r in kept] == pytest.approx([0.02, 0.04, 0.06, 0.08, 0.1])  # simulated bus time
    assert all(len(r.data) == 8 for r in kept)
    assert c.get_can_messages(delete=True) == kept
    assert c.get_can_messages(delete=False) == []
    c.remove_listening_id(0x120)
    sniffer = Sniffer(hw.channel)
    try:
        sniffer.bus.send(can.Message(arbitration_id=0x700, data=b"\x01\x02", is_extended_id=False, timestamp=t))
        run(hw, t, t + 0.1)
        (record,) = c.get_can_messages(delete=True)
        assert (record.can_id, record.data, record.timestamp) == (0x700, b"\x01\x02" + b"\0" * 6, t)
    finally:
        sniffer.close()
    with pytest.raises(ControllerError):
        c.add_listening_id(0x800)


def test_the_listening_buffer_is_bounded(hw: Hardware) -> None:
    hw.controller.add_listening_id(0x7FF)
    sniffer = Sniffer(hw.channel)
    try:
        for i in range(LISTEN_BUFFER + 5):
            sniffer.bus.send(can.Message(arbitration_id=0x7FF, data=i.to_bytes(4, "big"), is_extended_id=False))
        run(hw, 0.0, 0.02)
    finally:
        sniffer.close()
    records = hw.controller.get_can_messages(delete=True)
    assert len(records) == LISTEN_BUFFER
    assert records[0].data[:4] == (5).to_bytes(4, "big")  # the oldest went first


def test_send_can_message_reaches_the_bus_and_acts_on_a_board(hw: Hardware) -> None:
    right = hw.boards[Node.MOTOR_RIGHT]
    assert isinstance(right, MotorBoard)
    sniffer = Sniffer(hw.channel)
    try:
        assert hw.controller.send_can_message(0x7AB, b"\xde\xad", 0.0)
        assert hw.controller.send_can_message(0x111, b"\x00", 0.0)  # MotorRight_Brake, engage (8 bytes on the wire)
        run(hw, 0.0, 0.1)
        frames = [f for f in sniffer.frames() if f.arbitration_id in (0x7AB, 0x111)]
        assert [(f.arbitration_id, bytes(f.data)) for f in frames] == [
            (0x7AB, b"\xde\xad" + b"\0" * 6),
            (0x111, b"\0" * 8),
        ]
        assert right.brake_engaged
    finally:
        sniffer.close()
    with pytest.raises(ControllerError):
        hw.controller.send_can_message(0x100, b"\0" * 9, 0.1)


def test_the_radius_parameter_drives_the_odometry(make_hw: Any) -> None:
    params = {"RadiusWheel": 130.0}
    hw = make_hw(params=params.__getitem__)
    hw.connect(0.0)
    hw.init(0.0)
    hw.controller.set_wheel_velocities(400, 400)
    t, _ = run(hw, 0.0, 1.0)
    right = hw.boards[Node.MOTOR_RIGHT]
    assert isinstance(right, MotorBoard)
    before = hw.controller.wheel_travel[0]
    true_before = right.true_travel
    params["RadiusWheel"] = 143.0  # a wrong parameter: 10 % too large (E-HW-007)
    run(hw, t, t + 1.0)
    measured = hw.controller.wheel_travel[0] - before
    assert measured == pytest.approx(1.1 * (right.true_travel - true_before), rel=0.02)


def test_platforms_on_separate_channels_do_not_cross_talk(make_hw: Any) -> None:
    a, b = make_hw(), make_hw()
    assert a.channel != b.channel
    a.connect(0.0)
    a.init(0.0)
    txn = b.connect(0.0)
    run(b, 0.0, 0.2)
    assert txn.done and txn.missing == ()
    a.controller.set_wheel_velocities(300, 300)
    run(a, 0.0, 0.5)
    run(b, 0.2, 0.5)
    assert a.motors[0] is not None and a.motors[0].wheel_velocity > 0
    assert b.motors[0] is not None and b.motors[0].wheel_velocity == 0


def test_socketcan_error_frames_signal_bus_off(hw: Hardware) -> None:
    sniffer = Sniffer(hw.channel)
    try:
        sniffer.bus.send(can.Message(arbitration_id=CAN_ERR_BUSOFF, is_error_frame=True, timestamp=0.0))
        _, events = run(hw, 0.0, 0.04)
        assert hw.controller.bus_off and [e.kind for e in events] == ["connect_done", "init_done", "bus_off"]
        assert hw.controller.board_status().io_status & St.BUS_OFF
        sniffer.bus.send(can.Message(arbitration_id=CAN_ERR_RESTARTED, is_error_frame=True, timestamp=0.04))
        _, events = run(hw, 0.04, 0.08)
        assert not hw.controller.bus_off and [e.kind for e in events] == ["bus_on"]
    finally:
        sniffer.close()


def test_receive_stamping_for_real_interfaces(make_hw: Any) -> None:
    hw = make_hw()
    hw.controller.stamp = "receive"
    hw.connect(0.0)
    hw.controller.add_listening_id(0x220)
    run(hw, 0.0, 0.1)
    assert [r.timestamp for r in hw.controller.get_can_messages(True)] == pytest.approx([0.02, 0.04, 0.06, 0.08, 0.1])


def test_the_non_virtual_path(monkeypatch: pytest.MonkeyPatch, make_hw: Any) -> None:
    """interface="socketcan" (vcan0 or a real adapter): stock python-can buses, polled with recv(timeout=0), frames
    stamped at reception. No kernel CAN device here, so can.Bus is routed to python-can's own virtual bus."""
    opened: list[str] = []
    real_bus = can.Bus

    def fake_bus(interface: str, channel: str, **kwargs: Any) -> can.BusABC:
        opened.append(interface)
        return real_bus(interface="virtual", channel=f"fake-{channel}", **kwargs)

    monkeypatch.setattr(can, "Bus", fake_bus)
    with pytest.raises(ValueError, match="needs a channel"):
        make_hw(interface="socketcan")
    hw = make_hw(interface="socketcan", channel="vcan0")
    assert opened == ["socketcan"] * 8 and hw.controller.stamp == "receive"
    assert hw.connect(0.0).ok and hw.init(0.0).ok
    hw.controller.set_wheel_velocities(250, 250)
    run(hw, 0.0, 1.0)
    assert hw.motors[0] is not None and hw.motors[0].wheel_velocity == pytest.approx(250)
    assert hw.controller.board_status().motor_right_status == 0


def test_the_snapshot_is_assembled_again_whenever_a_reading_or_a_status_word_changed(hw: Hardware) -> None:
    """board_status is memoized between CAN frames; it must always equal a snapshot assembled afresh."""
    c = hw.controller

    def fresh() -> BoardStatus:
        readings = {n: r for n, r in c._readings.items() if n in c.connected}
        return assemble(readings, {n: c.status_word(n) for n in ALL_NODES})

    temps = set()
    for k in range(25):
        if k == 10:  # a reading changes: the right motor reports 80 degC from its next State frame on
            motor = hw.motors[0]
            assert motor is not None
            motor.temperature_override = 80.0
        run(hw, k * 0.02, (k + 1) * 0.02)
        status = c.board_status()
        assert status == fresh()
        temps.add(status.motor_right_temp)
    assert 80 in temps and len(temps) == 2
    assert c.board_status() is c.board_status()  # nothing arrived in between: the same snapshot
    sniffer = Sniffer(hw.channel)
    try:  # an error frame: the status words change, no reading does
        sniffer.bus.send(can.Message(arbitration_id=CAN_ERR_BUSOFF, is_error_frame=True, timestamp=0.5))
        run(hw, 0.5, 0.52)
        assert c.board_status().io_status & St.BUS_OFF and c.board_status() == fresh()
    finally:
        sniffer.close()
