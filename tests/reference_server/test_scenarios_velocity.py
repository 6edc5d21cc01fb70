"""Scenarios over TCP with a clock the test advances (``SteppedServer``): the velocity modes, the watchdog, and
how fast CMD_BREAK and the emergency stop act (guide 4.3 Mode Velocity, Mode Joystick (Software); 6.3
CMD_BREAK). Each command lands at a known control period, so "within one control cycle" is checked exactly."""

from __future__ import annotations

import math
from collections.abc import Iterator

import pytest

from tests.reference_server.conftest import Client
from tests.reference_server.world.scenarios import (
    START,
    MotionMode,
    OperationState,
    R,
    SteppedServer,
    command,
    running,
    sample,
    stepped_poll,
)

PERIOD = 0.02  # s: one control cycle (50 Hz)


@pytest.fixture
def client(stepped_server: SteppedServer) -> Iterator[Client]:
    with Client(stepped_server.ports[0]) as c:
        stepped_server.advance(0.2)  # the first scans
        yield c


def position(c: Client) -> tuple[float, float, float, float, float]:
    p = c.request(R.CMD_GET_POSITION())
    return p.x, p.y, p.angle, p.vel_trans, p.vel_rot


def mean_velocity(srv: SteppedServer, c: Client, periods: int = 10) -> tuple[float, float]:
    """The measured velocities (odometry, with encoder noise) averaged over ``periods`` control cycles."""
    vs, ws = [], []
    for _ in range(periods):
        srv.advance(PERIOD)
        *_, v, w = position(c)
        vs.append(v)
        ws.append(w)
    return sum(vs) / periods, sum(ws) / periods


def test_move_vel_drives_at_the_commanded_velocity(stepped_server: SteppedServer, client: Client) -> None:
    running(client, MotionMode.MODE_MOTION_VEL)
    for _ in range(20):  # 2 s at 400 mm/s and 0.2 rad/s, refreshed well within the 500 ms watchdog
        command(client, R.CMD_MOVE_VEL(vel_trans=400, vel_rot=200))
        stepped_server.advance(0.1)
    x, y, a, *_ = position(client)
    v, w = mean_velocity(stepped_server, client)
    assert v == pytest.approx(400, abs=5) and w == pytest.approx(0.2, abs=0.01)
    # 2 s on an arc of 2 m radius, less what the acceleration costs (MaxRotAcc 1.5 rad/s^2, MaxTransAcc 800 mm/s^2)
    assert a == pytest.approx(0.2 * 2.0 - 0.5 * 0.2 * (0.2 / 1.5), abs=0.03)
    assert math.hypot(x - START[0], y - START[1]) == pytest.approx(400 * 2.0 - 0.5 * 400 * (400 / 800), abs=40)


def test_move_vel_wheel_sets_both_wheels(stepped_server: SteppedServer, client: Client) -> None:
    running(client, MotionMode.MODE_MOTION_VEL)
    for _ in range(15):
        command(client, R.CMD_MOVE_VEL_WHEEL(vel_right=300, vel_left=100))  # v 200 mm/s, w 200/430 rad/s
        stepped_server.advance(0.1)
    v, w = mean_velocity(stepped_server, client)
    # the status beside the figures: a clean-clone run at load 9 saw v = 0.0 here once, with no clue why
    assert v == pytest.approx(200, abs=5) and w == pytest.approx(200 / 430, abs=0.01), (v, w, client.status())


def test_velocity_watchdog_stops_the_platform(stepped_server: SteppedServer, client: Client) -> None:
    running(client, MotionMode.MODE_MOTION_VEL)
    command(client, R.CMD_MOVE_VEL(vel_trans=300, vel_rot=0))  # once, then nothing: VelWatchdogTime 500 ms
    stepped_server.advance(0.38)  # at 300 mm/s after 0.375 s (MaxTransAcc 800 mm/s^2)
    # driving until the watchdog expires
    assert mean_velocity(stepped_server, client, 5)[0] == pytest.approx(300, abs=6)
    # expired at 0.5 s; braking from 300 mm/s at MaxTransAcc 800 mm/s^2 takes 0.375 s
    trace = stepped_poll(stepped_server, client, 0.48, every=PERIOD)
    assert trace[-1].vel_trans == 0 and trace[-20].vel_trans > 0
    rest = stepped_poll(stepped_server, client, 2.0, every=0.1)
    assert all(s.vel_trans == 0 for s in rest)
    assert abs(rest[-1].x - rest[0].x) <= 5  # the estimate may settle by a scan's correction, no more
    assert any("watchdog" in line for (line,) in client.request(R.CMD_GET_DEBUG_DATA()).protocol_queue)


def test_joystick_soft_decelerates_to_zero_when_commands_stop(stepped_server: SteppedServer, client: Client) -> None:
    running(client, MotionMode.MODE_MOTION_JOYSOFT)
    for _ in range(10):
        command(client, R.CMD_MOVE_VEL(vel_trans=400, vel_rot=0))
        stepped_server.advance(0.1)
    assert mean_velocity(stepped_server, client)[0] == pytest.approx(400, abs=5)
    trace = stepped_poll(stepped_server, client, 1.5, every=0.1)  # JoySoftVelTimeout 2 s: still driving
    assert all(s.vel_trans > 350 for s in trace)
    trace = stepped_poll(stepped_server, client, 2.0, every=0.1)  # then down to zero (0.5 s at MaxTransAcc)
    assert trace[-1].vel_trans == 0
    assert min(s.vel_trans for s in trace) >= 0  # decelerates, does not reverse


def test_joystick_hard_moves_nothing(stepped_server: SteppedServer, client: Client) -> None:
    running(client, MotionMode.MODE_MOTION_JOYHARD)
    for _ in range(10):
        command(client, R.CMD_MOVE_VEL(vel_trans=400, vel_rot=0), R.CMD_MOVE_ABS(x=4000, y=10000, angle=0))
        stepped_server.advance(0.1)
    x, y, _, v, _ = position(client)
    assert (x, y, v) == (START[0], START[1], 0.0)


def test_break_stops_within_one_control_cycle_and_continue_resumes(
    stepped_server: SteppedServer, client: Client
) -> None:
    running(client, MotionMode.MODE_MOTION_AUTOMATIC)
    command(client, R.CMD_MOVE_ABS(x=8000, y=10000, angle=0))
    trace = stepped_poll(stepped_server, client, 6.0, until=lambda s: s.vel_trans >= 900)
    assert trace[-1].vel_trans >= 900  # cruising at IpoTransVel
    command(client, R.CMD_BREAK())
    assert client.status().operation_state == OperationState.ST_OP_BREAKED
    stepped_server.advance(PERIOD)
    stopped = position(client)
    assert stopped[3:] == (0.0, 0.0)  # the very next control cycle measures no motion
    stepped_server.advance(2.0)
    later = position(client)
    assert later[3:] == (0.0, 0.0)
    assert math.dist(later[:2], stopped[:2]) <= 10  # the body stands (the estimate settles by a scan at most)
    command(client, R.CMD_CONTINUE())
    done = stepped_poll(stepped_server, client, 15.0, until=lambda s: bool(s.target_reached))
    assert done[-1].target_reached and math.dist((done[-1].x, done[-1].y), (8000, 10000)) <= 25


def test_emergency_stop_halts_within_one_control_cycle(stepped_server: SteppedServer, client: Client) -> None:
    running(client, MotionMode.MODE_MOTION_VEL)
    for _ in range(10):
        command(client, R.CMD_MOVE_VEL(vel_trans=600, vel_rot=0))
        stepped_server.advance(0.1)
    assert mean_velocity(stepped_server, client)[0] == pytest.approx(600, abs=5)
    command(client, R.CMD_MOVE_VEL(vel_trans=600, vel_rot=0))
    stepped_server.press_emergency(True)
    s = client.status()
    assert (s.emergency_state, s.operation_state, s.vel_trans) == (1, OperationState.ST_OP_READY, 0)
    stepped_server.advance(PERIOD)
    stopped = position(client)
    assert stopped[3:] == (0.0, 0.0)
    command(client, R.CMD_MOVE_VEL(vel_trans=600, vel_rot=0))  # refused: not Running
    stepped_server.advance(2.0)
    later = position(client)
    assert later[3:] == (0.0, 0.0) and math.dist(later[:2], stopped[:2]) <= 10
    stepped_server.press_emergency(False)
    stepped_server.advance(1.5)  # the safety system's reset (1 s)
    assert sample(client).vel_trans == 0
    assert client.status().emergency_state == 0
