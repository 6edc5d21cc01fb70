"""Odometry drift, correction against the map, covariance, "localization lost" after a kidnap, SET_FRM_PLTF."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pltf.conformance_tests.cases._common import FAR_OFFSET
from pltf.reference_server.world import MapGeometry
from pltf.reference_server.world.localization import Localization
from tests.reference_server.world.conftest import CORRIDOR_WEST, Sim, make_sim


def _error(sim: Sim) -> float:
    (x, y, _), (ex, ey, _) = sim.world.truth, sim.world.estimate
    return math.hypot(x - ex, y - ey)


def _drive_corridor(sim: Sim, seconds: float = 20.0) -> float:
    """Drive east along the corridor in MODE_MOTION_VEL; the largest position error seen."""
    worst = 0.0
    for k in range(int(seconds)):
        sim.world.command_velocity(800.0, 0.0, sim.now)
        sim.run(1.0)
        worst = max(worst, _error(sim))
        assert k < 60
    return worst


def test_localization_keeps_odometry_drift_bounded(office: MapGeometry) -> None:
    """Over four seeds (one seed's odometry may happen to drift little: its two wheel scale errors nearly
    equal, its noise walk short): with LocalLocalization every run stays within 40 mm; without it the
    odometry's error is on average more than three times larger."""
    on, off = [], []
    for seed in range(1, 5):
        on.append(_drive_corridor(make_sim(office, CORRIDOR_WEST, seed=seed, CollCheckEnabled=False)))
        off.append(
            _drive_corridor(make_sim(office, CORRIDOR_WEST, seed=seed, CollCheckEnabled=False, LocalLocalization=False))
        )
    assert max(on) < 40.0
    assert sum(off) > 3 * sum(on), (on, off)


def test_covariance_grows_with_odometry_and_shrinks_with_scans() -> None:
    loc = Localization()
    before = loc.deviations()
    for _ in range(100):
        loc.predict(20.0, 20.0, 430.0)
    grown = loc.deviations()
    assert grown[0] > before[0] and grown[2] >= before[2]
    import random

    for k in range(20):
        loc.correct(1.0, (loc.x, loc.y, loc.angle), 0.1 * k, random.Random(k), False)
    assert loc.deviations()[0] < grown[0]
    major, minor, angle, axis = loc.deviations()
    assert major >= minor >= 0 and angle > 0 and -math.pi / 2 < axis <= math.pi / 2


def test_kidnapped_the_platform_is_lost_until_set_frm_pltf(office: MapGeometry) -> None:
    sim = make_sim(office, CORRIDOR_WEST)
    sim.run(1.0)
    assert not sim.world.loc.lost
    sim.world.kidnap((19000.0, 15000.0, 1.0))  # into an office room
    sim.run(1.0)
    assert sim.world.loc.lost
    assert _error(sim) > 10000  # and nothing pulled the estimate over
    sim.world.set_estimate((19100.0, 14950.0, 1.02))  # CMD_SET_FRM_PLTF close to the truth
    sim.run(0.5)
    assert not sim.world.loc.lost and _error(sim) < 50.0


def test_a_set_frame_near_the_truth_is_pulled_back_and_one_far_off_stays(office: MapGeometry) -> None:
    """CMD_SET_FRM_PLTF 250 mm off: the next matching scan corrects it towards the truth (within the capture
    range). FAR_OFFSET (the frame the conformance cases set and read back) is beyond it: the estimate stays
    exactly where it was put."""
    sim = make_sim(office, CORRIDOR_WEST)
    sim.run(1.0)
    x, y, a = sim.world.truth
    sim.world.set_estimate((x + 250.0, y, a))
    sim.run(0.3)
    assert _error(sim) < 50.0
    dx, dy, milli_deg = FAR_OFFSET
    far = (x + dx, y + dy, a + math.radians(milli_deg / 1000.0))
    sim.world.set_estimate(far)
    sim.run(1.0)
    assert sim.world.estimate == pytest.approx(far, abs=1e-9)


def test_global_localization_finds_a_lost_platform(office: MapGeometry) -> None:
    sim = make_sim(office, CORRIDOR_WEST, GlobalLocalization=True)
    sim.run(0.5)
    sim.world.kidnap((19000.0, 15000.0, 1.0))
    assert sim.run(5.0, lambda w: w.loc.lost)
    assert sim.run(5.0, lambda w: not w.loc.lost)
    assert _error(sim) < 60.0


def test_without_a_map_nothing_is_corrected_and_nothing_is_lost() -> None:
    sim = make_sim(None, (0.0, 0.0, 0.0))
    sim.world.command_velocity(500.0, 0.2, 0.0)
    sim.run(0.4)
    sim.world.kidnap((5000.0, 0.0, 0.0))
    sim.run(1.0)
    assert not sim.world.loc.lost
    assert np.isfinite(sim.world.loc.deviations()).all()


def test_the_estimate_of_a_platform_at_rest_does_not_jitter(office: MapGeometry) -> None:
    sim = make_sim(office, CORRIDOR_WEST)
    sim.run(2.0)
    assert sim.world.estimate == CORRIDOR_WEST  # placed exactly at boot, never moved
    sim.world.set_estimate((1020.0, 10015.0, 0.01))  # CMD_SET_FRM_PLTF a little off: corrected although at rest
    sim.run(1.0)
    settled = sim.world.estimate
    assert _error(sim) < 15.0
    sim.run(2.0)
    assert sim.world.estimate == settled


@pytest.mark.parametrize("seed", range(5))
def test_deviations_are_the_eigen_decomposition_of_the_position_covariance(seed: int) -> None:
    """The closed form the status telegram uses, against numpy's eigh: deviations are the square roots of the
    eigenvalues, the principal axis the major eigenvector's direction in (-pi/2, pi/2]."""
    rng = np.random.default_rng(seed)
    loc = Localization()
    for _ in range(50):
        m = rng.normal(size=(3, 3)) * rng.uniform(1, 300)
        loc.cov = m @ m.T
        vals, vecs = np.linalg.eigh(loc.cov[:2, :2])
        major, minor, angle, axis = loc.deviations()
        assert major == pytest.approx(math.sqrt(vals[1]), rel=1e-9)
        assert minor == pytest.approx(math.sqrt(max(vals[0], 0.0)), rel=1e-6, abs=1e-6)
        assert angle == pytest.approx(math.sqrt(loc.cov[2, 2]))
        assert -math.pi / 2 < axis <= math.pi / 2
        direction = np.array([math.cos(axis), math.sin(axis)])
        assert abs(direction @ vecs[:, 1]) == pytest.approx(1.0, abs=1e-9)  # parallel to the major eigenvector
    loc.cov = np.diag([4.0, 4.0, 1.0])  # isotropic: no principal axis, pi/2 (eigh's identity eigenvectors)
    assert loc.deviations() == (2.0, 2.0, 1.0, math.pi / 2)
