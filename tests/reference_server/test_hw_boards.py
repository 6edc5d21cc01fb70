"""Every board of the fake hardware driven through the socket API of a real server: the frames on the virtual CAN
bus decode with spec/can/pltf.dbc, and GET_STATUS / GET_CAN_MESSAGES report what the boards sent."""

from __future__ import annotations

import re
from pathlib import Path

import can

from pltf.fake_hardware import ALL_NODES, Node, St, candb
from pltf.reference_server.world.model import factory as world_factory
from pltf.spec.codec import REQUESTS
from tests.reference_server.conftest import (
    EM_ACTIVE,
    OP_NOT_INIT,
    OP_READY,
    STATUS_BOARDS,
    Client,
    Control,
    ServerProcess,
    rig,
)
from tests.reference_server.helpers import wait_for

PROBED = [candb.message_for(n, "Probe").name for n in ALL_NODES]


def test_connect_probes_every_node_and_init_runs_the_self_test(data_dir: Path) -> None:
    with rig(data_dir, up=False) as r:
        st = r.status()
        assert all(getattr(st, f) == St.ABSENT for f in STATUS_BOARDS)  # erratum E-HW-003: before the connect
        assert r.sniffer.names(0.1) == set()  # erratum E-HW-004: the boards are silent until probed
        r.send("CMD_CONNECT_TO_PLTF")
        for node in ALL_NODES:
            r.sniffer.wait(candb.message_for(node, "ProbeReply").name, lambda s, n=node: s["NodeId"] == n)
        assert set(PROBED) <= {n for n, _, _ in r.sniffer.heard}
        r.wait_log("all CAN nodes answer")
        st = r.wait(lambda s: all(getattr(s, f) != St.ABSENT for f in STATUS_BOARDS), "every board connected")
        assert st.operation_state == OP_NOT_INIT and st.initialized == 0
        assert st.motor_right_status & St.NOT_INITIALIZED and st.motor_right_status & St.BRAKE_ENGAGED
        r.send("CMD_INIT_PLTF")
        for node in ALL_NODES:
            assert r.sniffer.wait(candb.message_for(node, "SelfTestResult").name)["Passed"] == 1
        for motor in ("MotorRight_Brake", "MotorLeft_Brake"):  # erratum E-HW-005: released after the self test
            assert r.sniffer.wait(motor)["Release"] == 1
        st = r.wait(lambda s: s.operation_state == OP_READY, "Ready")
        r.wait_log("self test passed")
        st = r.wait(lambda s: all(getattr(s, f) == 0 for f in STATUS_BOARDS), "every board well")
        assert st.initialized == 1 and st.io_battery_voltage > 23000


def test_a_missing_node_is_reported_not_faked(data_dir: Path) -> None:
    fitted = [n for n in ALL_NODES if n != Node.GYROBOARD]
    with rig(data_dir, nodes=fitted, expected=ALL_NODES) as r:  # bring_up: the self test waits for the probe
        r.wait_log("CAN nodes missing: GYROBOARD")
        st = r.status()
        assert (st.gyro_status, st.gyro_accel, st.gyro_angle, st.gyro_temp) == (St.ABSENT, (0, 0, 0), 0, 0)
        assert st.io_status == 0 and st.initialized == 1
        assert "GyroBoard_SelfTest" not in {n for n, _, _ in r.sniffer.collect()}


def test_wheel_setpoints_go_out_as_frames_and_odometry_comes_back_from_the_encoders(data_dir: Path) -> None:
    with rig(data_dir) as r:
        x0 = r.status().est_x
        r.run_vel()
        move = ("CMD_MOVE_VEL_WHEEL", {"vel_right": 300, "vel_left": 200})
        st = r.wait(lambda s: s.est_x - x0 > 100 and s.est_angle > 0, "driven forward, turning left", keep=move)
        assert r.sniffer.wait("MotorRight_Setpoint", lambda s: s["Velocity"] == 300)
        assert r.sniffer.wait("MotorLeft_Setpoint", lambda s: s["Velocity"] == 200)
        enc = r.sniffer.wait("MotorRight_Encoder", lambda s: s["Velocity"] == 300)
        assert enc["Status"] == 0
        # the command kept alive while the odometry is read: the sniffer's waits above take wall time, and on a
        # loaded machine the velocity watchdog stopped the platform meanwhile (a clean-clone run at load 10: 154 mm/s)
        r.wait(lambda p: 200 <= p.vel_trans <= 300 and p.vel_rot > 0, "odometry", keep=move, ask="CMD_GET_POSITION")
        pose = r.control("pose")
        assert abs(pose["estimate"][0] - pose["true"][0]) < 5  # no slip: the encoders measure the true travel
        assert st.motor_right_status == 0 and st.motor_left_status == 0


def test_set_brake_engages_and_releases_one_motor(data_dir: Path) -> None:
    with rig(data_dir) as r:
        r.sniffer.mark()
        r.send("CMD_SET_BRAKE", motor=1, state=0)  # guide 6.3: 0 brake enabled
        assert r.sniffer.wait("MotorRight_Brake")["Release"] == 0
        r.wait(lambda s: s.motor_right_status & St.BRAKE_ENGAGED and not s.motor_left_status, "right brake on")
        r.sniffer.mark()
        r.send("CMD_SET_BRAKE", motor=2, state=0)
        r.send("CMD_SET_BRAKE", motor=1, state=1)
        assert r.sniffer.wait("MotorLeft_Brake")["Release"] == 0
        assert r.sniffer.wait("MotorRight_Brake")["Release"] == 1
        r.wait(lambda s: s.motor_left_status & St.BRAKE_ENGAGED and not s.motor_right_status, "left brake on only")


def test_set_digout_switches_io_outputs_and_relays(data_dir: Path) -> None:
    with rig(data_dir) as r:
        r.send("CMD_SET_DIGOUT", board=0, channel=3, value=1)
        assert r.sniffer.wait("IoBoard_DigOut") == {"Channel": 3, "Value": 1}
        r.wait(lambda s: s.io_digital_out == 0b1000, "IO output 3 on")
        assert r.sniffer.wait("IoBoard_Digital", lambda s: s["DigOut"] == 0b1000)
        r.send("CMD_SET_DIGOUT", board=1, channel=2, value=1)
        assert r.sniffer.wait("RelayBoard_RelayOut") == {"Channel": 2, "Value": 1}
        assert r.sniffer.wait("RelayBoard_State", lambda s: s["Relays"] == 0b100)
        r.send("CMD_SET_DIGOUT", board=1, channel=8, value=1)  # erratum E-HW-010: the relay board has 8 relays
        r.wait_log("CMD_SET_DIGOUT refused")
        assert "RelayBoard_RelayOut" not in r.sniffer.names(0.1)


def test_ultrasonic_start_and_stop(data_dir: Path) -> None:
    with rig(data_dir, motion=world_factory(1)) as r:  # the world's walls give echoes
        r.send("CMD_START_ULTRASONIC", active_channels=0b101)
        assert r.sniffer.wait("UsBoard_Start")["ActiveMask"] == 0b101
        st = r.wait(lambda s: s.us_status & St.MEASURING and s.us_distance[0] > 0, "measuring")
        assert st.us_distance[1] == 0 and st.us_distance[2] > 0 and not any(st.us_distance[3:])  # E-HW-012
        assert r.sniffer.wait("UsBoard_Distances1_4", lambda s: s["Distance1"] > 0)["Distance2"] == 0
        r.sniffer.mark()
        r.send("CMD_STOP_ULTRASONIC")
        assert r.sniffer.wait("UsBoard_Stop") == {}
        st = r.wait(lambda s: not s.us_status & St.MEASURING, "stopped")
        assert st.us_distance == (0,) * 16


def test_gyro_and_radar_boards_report_from_the_bus(data_dir: Path) -> None:
    with rig(data_dir) as r:
        r.run_vel()
        turn = ("CMD_MOVE_VEL", {"vel_trans": 0, "vel_rot": 500})
        st = r.wait(lambda s: s.gyro_angle > 1000, "the gyro angle grows (rad * 10000)", keep=turn)
        assert r.sniffer.wait("GyroBoard_Angle", lambda s: s["Angle"] > 0.05)["Angle"] > 0.05
        assert st.gyro_status == 0 and st.gyro_accel[2] > 90_000  # gravity, m/s^2 * 10000
        assert st.radar_status == 0 and st.radar_velocity == (0, 0, 0, 0)  # nothing moves in the world
        assert r.sniffer.wait("RadarBoard_Velocity") == {f"Velocity{i}": 0 for i in range(1, 5)}


def test_can_listening_ids_buffer_the_real_traffic_with_timestamps(data_dir: Path) -> None:
    with rig(data_dir) as r:
        encoder = candb.message_for(Node.MOTOR_RIGHT, "Encoder")
        r.send("CMD_ADD_CAN_LISTENING_ID", can_id=encoder.frame_id)
        r.send("CMD_ADD_CAN_LISTENING_ID", can_id=0x701)
        r.get("CMD_GET_CAN_MESSAGES", delete=1)
        kept = r.wait_messages(lambda m: len(m) >= 5, delete=0)
        stamps = [m[0] for m in kept]
        assert stamps == sorted(stamps) and all(0 < t < r.status().timestamp / 1000 + 0.1 for t in stamps)
        assert {m[1] for m in kept} == {encoder.frame_id}
        for _, _, data in kept:  # the payload decodes with the database
            assert set(encoder.decode(bytes(data)[: encoder.length])) == {"Ticks", "Velocity", "Status", "Counter"}
        again = r.get("CMD_GET_CAN_MESSAGES", delete=1).messages  # keep: still there, then deleted
        assert list(again[: len(kept)]) == list(kept)
        newer = r.get("CMD_GET_CAN_MESSAGES", delete=0).messages
        assert not set(newer) & set(again)
        r.sniffer.mark()
        r.send("CMD_SEND_CAN_MESSAGE", can_id=0x701, data=(1, 2, 3, 4, 5, 6, 7, 8))
        assert r.sniffer.wait("APP")["data"] == bytes(range(1, 9))  # on the bus, not received back (E-HW-013)
        r.sniffer.bus.send(can.Message(arbitration_id=0x701, data=b"\x09" * 8, is_extended_id=False))
        got = r.wait_messages(lambda m: any(x[1] == 0x701 for x in m), delete=0)
        assert [x[2] for x in got if x[1] == 0x701] == [(9,) * 8]
        r.send("CMD_REMOVE_CAN_LISTENING_ID", can_id=encoder.frame_id)
        r.get("CMD_GET_CAN_MESSAGES", delete=1)
        r.sniffer.mark()
        r.sniffer.wait("MotorRight_Encoder", lambda s: s["Counter"] % 3 == 0)
        r.sniffer.mark()
        r.sniffer.wait("MotorRight_Encoder")
        assert r.get("CMD_GET_CAN_MESSAGES", delete=1).messages == ()


def test_shutdown_takes_the_bus_down(data_dir: Path) -> None:
    with rig(data_dir) as r:
        r.sniffer.mark()
        r.send("CMD_SHUTDOWN_PLTF")
        for node in ALL_NODES:
            r.sniffer.wait(candb.message_for(node, "Shutdown").name)
        st = r.wait(lambda s: s.operation_state == OP_NOT_INIT, "not initialized")
        assert all(getattr(st, f) == St.ABSENT for f in STATUS_BOARDS)
        assert r.sniffer.names(0.2) == set()  # every board is silent again (E-HW-004)
        r.bring_up()  # and the platform comes back
        r.wait(lambda s: all(getattr(s, f) == 0 for f in STATUS_BOARDS), "every board back")


def test_the_command_line_server_has_the_hardware_and_its_control_port(tmp_path: Path) -> None:
    srv = ServerProcess(tmp_path / "data", tmp_path / "log", "--control-port", "0", "--motion", "ideal", hardware=True)
    try:
        port = int(wait_for(lambda: re.findall(r"control channel started at port (\d+)", srv.log()), timeout=10)[0])
        control = Control(port)
        with Client(srv.ports[0]) as client:
            client.send(REQUESTS.CMD_CONNECT_TO_PLTF())
            wait_for(lambda: control("status")["bus_up"] and client.status().io_status != St.ABSENT, timeout=10)
            control("estop press")
            assert wait_for(lambda: client.status().emergency_state == EM_ACTIVE, timeout=10)
        control.close()
    finally:
        srv.kill()
    assert "CAN nodes" in srv.log()
