"""The small ideal differential drive and the roadmap router."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from pltf.reference_server.kinematics import Drive, Frame, Roadmap, normalize, relative_to_world
from pltf.reference_server.motion_api import advance_ideal
from pltf.spec.documents import DocumentKind, validate_document
from pltf.spec.parameters import ParameterStore

DT = 0.02
ROADMAP = Path(__file__).resolve().parents[2] / "fixtures" / "roadmaps" / "office.rm"


def run(drive: Drive, seconds: float, start: float = 0.0) -> float:
    now = start
    for _ in range(round(seconds / DT)):
        now += DT
        advance_ideal(drive, now, DT)
    return now


@pytest.fixture
def params() -> ParameterStore:
    return ParameterStore()


def test_normalize() -> None:
    assert normalize(3 * math.pi) == pytest.approx(math.pi)
    assert normalize(-math.pi) == pytest.approx(math.pi)
    assert normalize(-0.5) == -0.5


def test_relative_to_world() -> None:
    f = relative_to_world(Frame(1000, 0, math.pi / 2), Frame(500, 0, math.pi / 2))
    assert (f.x, f.y, f.angle) == pytest.approx((1000, 500, math.pi))


def test_wheel_velocities_drive_straight_and_turn(params: ParameterStore) -> None:
    drive = Drive(params.get)
    drive.command_wheels(300, 300, 0.0)
    for k in range(50):  # resend within the watchdog, 1 s
        drive.command_wheels(300, 300, k * DT)
        advance_ideal(drive, (k + 1) * DT, DT)
    assert drive.v == pytest.approx(300)
    assert drive.w == 0
    assert 200 < drive.pose.x < 300
    drive.command_wheels(100, -100, 1.0)
    run(drive, 0.4, 1.0)
    assert drive.w == pytest.approx(200 / float(params.get("DistWheels")))


def test_velocity_watchdog_stops_the_platform(params: ParameterStore) -> None:
    drive = Drive(params.get)
    drive.command_velocity(500, 0, 0.0)
    watchdog = float(params.get("VelWatchdogTime")) / 1000
    run(drive, watchdog - 0.1)
    assert drive.active and drive.v > 0
    run(drive, 2.0, watchdog - 0.1)
    assert not drive.active
    assert drive.v == 0


def test_joystick_keeps_the_velocity_then_decays(params: ParameterStore) -> None:
    drive = Drive(params.get)
    drive.command_velocity(400, 0.2, 0.0, kind="joy")
    timeout = float(params.get("JoySoftVelTimeout")) / 1000
    run(drive, timeout - 0.1)
    assert drive.v == pytest.approx(400)
    run(drive, 2.0, timeout - 0.1)
    assert (drive.v, drive.w) == (0, 0)
    assert not drive.active


def test_velocities_are_limited(params: ParameterStore) -> None:
    drive = Drive(params.get)
    drive.command_velocity(1e6, -1e6, 0.0)
    run(drive, 0.4)
    assert drive._v_cmd == params.get("MaxTransVel")
    assert drive._w_cmd == -params.get("MaxRotVel")


@pytest.mark.parametrize("target", [Frame(1000, 0, 0), Frame(-800, 600, math.pi / 2), Frame(0, 0, -2.0)])
def test_path_reaches_the_target_within_tolerance(params: ParameterStore, target: Frame) -> None:
    drive = Drive(params.get)
    drive.command_path([target])
    for _ in range(2000):
        run(drive, DT)
        if drive.target_reached:
            break
    assert drive.target_reached and not drive.active
    assert math.hypot(drive.pose.x - target.x, drive.pose.y - target.y) <= float(params.get("TargetReachedTolPos"))
    assert abs(normalize(drive.pose.angle - target.angle)) <= math.radians(float(params.get("TargetReachedTolAngle")))
    assert (drive.v, drive.w) == (0, 0)


def test_a_new_path_preempts_and_break_holds(params: ParameterStore) -> None:
    drive = Drive(params.get)
    drive.command_path([Frame(5000, 0, 0)])
    now = run(drive, 1.0)
    drive.command_path([Frame(0, 0, 0)])
    assert drive.remaining_path() == [Frame(0, 0, 0)]
    drive.hold()
    now = run(drive, 2.0, now)
    held = drive.pose.frame()
    now = run(drive, 0.5, now)
    assert drive.pose.frame() == held and drive.v == 0
    drive.resume()
    run(drive, 20, now)
    assert drive.target_reached


def test_ipo_velocity_parameter_is_used(params: ParameterStore) -> None:
    params.set_text("IpoTransVel", "200")
    drive = Drive(params.get)
    drive.command_path([Frame(3000, 0, 0)])
    run(drive, 3.0)
    assert drive.v == pytest.approx(200)


def test_roadmap_route_is_shortest_and_uses_edge_points() -> None:
    roadmap = Roadmap(validate_document(DocumentKind.ROADMAP, ROADMAP.read_bytes()))
    kitchen = roadmap.find("Kitchen")
    assert kitchen is not None and kitchen.frame.angle == pytest.approx(math.pi / 2)
    assert roadmap.find("r_kitchen") == kitchen  # by id as a fallback
    assert roadmap.find("Nowhere") is None
    start = roadmap.nearest(2100, 9900)
    assert start is not None and start.name == "Corridor_W"
    frames = roadmap.route(start.id, kitchen.id)
    assert frames is not None
    assert [(f.x, f.y) for f in frames] == [(1000, 10000), (5000, 10000), (5000, 11200), (5000, 12200)]
    assert frames[-1].angle == pytest.approx(math.pi / 2)
    back = roadmap.route(kitchen.id, start.id)  # edges are travelled both ways (erratum E-XML-003)
    assert back is not None
    assert [(f.x, f.y) for f in back] == [(5000, 12200), (5000, 11200), (5000, 10000), (1000, 10000)]


def test_unreachable_station() -> None:
    xml = (
        b'<roadmap><stations><station id="a" name="A"><point x="0" y="0"/></station>'
        b'<station id="b" name="B"><point x="10" y="0"/></station></stations><edges/></roadmap>'
    )
    roadmap = Roadmap(validate_document(DocumentKind.ROADMAP, xml))
    assert roadmap.route("a", "b") is None
    assert roadmap.route("a", "a") == [Frame(0, 0, 0)]
