"""Scenarios over TCP with the CAN boards in the loop (the server's default, ``pltf serve``), on a stepped clock:
CMD_BREAK and the emergency stop act within one control cycle on what the platform commands, and the body then
stops as fast as the motor boards brake (erratum E-MOT-013), and a move still reaches its target."""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator
from typing import Any

import pytest

from tests.reference_server.conftest import Client
from tests.reference_server.world.scenarios import (
    MotionMode,
    OperationState,
    R,
    SteppedServer,
    command,
    running_stepped,
    settled_at,
    stepped_poll,
)

PERIOD = 0.02
RAMP = 2000.0  # mm/s^2: a motor board ramps to a new setpoint (fake_hardware MotorParams.acc_limit)
BRAKE = 5000.0  # mm/s^2: a motor board without power brakes (MotorParams.brake_decel)


@pytest.fixture
def hw_client(hardware_server: SteppedServer) -> Iterator[Client]:
    with Client(hardware_server.ports[0]) as c:
        yield c


def stopping_distance(v: float, decel: float) -> float:
    """How far a wheel at ``v`` rolls braking at ``decel``, plus two periods until the boards act."""
    return v * v / (2.0 * decel) + v * 2 * PERIOD


def test_a_move_reaches_its_target_through_the_motor_boards(hardware_server: SteppedServer, hw_client: Client) -> None:
    running_stepped(hardware_server, hw_client, MotionMode.MODE_MOTION_AUTOMATIC)
    command(hw_client, R.CMD_MOVE_ABS(x=5000, y=12200, angle=90000))  # into the kitchen, through its door
    goal = (5000.0, 12200.0, math.pi / 2)
    trace = stepped_poll(hardware_server, hw_client, 30.0, until=settled_at(goal, pos=40.0, angle_deg=2.5))
    assert settled_at(goal, pos=40.0, angle_deg=2.5)(trace[-1]), trace[-1]


def test_break_freezes_the_command_at_once_and_the_boards_ramp_down(
    hardware_server: SteppedServer, hw_client: Client
) -> None:
    c = hw_client
    running_stepped(hardware_server, c, MotionMode.MODE_MOTION_AUTOMATIC)
    command(c, R.CMD_MOVE_ABS(x=9000, y=10000, angle=0))
    stepped_poll(hardware_server, c, 8.0, until=lambda s: s.vel_trans >= 900)
    before = c.status()
    command(c, R.CMD_BREAK())
    after: list[Any] = []
    for _ in range(round(1.0 / PERIOD)):
        hardware_server.advance(PERIOD)
        after.append(c.status())
    assert after[0].operation_state == OperationState.ST_OP_BREAKED
    assert len({(s.cmd_x, s.cmd_y) for s in after}) == 1  # the commanded frame stands from the first cycle on
    v0 = before.vel_trans
    ramp_time = v0 / RAMP
    stopped = [s for s in after if s.vel_trans == 0]
    # the encoder frames report the stop a few cycles late
    assert stopped and stopped[0].timestamp / 1000.0 - before.timestamp / 1000.0 <= ramp_time + 5 * PERIOD
    # the zero setpoint reaches the boards over CAN in the next cycle, the encoder frames come a cycle later:
    # from then on the wheels only slow down
    assert all(b.vel_trans <= a.vel_trans + 10 for a, b in itertools.pairwise(after[2:]))
    assert after[-1].est_x - before.est_x <= stopping_distance(v0, RAMP) + 30
    command(c, R.CMD_CONTINUE())
    goal = (9000.0, 10000.0, 0.0)
    trace = stepped_poll(hardware_server, c, 20.0, until=settled_at(goal, pos=40.0, angle_deg=2.5))
    assert settled_at(goal, pos=40.0, angle_deg=2.5)(trace[-1])


def test_the_emergency_circuit_brakes_the_wheels(hardware_server: SteppedServer, hw_client: Client) -> None:
    c = hw_client
    running_stepped(hardware_server, c, MotionMode.MODE_MOTION_VEL)
    for _ in range(15):
        command(c, R.CMD_MOVE_VEL(vel_trans=800, vel_rot=0))
        hardware_server.advance(0.1)
    before = c.status()
    assert before.vel_trans >= 750

    def press() -> None:
        link = hardware_server.platform.hardware
        assert link is not None
        link.hw.circuit.press()  # the button on the platform: the circuit opens, the motors lose power

    hardware_server.call(press)
    after: list[Any] = []
    for _ in range(round(0.6 / PERIOD)):
        hardware_server.advance(PERIOD)
        after.append(c.status())
    assert after[0].emergency_state == 1 and after[0].operation_state == OperationState.ST_OP_READY
    stopped = [s for s in after if s.vel_trans == 0]
    assert stopped and stopped[0].timestamp / 1000.0 - before.timestamp / 1000.0 <= 800 / BRAKE + 5 * PERIOD
    assert after[-1].est_x - before.est_x <= stopping_distance(800, BRAKE) + 30
    command(c, R.CMD_MOVE_VEL(vel_trans=800, vel_rot=0))  # refused while the stop is active
    hardware_server.advance(1.0)
    assert c.status().vel_trans == 0
