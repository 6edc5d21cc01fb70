"""The platform's belief about its pose: odometry, a covariance, scan matching against the map, "lost".

Rules (erratum E-MOT-004):
- ``predict(dr, dl)`` integrates the measured wheel travel (encoder frames) and grows the covariance like a
  differential-drive EKF: each wheel's travel variance is ``ODO_VAR`` mm^2 per mm driven.
- ``correct(score, truth, rng)`` runs once per laser scan while LocalLocalization is on and a map is
  active. ``score`` is the share of beams whose measured range agrees with the range expected from the
  ESTIMATED pose on the map (computed by the caller, a real comparison of two scans). A scan that fits
  (score >= ``MATCH``) corrects the estimate with a Kalman update; the matcher's result is modelled as the
  true pose plus seeded noise, but only within its capture range (``CAPTURE_POS``, ``CAPTURE_ANGLE``): beyond
  it a matcher would lock onto the nearby local optimum, so nothing is corrected. ``LOST_AFTER`` scans in a
  row that do not fit make the localization lost (a kidnap: the true pose jumped); a fitting scan ends it.
- GlobalLocalization on and lost: after ``GLOBAL_DELAY`` s of scans the platform finds itself on the whole
  map (estimate = truth + noise).
- ``set_estimate`` (CMD_SET_FRM_PLTF) replaces the estimate and resets the covariance.
- Standing still (less than 1 mm of odometry since the last correction) with a position deviation below
  ``STILL_SIGMA``, a fitting scan corrects nothing: the estimate of a platform at rest does not jitter.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

import numpy as np

from pltf.reference_server.world.geometry import F64

ODO_VAR = 0.005  # mm^2 per mm of wheel travel (more than the simulated encoders' noise: the scale error too)
MEAS_POS = 10.0  # mm: standard deviation of a matched scan's position
MEAS_ANGLE = math.radians(0.3)
CAPTURE_POS = 400.0  # mm
CAPTURE_ANGLE = math.radians(12.0)
MATCH = 0.5  # share of agreeing beams for a scan to fit
LOST_AFTER = 5  # scans
GLOBAL_DELAY = 2.0  # s
INITIAL_SIGMA = (30.0, 30.0, math.radians(1.0))
STILL_SIGMA = 15.0  # mm: standing still, a scan corrects only an estimate less certain than this


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def _initial() -> F64:
    return np.diag(np.square(np.array(INITIAL_SIGMA)))


@dataclass
class Localization:
    x: float = 0.0
    y: float = 0.0
    angle: float = 0.0
    cov: F64 = field(default_factory=_initial)
    lost: bool = False
    misfits: int = 0
    lost_since: float | None = None
    last_score: float = 1.0
    moved: float = 0.0  # mm and rad of odometry since the last correction

    def set_estimate(self, x: float, y: float, angle: float, exact: bool = False) -> None:
        """A new estimate: a frame someone gives (INITIAL_SIGMA), or ``exact`` (the start pose at boot)."""
        self.x, self.y, self.angle = x, y, _wrap(angle)
        self.cov = _initial() / (100.0 if exact else 1.0)
        self.lost, self.misfits, self.lost_since, self.moved = False, 0, None, 0.0

    def predict(self, dr: float, dl: float, track: float) -> None:
        """Odometry: the pose moves by the measured wheel travel; P = F P F' + G Q G' (plain floats: 50 Hz)."""
        d, da = 0.5 * (dr + dl), (dr - dl) / track
        mid = self.angle + 0.5 * da
        c, s = math.cos(mid), math.sin(mid)
        self.x += d * c
        self.y += d * s
        self.angle = _wrap(self.angle + da)
        self.moved += abs(d) + 500.0 * abs(da)
        (p00, p01, p02), (_, p11, p12), (_, _, p22) = self.cov.tolist()
        a, b = -d * s, d * c  # F = [[1, 0, a], [0, 1, b], [0, 0, 1]]
        r00, r01, r02 = p00 + a * p02, p01 + a * p12, p02 + a * p22
        r11, r12 = p11 + b * p12, p12 + b * p22
        n00, n01, n11 = r00 + a * r02, r01 + b * r02, r11 + b * r12
        k = d / (2.0 * track)  # G = d(x, y, angle) / d(dr, dl)
        g = ((0.5 * c - k * s, 0.5 * c + k * s), (0.5 * s + k * c, 0.5 * s - k * c), (1.0 / track, -1.0 / track))
        qr, ql = ODO_VAR * abs(dr) + 1e-9, ODO_VAR * abs(dl) + 1e-9

        def gq(i: int, j: int) -> float:
            return g[i][0] * g[j][0] * qr + g[i][1] * g[j][1] * ql

        m02, m12, m22 = r02 + gq(0, 2), r12 + gq(1, 2), p22 + gq(2, 2)
        m00, m01, m11 = n00 + gq(0, 0), n01 + gq(0, 1), n11 + gq(1, 1)
        self.cov = np.array([[m00, m01, m02], [m01, m11, m12], [m02, m12, m22]])

    def correct(
        self, score: float, truth: tuple[float, float, float], now: float, rng: random.Random, global_on: bool
    ) -> None:
        self.last_score = score
        if score < MATCH:
            self.misfits += 1
            if self.misfits >= LOST_AFTER and not self.lost:
                self.lost, self.lost_since = True, now
            if self.lost and global_on and self.lost_since is not None and now - self.lost_since >= GLOBAL_DELAY:
                self.set_estimate(
                    truth[0] + rng.gauss(0, MEAS_POS),
                    truth[1] + rng.gauss(0, MEAS_POS),
                    truth[2] + rng.gauss(0, MEAS_ANGLE),
                )
            return
        self.misfits, self.lost, self.lost_since = 0, False, None
        if self.moved < 1.0 and math.sqrt(max(self.cov[0, 0], self.cov[1, 1])) < STILL_SIGMA:
            return  # standing still and sure: the estimate stands still too
        self.moved = 0.0
        ex, ey, ea = truth[0] - self.x, truth[1] - self.y, _wrap(truth[2] - self.angle)
        if math.hypot(ex, ey) > CAPTURE_POS or abs(ea) > CAPTURE_ANGLE:
            return  # locked onto a local optimum near the estimate: fits, corrects nothing
        z = np.array([ex + rng.gauss(0, MEAS_POS), ey + rng.gauss(0, MEAS_POS), ea + rng.gauss(0, MEAS_ANGLE)])
        r = np.diag([MEAS_POS**2, MEAS_POS**2, MEAS_ANGLE**2]) / max(score, 1e-3)
        k = self.cov @ np.linalg.inv(self.cov + r)
        dx = k @ z
        self.x += float(dx[0])
        self.y += float(dx[1])  # floats: the pose stays plain Python numbers
        self.angle = _wrap(self.angle + float(dx[2]))
        self.cov = (np.eye(3) - k) @ self.cov
        self.cov = 0.5 * (self.cov + self.cov.T)

    def deviations(self) -> tuple[float, float, float, float]:
        """Status telegram: principal and minor deviation (mm), angle deviation and principal axis (rad).

        The eigen decomposition of the 2x2 position block in closed form (numpy's ``eigh`` took 50 us of each
        status recomputation): eigenvalues m +- d, principal axis atan2(2b, a - c) / 2 in (-pi/2, pi/2]; an
        isotropic block (no principal axis) reports pi/2, as ``eigh``'s identity eigenvectors did."""
        a, b, c = float(self.cov[0, 0]), float(self.cov[0, 1]), float(self.cov[1, 1])
        m, d = 0.5 * (a + c), math.hypot(0.5 * (a - c), b)
        major, minor = math.sqrt(max(m + d, 0.0)), math.sqrt(max(m - d, 0.0))
        axis = math.pi / 2 if b == 0.0 and a == c else 0.5 * math.atan2(2.0 * b, a - c)
        return major, minor, math.sqrt(max(float(self.cov[2, 2]), 0.0)), axis
