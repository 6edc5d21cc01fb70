"""Every board driven through the controller API; the frames on the bus decode with the database."""

from __future__ import annotations

import math
import random
from collections import Counter
from typing import Any

import pytest

from pltf.fake_hardware import ControllerError, Hardware, Node, St
from pltf.fake_hardware.boards import IoBoard, MotorBoard, RelayBoard, UltrasonicBoard
from tests.fake_hardware.conftest import Sniffer, run


def names(decoded: list[tuple[str, dict[str, Any], Any]]) -> Counter[str]:
    return Counter(name for name, _, _ in decoded)


def last(decoded: list[tuple[str, dict[str, Any], Any]], name: str) -> dict[str, Any]:
    return [s for n, s, _ in decoded if n == name][-1]


def test_boards_are_silent_until_probed_and_answer_probe_and_self_test(make_hw: Any) -> None:
    hw = make_hw()
    sniffer = Sniffer(hw.channel)
    try:
        run(hw, 0.0, 0.5)
        assert sniffer.frames() == []
        txn = hw.connect(0.5)
        assert txn.done and txn.ok and txn.missing == ()
        hw.init(0.5)
        decoded = sniffer.decoded()
        seen = names(decoded)
        for prefix in ("IoBoard", "MotorRight", "MotorLeft", "UsBoard", "RelayBoard", "RadarBoard", "GyroBoard"):
            for function in ("Probe", "ProbeReply", "SelfTest", "SelfTestResult"):
                assert seen[f"{prefix}_{function}"] == 1, (prefix, function)
        replies = [s for n, s, _ in decoded if n.endswith("_ProbeReply")]
        assert sorted(s["NodeId"] for s in replies) == list(range(7))
        assert all(s["Passed"] == 1 for n, s, _ in decoded if n.endswith("_SelfTestResult"))
        assert all(f.timestamp == 0.5 for _, _, f in decoded)  # simulated time, not the wall clock
    finally:
        sniffer.close()


def test_cyclic_rates_follow_the_database(hw: Hardware, sniffer: Sniffer) -> None:
    run(hw, 0.0, 0.02)
    sniffer.frames()
    run(hw, 0.02, 1.02)
    seen = names(sniffer.decoded())
    assert seen["MotorRight_Encoder"] == 50 and seen["MotorLeft_Encoder"] == 50
    assert seen["MotorRight_State"] == 10 and seen["IoBoard_Battery"] == 10
    assert seen["GyroBoard_Angle"] == 20 and seen["RelayBoard_State"] == 10
    assert seen["MotorRight_Setpoint"] == 50  # the controller's cyclic setpoints (E-HW-008)
    assert seen["UsBoard_Distances1_4"] == 0  # not measuring


def test_motor_follows_setpoints_within_its_acceleration_and_odometry_matches(hw: Hardware, sniffer: Sniffer) -> None:
    right, left = hw.motors
    assert right is not None and left is not None
    hw.controller.set_wheel_velocities(500, -250)
    t, _ = run(hw, 0.0, 0.1)
    assert 0 < right.wheel_velocity < 500  # still accelerating at 2000 mm/s^2
    t, _ = run(hw, t, 2.0)
    assert right.wheel_velocity == pytest.approx(500) and left.wheel_velocity == pytest.approx(-250)
    decoded = sniffer.decoded()
    assert last(decoded, "MotorRight_Setpoint")["Velocity"] == 500
    assert last(decoded, "MotorLeft_Setpoint")["Velocity"] == -250
    assert last(decoded, "MotorRight_Encoder")["Velocity"] == 500
    assert last(decoded, "MotorLeft_State")["Setpoint"] == -250
    assert last(decoded, "MotorRight_State")["Current"] > 0 > last(decoded, "MotorLeft_State")["Current"]
    travel_r, travel_l = hw.controller.wheel_travel
    # the controller is at most one encoder frame (20 ms) behind the wheel
    assert travel_r == pytest.approx(right.true_travel, abs=500 * 0.02 + 0.1)
    assert travel_l == pytest.approx(left.true_travel, abs=250 * 0.02 + 0.1)
    assert hw.controller.wheel_velocities == (500.0, -250.0)
    dr, dl = hw.controller.take_wheel_travel()
    assert (dr, dl) == (travel_r, travel_l) and hw.controller.take_wheel_travel() == (0.0, 0.0)


def test_encoder_ticks_and_wrap(make_hw: Any) -> None:
    hw = make_hw()
    right = hw.boards[Node.MOTOR_RIGHT]
    assert isinstance(right, MotorBoard)
    right.tick_offset = 2**31 - 1000  # wraps after about 10 mm
    hw.connect(0.0)
    hw.init(0.0)
    hw.controller.set_wheel_velocities(300, 0)
    run(hw, 0.0, 1.0)
    assert right.ticks < 0  # wrapped
    assert right.params.ticks_per_rev == 81920
    assert hw.controller.wheel_travel[0] == pytest.approx(right.true_travel, abs=300 * 0.02 + 0.1)


def test_brake_command_stops_the_wheel_and_shows_in_the_status(hw: Hardware, sniffer: Sniffer) -> None:
    right, left = hw.motors
    assert right is not None and left is not None
    hw.controller.set_wheel_velocities(400, 400)
    t, _ = run(hw, 0.0, 0.5)
    hw.controller.set_brake(1, released=False, now=t)  # guide: 0 = brake enabled
    t, _ = run(hw, t, 1.0)
    assert right.wheel_velocity == 0 and left.wheel_velocity == pytest.approx(400)
    assert last(sniffer.decoded(), "MotorRight_Brake") == {"Release": 0}
    status = hw.controller.board_status()
    assert status.motor_right_status & St.BRAKE_ENGAGED and not status.motor_left_status & St.BRAKE_ENGAGED
    assert hw.controller.drive_fault() == "MOTOR_RIGHT brake engaged"
    hw.controller.set_brake(1, released=True, now=t)
    run(hw, t, 1.5)
    assert right.wheel_velocity == pytest.approx(400)
    with pytest.raises(ControllerError):
        hw.controller.set_brake(3, released=True, now=t)


def test_setpoint_watchdog_stops_a_motor_without_setpoints(hw: Hardware) -> None:
    right, _ = hw.motors
    assert right is not None
    hw.controller.set_wheel_velocities(300, 300)
    t, _ = run(hw, 0.0, 0.5)
    for _ in range(30):  # the boards alone, as if the controller had died
        t += 0.02
        for board in hw.boards.values():
            board.step(t)
    assert right.wheel_velocity == 0 and right.status() & St.SETPOINT_TIMEOUT


def test_io_board_digital_out_inputs_and_battery(hw: Hardware, sniffer: Sniffer) -> None:
    io = hw.boards[Node.IOBOARD]
    assert isinstance(io, IoBoard)
    io.digital_in = 0x8001
    io.analog_in = [1, 2, 3, 4, 5, 6, 7, 1023]
    hw.controller.set_digout(0, 3, True, 0.0)
    hw.controller.set_digout(0, 15, True, 0.0)
    hw.controller.set_digout(0, 3, False, 0.0)
    run(hw, 0.0, 0.2)
    decoded = sniffer.decoded()
    assert [s for n, s, _ in decoded if n == "IoBoard_DigOut"] == [
        {"Channel": 3, "Value": 1},
        {"Channel": 15, "Value": 1},
        {"Channel": 3, "Value": 0},
    ]
    assert last(decoded, "IoBoard_Digital") == {"DigIn": 0x8001, "DigOut": 0x8000, "Status": 0}
    s = hw.controller.board_status()
    assert (s.io_digital_in, s.io_digital_out, s.io_status) == (0x8001, 0x8000, 0)
    assert s.io_analog_in == (1, 2, 3, 4, 5, 6, 7, 1023)
    assert s.io_battery_voltage == 25600
    with pytest.raises(ControllerError):
        hw.controller.set_digout(0, 16, True, 0.2)


def test_relay_board_relays_keypad_opto_and_analog(hw: Hardware, sniffer: Sniffer) -> None:
    relay = hw.boards[Node.RELAYBOARD]
    assert isinstance(relay, RelayBoard)
    relay.digital_in, relay.keypad = 0x05, 0x03
    relay.analog_in = [10, 20, 30, 40, 50, 60, 70, 80]
    relay.opto_distance = [820, 815, 0, 12]
    hw.controller.set_digout(1, 1, True, 0.0)  # "the second channel of Relay out is attached to a camera"
    run(hw, 0.0, 0.2)
    state = last(sniffer.decoded(), "RelayBoard_State")
    assert state["Relays"] == 0x02 and state["EmergencyCircuitOpen"] == 0
    s = hw.controller.board_status()
    assert s.relay_digital_in == 0x05 | 0x03 << 8  # keypad in bits 8-15 (E-HW-011)
    assert s.relay_analog_in == (10, 20, 30, 40, 50, 60, 70, 80)
    assert s.relay_opto_distance == (820, 815, 0, 12) and s.relay_status == 0
    with pytest.raises(ControllerError):
        hw.controller.set_digout(1, 8, True, 0.2)  # 8 relays (E-HW-010)
    with pytest.raises(ControllerError):
        hw.controller.set_digout(2, 0, True, 0.2)


def test_ultrasonic_board_measures_the_active_sensors_only(make_hw: Any) -> None:
    ranges = [float(500 + 100 * i) for i in range(16)]
    ranges[2] = math.inf  # no echo
    ranges[3] = 4000.0  # beyond the range
    hw = make_hw(us_source=lambda now: ranges)
    hw.connect(0.0)
    hw.init(0.0)
    sniffer = Sniffer(hw.channel)
    try:
        us = hw.boards[Node.USBOARD]
        assert isinstance(us, UltrasonicBoard)
        us.analog_in = [100, 200, 300, 400]
        hw.controller.start_ultrasonic(0b1000_0000_0000_1111, 0.0)
        t, _ = run(hw, 0.0, 0.3)
        decoded = sniffer.decoded()
        assert last(decoded, "UsBoard_Start") == {"ActiveMask": 0x800F}
        assert last(decoded, "UsBoard_Status") == {"Status": St.MEASURING, "ActiveMask": 0x800F}
        s = hw.controller.board_status()
        assert s.us_distance == (500, 600, 3000, 3000) + (0,) * 11 + (2000,)
        assert s.us_analog_in == (100, 200, 300, 400, 0, 0, 0, 0)  # 4 inputs on the board (E-REP-007)
        assert s.us_status == St.MEASURING
        hw.controller.stop_ultrasonic(t)
        t, _ = run(hw, t, t + 0.3)
        later = sniffer.decoded()
        assert names(later)["UsBoard_Stop"] == 1
        assert not any(n.startswith("UsBoard_Distances") for n, _, f in later if f.timestamp > t - 0.2)
        assert hw.controller.board_status().us_distance == (0,) * 16
        with pytest.raises(ControllerError):
            hw.controller.start_ultrasonic(0x10000, t)
    finally:
        sniffer.close()


def test_radar_and_gyro_boards(make_hw: Any) -> None:
    hw = make_hw(
        radar_source=lambda now: [120.0, -35.4, 0.0, 3000.0],
        motion_source=lambda now: (0.25, -0.5, 9.81, 0.0 if now < 1.0 else 0.5),
    )
    hw.connect(0.0)
    hw.init(0.0)
    sniffer = Sniffer(hw.channel)
    try:
        run(hw, 0.0, 2.0)
        s = hw.controller.board_status()
        assert s.radar_velocity == (120, -35, 0, 3000) and s.radar_status == 0
        assert s.gyro_accel == (2500, -5000, 98100)  # x 10000 (0.001 m/s^2 on CAN)
        assert s.gyro_angle == pytest.approx(0.5 * 10_000, abs=0.02 * 0.5 * 10_000 + 1)  # 1 s at 0.5 rad/s
        assert s.gyro_temp == 350_000 and s.gyro_status == 0
        decoded = sniffer.decoded()
        assert last(decoded, "RadarBoard_Velocity")["Velocity2"] == -35
        assert last(decoded, "GyroBoard_Accel")["AccelZ"] == pytest.approx(9.81)
        assert hw.init(2.0).results[Node.GYROBOARD].errors == 0x02  # turning: no calibration (E-HW-019)
    finally:
        sniffer.close()


def test_shutdown_silences_the_boards_and_drops_the_bus(hw: Hardware, sniffer: Sniffer) -> None:
    run(hw, 0.0, 0.2)
    hw.shutdown(0.2)
    run(hw, 0.2, 0.4)
    decoded = sniffer.decoded()
    assert names(decoded)["MotorLeft_Shutdown"] == 1
    assert not [n for n, _, f in decoded if f.timestamp > 0.21]
    assert not hw.controller.bus_up and hw.controller.board_status().motor_left_status == St.ABSENT


def test_every_frame_of_a_busy_run_decodes(make_hw: Any) -> None:
    rng = random.Random(3)
    hw = make_hw(us_source=lambda now: [rng.uniform(100, 3500) for _ in range(16)])
    sniffer = Sniffer(hw.channel)
    try:
        hw.connect(0.0)
        hw.init(0.0)
        hw.controller.start_ultrasonic(0xFFFF, 0.0)
        t = 0.0
        for k in range(50):
            hw.controller.set_wheel_velocities(rng.uniform(-800, 800), rng.uniform(-800, 800))
            hw.controller.set_digout(k % 2, k % 8, bool(k % 3), t)
            t, _ = run(hw, t, t + 0.1)
        decoded = sniffer.decoded()
        assert len(decoded) > 1500
        assert len(names(decoded)) >= 50
    finally:
        sniffer.close()
