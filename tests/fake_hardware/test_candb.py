"""spec/can/pltf.dbc: the identifier scheme, senders, receivers, cycle times and units (erratum E-HW-001/002)."""

from __future__ import annotations

import random

import pytest

from pltf.fake_hardware import candb
from pltf.fake_hardware.candb import APPLICATION_IDS, PREFIX, Node

DB = candb.database()
COMMON = ("Probe", "ProbeReply", "SelfTest", "SelfTestResult", "Shutdown")


def test_every_message_follows_the_identifier_scheme() -> None:
    names = [m.name for m in DB.messages]
    assert len(names) == len(set(names))
    for m in DB.messages:
        node = Node(m.frame_id >> 8)
        function = m.frame_id & 0xFF
        assert m.name.startswith(PREFIX[node] + "_"), m.name
        assert not m.is_extended_frame and m.frame_id not in APPLICATION_IDS
        to_node = 0x01 <= function <= 0x1F and function not in (0x02, 0x04)
        sender, receiver = ("PLTF_CTRL", node.name) if to_node else (node.name, "PLTF_CTRL")
        assert m.senders == [sender], m.name
        assert all(s.receivers == [receiver] for s in m.signals), m.name
        assert 0x01 <= function <= 0x05 or 0x10 <= function <= 0x2F, m.name
        assert m.length <= 8


@pytest.mark.parametrize("node", list(Node))
def test_every_node_has_probe_self_test_and_shutdown(node: Node) -> None:
    for offset, function in enumerate(COMMON, start=1):
        assert candb.message_for(node, function).frame_id == node * 0x100 + offset


def test_data_from_the_nodes_is_cyclic_and_commands_are_not() -> None:
    for m in DB.messages:
        function = m.frame_id & 0xFF
        assert (m.cycle_time is not None) == (function >= 0x20), m.name
    assert candb.cycle_time(candb.message_for(Node.MOTOR_RIGHT, "Encoder")) == 0.02
    assert candb.cycle_time(candb.message_for(Node.IOBOARD, "Battery")) == 0.1


def test_units_match_the_status_telegram() -> None:
    units = {(m.name, s.name): s.unit for m in DB.messages for s in m.signals}
    assert units["IoBoard_Battery", "Voltage"] == "mV"
    assert units["UsBoard_Distances1_4", "Distance1"] == "mm"
    assert units["RadarBoard_Velocity", "Velocity4"] == "mm/s"
    assert units["MotorLeft_Setpoint", "Velocity"] == "mm/s"
    assert units["MotorLeft_State", "Temperature"] == "degC"
    assert units["GyroBoard_Angle", "Angle"] == "rad"
    assert units["MotorRight_Encoder", "Ticks"] == "ticks"


def test_build_clamps_to_the_signal_range_and_decode_accepts_long_frames() -> None:
    msg = candb.message_for(Node.MOTOR_RIGHT, "Setpoint")
    frame = candb.build(msg, {"Velocity": 100_000, "Counter": 3}, 1.5)
    assert frame.timestamp == 1.5 and not frame.is_extended_id
    assert candb.decode(msg, frame) == {"Velocity": 32767, "Counter": 3}
    frame.data = bytearray(frame.data) + b"\0" * 5
    assert candb.decode(msg, frame) == {"Velocity": 32767, "Counter": 3}
    frame.data = frame.data[:2]
    assert candb.decode(msg, frame) is None


def test_node_of() -> None:
    assert candb.node_of(0x120) == Node.MOTOR_RIGHT
    assert candb.node_of(0x701) is None


def test_the_precompiled_codec_equals_cantools_on_every_message() -> None:
    """Random frames, more than its caches hold: the same bytes and values as cantools, before and after the
    codec stops looking frames up (random values never repeat)."""
    rng = random.Random(5)
    for msg in DB.messages:
        codec = candb.codec(msg)
        for _ in range(2 * candb.FrameCodec.CACHE + 10):
            values = {}
            for s in msg.signals:
                lo, hi = float(s.minimum), float(s.maximum)
                value = rng.uniform(lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo))
                values[s.name] = round(value) if s.scale == 1 and rng.random() < 0.5 else value
            clamped = {
                k: min(max(v, float(msg.get_signal_by_name(k).minimum)), float(msg.get_signal_by_name(k).maximum))
                for k, v in values.items()
            }
            data = codec.encode(values)
            assert data == msg.encode(clamped, scaling=True, strict=False), msg.name
            assert codec.decode(data) == msg.decode(data, decode_choices=False), msg.name
        if sum(s.length for s in msg.signals) >= 24:  # frames that cannot repeat by chance
            assert codec._cached == [False, False], msg.name
        frame = candb.build(msg, {s.name: s.maximum for s in msg.signals}, 1.5)
        assert frame.timestamp == 1.5 and frame.arbitration_id == msg.frame_id and len(frame.data) == msg.length


def test_a_repeating_frame_stays_cached() -> None:
    msg = candb.message_for(Node.IOBOARD, "Battery")
    codec = candb.FrameCodec(msg)
    signals = {s.name: 0 for s in msg.signals}
    for k in range(3 * candb.FrameCodec.CACHE):
        signals[msg.signals[0].name] = k % 8
        data = codec.encode(signals)
        assert codec.decode(data) == msg.decode(data, decode_choices=False)
    assert codec._cached == [True, True] and len(codec._encoded) == 8
