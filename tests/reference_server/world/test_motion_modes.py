"""Motion modes (guide 4.3): velocity and its watchdog, joystick decay, break/stop/halt, the collision check,
walls that stop the body, and determinism (same seed + same commands -> the same trajectory)."""

from __future__ import annotations

import math

import pytest

from pltf.reference_server.world import MapGeometry
from tests.reference_server.world.conftest import CORRIDOR_WEST, DT, Sim, geometry_of, make_sim, room

OPEN = geometry_of(room(20000, 20000))


def _moved(a: tuple[float, float, float], b: tuple[float, float, float]) -> float:
    return math.hypot(a[0] - b[0], a[1] - b[1])


def test_velocity_is_kept_until_the_watchdog_expires() -> None:
    sim = make_sim(OPEN, (2000.0, 10000.0, 0.0))
    sim.world.command_velocity(500.0, 0.0, 0.0)
    sim.run(0.45)  # VelWatchdogTime 500 ms
    assert sim.world.motion.v > 300 and sim.world.active
    sim.run(0.1)
    assert "velocity watchdog expired: platform stopped" in sim.events
    assert sim.run(1.0, lambda w: not w.active and w.motion.v == 0.0)
    stopped = sim.world.truth
    sim.run(1.0)
    assert sim.world.truth == stopped


def test_velocity_resent_within_the_watchdog_keeps_driving() -> None:
    sim = make_sim(OPEN, (2000.0, 10000.0, 0.0))
    for _ in range(10):
        sim.world.command_velocity(500.0, 0.0, sim.now)
        sim.run(0.3)
    assert sim.world.active and sim.world.measured[0] == pytest.approx(500.0, abs=20)
    assert sim.world.truth[0] > 2000 + 500 * 2.5


def test_wheel_velocities_through_dist_wheels() -> None:
    sim = make_sim(OPEN, (10000.0, 10000.0, 0.0))
    for _ in range(5):
        sim.world.command_wheels(300.0, 100.0, sim.now)
        sim.run(0.2)
    assert sim.world.motion.v == pytest.approx(200.0) and sim.world.motion.w == pytest.approx(200.0 / 430.0)
    assert sim.world.setpoints == pytest.approx((300.0, 100.0))
    v, w = sim.world.measured  # from one period's noisy encoder travel
    assert v == pytest.approx(200.0, abs=10) and w == pytest.approx(200.0 / 430.0, abs=0.1)


def test_joystick_velocity_decays_after_the_timeout() -> None:
    sim = make_sim(OPEN, (2000.0, 10000.0, 0.0))
    sim.world.command_velocity(400.0, 0.1, 0.0, kind="joy")
    sim.run(1.9)  # JoySoftVelTimeout 2000 ms
    assert sim.world.motion.v == pytest.approx(400.0)
    assert sim.run(2.0, lambda w: w.motion.v == 0.0 and w.motion.w == 0.0)
    assert sim.now < 2.0 + 400 / 800 + 0.2  # decelerated with MaxTransAcc, not abruptly... nor slowly
    sim.run(0.1)
    assert not sim.world.active


@pytest.mark.parametrize("how", ["hold", "halt"])
def test_break_and_emergency_halt_stop_within_one_control_period(how: str) -> None:
    sim = make_sim(OPEN, (2000.0, 10000.0, 0.0))
    sim.world.move_to((15000.0, 10000.0, 0.0))
    sim.run(4.0)
    assert sim.world.motion.v > 500
    getattr(sim.world, how)()
    before = sim.world.truth
    sim.run(DT)
    assert sim.world.truth == before  # not a millimetre in the next period
    sim.run(1.0)
    assert sim.world.truth == before
    assert sim.world.active is (how == "hold")  # BREAK keeps the command, the emergency stop ends it
    if how == "hold":
        sim.world.resume()
        assert sim.until_idle(60.0) and sim.world.target_reached


def test_stop_ends_the_command_with_a_ramp() -> None:
    sim = make_sim(OPEN, (2000.0, 10000.0, 0.0))
    sim.world.move_to((15000.0, 10000.0, 0.0))
    sim.run(4.0)
    v = sim.world.motion.v
    sim.world.stop()
    assert not sim.world.active
    sim.run(DT)
    assert 0 < sim.world.motion.v < v
    assert sim.run(3.0, lambda w: w.motion.v == 0.0)
    assert not sim.world.target_reached


def test_the_collision_check_stops_in_front_of_a_wall(office: MapGeometry) -> None:
    sim = make_sim(office, (3000.0, 10000.0, math.pi / 2))  # facing the corridor's north wall, 1.2 m away
    for _ in range(20):
        sim.world.command_velocity(300.0, 0.0, sim.now)
        sim.run(0.2)
    assert sim.world.collision and sim.world.motion.collision and not sim.world.contact
    front = sim.world.truth[1] + sim.world.footprint.front
    assert 11200 - front >= 300 - 30 - 0.2 * 300  # CollLaserMinDist, laser noise, one scan period of travel
    assert sim.contacts == 0


def test_without_the_collision_check_a_wall_stops_the_body(office: MapGeometry) -> None:
    sim = make_sim(office, (3000.0, 10000.0, math.pi / 2), CollCheckEnabled=False)
    for _ in range(20):
        sim.world.command_velocity(300.0, 0.0, sim.now)
        sim.run(0.2)
    assert sim.world.collision and sim.world.contact and sim.contacts > 0
    front = sim.world.truth[1] + sim.world.footprint.front
    assert 11200 - 1.0 <= front <= 11200  # at the wall, not through it
    assert abs(sim.world.estimate[1] - sim.world.truth[1]) < 30  # blocked wheels do not roll (motion_api)


def test_the_same_seed_and_commands_give_the_same_trajectory(office: MapGeometry) -> None:
    def run(seed: int) -> list[tuple[float, float, float]]:
        sim = make_sim(office, CORRIDOR_WEST, seed=seed)
        sim.world.set_mouse_obstacle((9000.0, 10000.0))
        sim.world.move_to((19000.0, 12200.0, math.pi / 2))
        sim.run(8.0)
        sim.world.set_mouse_obstacle(None)
        sim.world.command_velocity(300.0, 0.2, sim.now, kind="joy")
        sim.run(3.0)
        return sim.trace

    first = run(5)
    assert run(5) == first
    assert run(6) != first


def _beside_a_post() -> Sim:
    """A post beside the rear, behind the laser's field of view: turning right swings the rear into it."""
    sim = make_sim(OPEN, (10000.0, 10000.0, 0.0))
    sim.world.set_obstacle("post", (10000.0 - 250.0, 10000.0 + 270.0 + 150.0, 60.0))
    sim.world.sense(0.0, force=True)
    return sim


def _turn(sim: Sim, w: float, seconds: float) -> None:
    """MODE_MOTION_VEL on the spot at ``w`` rad/s, the command renewed every 0.2 s (the watchdog)."""
    for _ in range(round(seconds / 0.2)):
        sim.world.command_velocity(0.0, w, sim.now)
        sim.run(0.2)


def test_a_turn_on_the_spot_does_not_swing_the_rear_into_what_only_the_ultrasonic_sees() -> None:
    sim = _beside_a_post()
    _turn(sim, -0.5, 2.0)
    # the rear corner (sweep 504 mm) would reach the post after some 20 degrees: held back within the look-ahead
    assert sim.contacts == 0 and sim.world.collision and abs(sim.world.truth[2]) < math.radians(15.0)
    _turn(sim, 0.5, 2.0)  # the other way round is free
    assert sim.world.truth[2] > 0.5 and sim.contacts == 0


def test_a_turn_held_back_by_an_echo_goes_on_once_the_echo_is_gone() -> None:
    # the turn check remembers its verdict on the echoes while they stay the same: a new echo must end it
    sim = _beside_a_post()
    _turn(sim, -0.5, 1.0)
    held_at = sim.world.truth[2]
    assert sim.world.collision and abs(held_at) < math.radians(15.0)
    sim.world.set_obstacle("post", None)
    _turn(sim, -0.5, 1.0)
    assert sim.world.truth[2] < held_at - 0.3 and not sim.world.collision and sim.contacts == 0


def _turn_beside_a_wall(gap: float, w: float) -> tuple[float, bool]:
    """Turn on the spot by 90 degrees (``w`` rad/s) beside a wall parallel to the heading, ``gap`` mm to the right
    of the wheel axis' midpoint (the default footprint: rear corners 504 mm from it): (turned rad, collision)."""
    y0 = 10000.0
    sim = make_sim(geometry_of([*room(20000, 20000), (5000.0, y0 - gap, 15000.0, y0 - gap)]), (10000.0, y0, 0.0))
    sim.world.sense(0.0, force=True)
    for _ in range(25):
        sim.world.command_velocity(0.0, w, sim.now)
        sim.run(0.2)
        if abs(sim.world.truth[2]) >= math.pi / 2:
            break
    assert sim.contacts == 0
    return abs(sim.world.truth[2]), sim.world.collision


def test_a_turn_on_the_spot_beside_a_wall_the_rear_clears_is_not_held_back() -> None:
    # seen 2026-11-26 in the editor test under load: at station Bravo the right side's rear sensor read ~230 mm
    # of a wall 596 mm from the axis, under the old fixed 250 mm threshold, and the turn stalled although the
    # corner passes 92 mm clear of the wall; the job drove on 70 degrees off its path and ended stuck in a door
    turned, held = _turn_beside_a_wall(596.0, 0.5)
    assert turned >= math.pi / 2 and not held


def test_a_turn_on_the_spot_that_would_swing_the_rear_into_a_wall_is_held_back_the_other_way_is_free() -> None:
    turned, held = _turn_beside_a_wall(470.0, 0.5)  # left: the right rear corner swings out to 504 mm
    assert held and turned < math.radians(45.0)
    turned, held = _turn_beside_a_wall(470.0, -0.5)  # right: that corner swings away from the wall
    assert turned >= math.pi / 2 and not held
