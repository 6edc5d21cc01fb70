"""Every fault of the issue, injected through the FaultInjector; the test checks the controller's view."""

from __future__ import annotations

from typing import Any

import pytest

from pltf.fake_hardware import Fault, FaultError, FaultKind, Hardware, Node, St
from pltf.fake_hardware.boards import IoBoard, MotorBoard
from pltf.fake_hardware.controller import NODE_TIMEOUT
from tests.fake_hardware.conftest import run

K = FaultKind


def motors(hw: Hardware) -> tuple[MotorBoard, MotorBoard]:
    right, left = hw.motors
    assert right is not None and left is not None
    return right, left


def drive(hw: Hardware, right: float = 400, left: float = 400, until: float = 1.0) -> float:
    hw.controller.set_wheel_velocities(right, left)
    t, _ = run(hw, 0.0, until)
    return t


def test_unplug_and_replug_a_node(hw: Hardware) -> None:
    t, _ = run(hw, 0.0, 0.2)
    hw.faults.inject(Fault(K.UNPLUG, "USBOARD"), t)
    t, events = run(hw, t, t + NODE_TIMEOUT + 0.1)
    assert [(e.kind, e.node) for e in events] == [("node_lost", Node.USBOARD)]
    s = hw.controller.board_status()
    assert s.us_status & St.NODE_TIMEOUT and not s.io_status & St.NODE_TIMEOUT
    assert hw.faults.clear(K.UNPLUG, "USBOARD", t)
    t, events = run(hw, t, t + 0.2)
    assert [(e.kind, e.node) for e in events] == [("node_back", Node.USBOARD)]
    assert hw.controller.board_status().us_status == 0


def test_a_node_unplugged_at_connect_is_missing(make_hw: Any) -> None:
    hw = make_hw()
    hw.faults.inject(Fault(K.UNPLUG, "RADARBOARD"), 0.0)
    txn = hw.connect(0.0)
    run(hw, 0.0, 0.2)
    assert txn.missing == (Node.RADARBOARD,)
    assert hw.controller.board_status().radar_status == St.ABSENT


def test_unplugged_motor_stops_the_drive(hw: Hardware) -> None:
    t = drive(hw)
    hw.faults.inject(Fault(K.UNPLUG, "MOTOR_LEFT"), t)
    run(hw, t, t + 1.0)
    _, left = motors(hw)
    assert left.wheel_velocity == 0  # its setpoints no longer arrive: the watchdog stops it
    assert hw.controller.drive_fault() == "MOTOR_LEFT not answering"


def test_emergency_stop_pressed_and_released(hw: Hardware) -> None:
    right, left = motors(hw)
    t = drive(hw)
    hw.faults.inject(Fault(K.EMERGENCY_STOP), t)
    t, events = run(hw, t, t + 0.02)
    assert [e.kind for e in events] == ["emergency_pressed"]  # the relay board sent its State at once
    t, _ = run(hw, t, t + 0.5)
    assert right.wheel_velocity == 0 == left.wheel_velocity
    c = hw.controller
    assert c.emergency_active and c.drive_fault() == "emergency stop"
    s = c.board_status()
    assert s.relay_status & St.EMERGENCY_STOP
    assert s.motor_right_status & (St.EMERGENCY_STOP | St.BRAKE_ENGAGED) == St.EMERGENCY_STOP | St.BRAKE_ENGAGED
    hw.faults.clear(K.EMERGENCY_STOP, now=t)
    t, events = run(hw, t, t + 0.5)
    assert [e.kind for e in events] == ["emergency_released"]
    assert not c.emergency_active and c.drive_fault() is None
    assert right.wheel_velocity == 0  # no motion until a new command (E-HW-009)
    c.set_wheel_velocities(200, 200)
    run(hw, t, t + 0.5)
    assert right.wheel_velocity == pytest.approx(200)


def test_motor_over_temperature(hw: Hardware) -> None:
    right, left = motors(hw)
    t = drive(hw)
    hw.faults.inject(Fault(K.OVERTEMP, "MOTOR_RIGHT", 92.0), t)
    t, _ = run(hw, t, t + 0.5)
    s = hw.controller.board_status()
    assert s.motor_right_temp == 92 and s.motor_right_status & St.OVER_TEMPERATURE
    assert right.wheel_velocity == 0 and left.wheel_velocity == pytest.approx(400)
    assert hw.controller.drive_fault() == "MOTOR_RIGHT over-temperature"
    assert hw.init(t).results[Node.MOTOR_RIGHT].errors == 0x02
    hw.faults.clear(K.OVERTEMP, "MOTOR_RIGHT", t)
    assert hw.init(t).ok
    t, _ = run(hw, t, t + 0.5)
    s = hw.controller.board_status()
    assert s.motor_right_temp < 30 and not s.motor_right_status & St.OVER_TEMPERATURE
    assert right.wheel_velocity == pytest.approx(400)


def test_the_motor_heats_with_its_current() -> None:
    from pltf.fake_hardware.boards.motor import MotorParams

    p = MotorParams()
    steady = p.ambient + p.heat_per_a2 * 5.0**2 * p.thermal_tau
    assert steady == pytest.approx(55.0)  # 5 A continuous stays below the 80 degC trip


def test_encoder_slip_shows_as_an_odometry_error(hw: Hardware) -> None:
    right, left = motors(hw)
    hw.faults.inject(Fault(K.SLIP, "MOTOR_LEFT", 0.1), 0.0)
    drive(hw, until=2.0)
    travel_r, travel_l = hw.controller.wheel_travel
    assert travel_r == pytest.approx(right.true_travel, rel=0.02)
    assert travel_l == pytest.approx(1.1 * left.true_travel, rel=0.02)


def test_the_world_reports_a_blocked_wheel(hw: Hardware) -> None:
    right, _ = motors(hw)
    t = drive(hw, until=0.5)
    for k in range(1, 26):  # the world holds the right wheel (a wall): it does not roll
        right.report_wheel_travel(0.0)
        hw.step(t + k * 0.02)
    s = hw.controller.board_status()
    assert s.motor_right_status & St.STALL and not s.motor_left_status & St.STALL
    assert abs(hw.controller.take_wheel_travel()[0] - hw.controller.wheel_travel[0]) < 1e-9


def test_can_frame_loss_is_detected_and_odometry_survives_it(hw: Hardware) -> None:
    right, _ = motors(hw)
    hw.faults.inject(Fault(K.CAN_LOSS, None, 0.2), 0.0)
    t, events = run(hw, 0.0, 0.5)
    assert any(e.kind == "frames_lost" for e in events)
    assert hw.controller.frames_lost[Node.MOTOR_RIGHT] > 0
    assert hw.controller.board_status().motor_right_status & St.FRAMES_LOST
    assert hw.conditions.rng is not None and hw.ports[Node.IOBOARD].stats.dropped_tx > 0
    hw.faults.clear(K.CAN_LOSS, None, t)
    hw.controller.set_wheel_velocities(300, 300)
    t, _ = run(hw, t, t + 2.0)
    assert not hw.controller.board_status().motor_right_status & St.FRAMES_LOST
    # absolute ticks: a lost frame costs no distance (E-HW-007)
    assert hw.controller.wheel_travel[0] == pytest.approx(right.true_travel, abs=300 * 0.02 + 0.1)


def test_total_loss_on_one_sender_looks_like_a_dead_node(hw: Hardware) -> None:
    hw.faults.inject(Fault(K.CAN_LOSS, "GYROBOARD", 1.0), 0.0)
    run(hw, 0.0, 1.0)
    s = hw.controller.board_status()
    assert s.gyro_status & St.NODE_TIMEOUT and not s.radar_status & St.NODE_TIMEOUT


def test_can_delay(hw: Hardware) -> None:
    right, _ = motors(hw)
    hw.controller.add_listening_id(0x120)
    hw.faults.inject(Fault(K.CAN_DELAY, "MOTOR_RIGHT", 0.1), 0.0)
    hw.controller.set_wheel_velocities(500, 500)
    t, _ = run(hw, 0.0, 1.0)
    records = hw.controller.get_can_messages(delete=True)
    assert records[0].timestamp == pytest.approx(0.12)  # sent at 0.02, on the bus 0.1 s later
    lag = right.true_travel - hw.controller.wheel_travel[0]
    assert lag == pytest.approx(500 * 0.12, abs=500 * 0.03)  # the odometry trails by the delay
    hw.faults.inject(Fault(K.CAN_DELAY, "MOTOR_RIGHT", 2.0), t)  # longer than the node timeout
    run(hw, t, t + 1.0)
    assert hw.controller.board_status().motor_right_status & St.NODE_TIMEOUT


def test_controller_bus_off(hw: Hardware) -> None:
    right, left = motors(hw)
    t = drive(hw)
    hw.faults.inject(Fault(K.BUS_OFF), t)
    t, events = run(hw, t, t + 1.0)
    assert [e.kind for e in events][:1] == ["bus_off"] and "node_lost" in [e.kind for e in events]
    s = hw.controller.board_status()
    words = [v for f, v in s.as_fields().items() if f.endswith("_status")]
    assert all(w & (St.BUS_OFF | St.NODE_TIMEOUT) == St.BUS_OFF | St.NODE_TIMEOUT for w in words)
    assert right.wheel_velocity == 0 == left.wheel_velocity  # the setpoint watchdog (E-HW-008)
    assert right.status() & St.SETPOINT_TIMEOUT
    assert hw.controller.drive_fault() == "CAN bus-off"
    hw.faults.clear(K.BUS_OFF, now=t)
    t, events = run(hw, t, t + 0.5)
    assert "bus_on" in [e.kind for e in events]
    assert hw.controller.board_status().motor_left_status == St.FRAMES_LOST  # the counters jumped meanwhile
    assert right.wheel_velocity == pytest.approx(400)  # setpoints flow again
    run(hw, t, t + 1.0)
    assert hw.controller.board_status().motor_left_status == 0


def test_node_bus_off(hw: Hardware) -> None:
    hw.faults.inject(Fault(K.BUS_OFF, "IOBOARD"), 0.0)
    run(hw, 0.0, 1.0)
    s = hw.controller.board_status()
    assert s.io_status & St.NODE_TIMEOUT and not s.io_status & St.BUS_OFF and s.relay_status == 0


def test_battery_drop(hw: Hardware) -> None:
    io = hw.boards[Node.IOBOARD]
    assert isinstance(io, IoBoard)
    hw.faults.inject(Fault(K.BATTERY, None, 22_000.0, ramp=2.0), 0.0)
    t, _ = run(hw, 0.0, 1.0)
    mid = hw.controller.board_status().io_battery_voltage
    assert 23_000 < mid < 24_500  # halfway down the ramp
    t, _ = run(hw, t, t + 1.5)
    s = hw.controller.board_status()
    assert s.io_battery_voltage == 22_000 and s.io_status & St.LOW_BATTERY
    assert hw.init(t).results[Node.IOBOARD].errors == 0x01
    hw.faults.clear(K.BATTERY, now=t)
    run(hw, t, t + 0.2)
    assert hw.controller.board_status().io_battery_voltage == 25_600


def test_fault_duration_and_schedule(hw: Hardware) -> None:
    hw.faults.schedule(0.5, Fault(K.UNPLUG, "RELAYBOARD"), duration=1.0)
    t, events = run(hw, 0.0, 0.4)
    assert hw.ports[Node.RELAYBOARD].connected and hw.faults.describe()["scheduled"]
    t, events = run(hw, t, 1.2)
    assert not hw.ports[Node.RELAYBOARD].connected
    assert any("fault inject" in e.text for e in events) and any(e.kind == "node_lost" for e in events)
    t, events = run(hw, t, 1.6)
    assert hw.ports[Node.RELAYBOARD].connected and hw.faults.active == {}
    assert any("after its duration" in e.text for e in events)


@pytest.mark.parametrize(
    "fault",
    [
        Fault(K.UNPLUG),
        Fault(K.UNPLUG, "NOT_A_NODE"),
        Fault(K.OVERTEMP, "IOBOARD", 90.0),
        Fault(K.CAN_LOSS, None, 1.5),
        Fault(K.EMERGENCY_STOP, "RELAYBOARD"),
        Fault(K.SERIAL_SILENCE),  # the fixture platform has no scanner
    ],
)
def test_bad_faults_are_refused(hw: Hardware, fault: Fault) -> None:
    with pytest.raises(FaultError):
        hw.faults.inject(fault, 0.0)
    assert hw.faults.active == {}


def test_a_fault_on_a_board_that_is_not_fitted_is_refused(make_hw: Any) -> None:
    hw = make_hw(nodes=[Node.MOTOR_RIGHT, Node.MOTOR_LEFT])
    with pytest.raises(FaultError, match="not fitted"):
        hw.faults.inject(Fault(K.UNPLUG, "GYROBOARD"), 0.0)


def test_serial_corruption_is_rejected_and_counted(make_hw: Any) -> None:
    ranges = [1000.0 + i for i in range(541)]
    hw = make_hw(scanner="sim://", scan_source=lambda now: ranges)
    hw.faults.inject(Fault(K.SERIAL_CORRUPT, None, 0.3), 0.0)
    run(hw, 0.0, 4.0)
    assert hw.scanner is not None and hw.scan_reader is not None
    d = hw.scan_reader.decoder
    assert hw.scanner.corrupted > 10
    assert d.telegrams == hw.scanner.sent - hw.scanner.corrupted  # every corrupt one rejected, no good one lost
    assert hw.scanner.corrupted - 3 <= d.crc_errors <= hw.scanner.corrupted  # (a hit in the header is just skipped)
    assert d.lost >= hw.scanner.corrupted - 2  # gaps in the telegram numbers (not at the ends)
    assert hw.scan_reader.last_scan is not None
    assert hw.scan_reader.last_scan.ranges_mm[:3] == (1000, 1000, 1000)
    assert hw.scanner_ok


def test_serial_silence(make_hw: Any) -> None:
    hw = make_hw(scanner="sim://")
    t, _ = run(hw, 0.0, 0.5)
    assert hw.scanner_ok and hw.scan_reader is not None and hw.scan_reader.decoder.telegrams == 13
    hw.faults.inject(Fault(K.SERIAL_SILENCE), t)
    t, events = run(hw, t, t + 0.5)
    assert [e.kind for e in events] == ["scanner_lost"] and not hw.scanner_ok
    hw.faults.clear(K.SERIAL_SILENCE, now=t)
    t, events = run(hw, t, t + 0.2)
    assert [e.kind for e in events] == ["scanner_back"] and hw.scanner_ok
