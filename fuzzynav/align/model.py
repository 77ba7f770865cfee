"""Error model of the alignment filters (stationary base, ENU, phi-angle form).

``d(dv)/dt = -2 [w_ie x] dv + [f^n x] phi + C_bn nabla``,
``d(phi)/dt = -[w_ie x] phi - C_bn eps`` (``C_calc = (I - [phi x]) C_true``), the biases
``nabla`` (accelerometer) and ``eps`` (gyro) random constants in the body frame.  The
10-state filter of paper 002 keeps the east and north rows of ``dv`` and the body x, y
accelerometer biases (at a level attitude these are the ENU ones up to the heading); the
12-state velocity-matching form keeps all three.  Measurement: the velocity of the
(open-loop) solution against the zero velocity of the base, ``H = [I 0]``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from fuzzynav import units
from fuzzynav.align.alignment_states import LAYOUT_12, AlignLayout
from fuzzynav.nav import attitude, earth

__all__ = ["AlignNoise", "system_matrix", "TAYLOR_TERMS", "transition", "measurement_matrix"]


@dataclass(frozen=True)
class AlignNoise:
    """Initial sigmas, process and measurement noise of an alignment filter (SI).

    Defaults are paper 002's: P0 = diag((0.05 m/s)^2 x2, (1 deg)^2 x3, (100 ug)^2 x2,
    (0.02 deg/h)^2 x3), Q0 = diag((50 ug)^2 x2, (0.01 deg/h)^2 x3, 0 x5) per second,
    R0 = diag((0.05 m/s)^2 x2), T = 1 s.  (The paper's P0 lists the gyro terms before the
    accelerometer ones, against its own state order; they are assigned here by meaning.)

    Attributes
    ----------
    vel_sigma_mps, att_sigma_rad, accel_bias_sigma_mps2, gyro_bias_sigma_rps : float
        Initial 1-sigma of each block.
    accel_noise_mps2_psqrts, gyro_noise_rps_psqrts : float
        White-noise densities driving velocity and attitude (Q per second).
    meas_sigma_mps : float
        Velocity measurement sigma (R0).
    period_s : float
        Filter period T.
    """

    vel_sigma_mps: float = 0.05
    att_sigma_rad: float = 1.0 * units.DEG
    accel_bias_sigma_mps2: float = 100.0 * units.UG
    gyro_bias_sigma_rps: float = 0.02 * units.DPH
    accel_noise_mps2_psqrts: float = 50.0 * units.UG
    gyro_noise_rps_psqrts: float = 0.01 * units.DPH
    meas_sigma_mps: float = 0.05
    period_s: float = 1.0

    def _blocks(self, layout: AlignLayout, values: dict) -> np.ndarray:
        out = np.zeros(layout.n)
        for name, _ in layout.blocks:
            out[layout[name]] = values[name]
        return out

    def p0(self, layout: AlignLayout) -> np.ndarray:
        """Initial covariance (diagonal matrix)."""
        return np.diag(self._blocks(layout, {
            "vel": self.vel_sigma_mps, "att": self.att_sigma_rad,
            "accel_bias": self.accel_bias_sigma_mps2,
            "gyro_bias": self.gyro_bias_sigma_rps}) ** 2)

    def qd(self, layout: AlignLayout) -> np.ndarray:
        """Discrete process noise over one period, ``diag(q) T``."""
        return np.diag(self._blocks(layout, {
            "vel": self.accel_noise_mps2_psqrts, "att": self.gyro_noise_rps_psqrts,
            "accel_bias": 0.0, "gyro_bias": 0.0}) ** 2 * self.period_s)

    def r0(self, layout: AlignLayout) -> np.ndarray:
        """Measurement noise of the velocity measurement."""
        return np.eye(layout.size("vel")) * self.meas_sigma_mps**2


def _selection(layout: AlignLayout) -> np.ndarray:
    """Indices of ``layout``'s states in :data:`LAYOUT_12` (first axes of each block)."""
    return np.concatenate([np.arange(LAYOUT_12[name].start, LAYOUT_12[name].start + size)
                           for name, size in layout.blocks])


def system_matrix(layout: AlignLayout, C_bn, f_n, lat_rad) -> np.ndarray:
    """Continuous-time ``A`` at attitude ``C_bn`` and specific force ``f_n`` [m/s^2].

    ``C_bn`` (..., 3, 3) and ``f_n`` (..., 3) may carry leading epoch axes; ``A`` then has
    them too, (..., n, n).
    """
    L = LAYOUT_12
    C_bn = np.asarray(C_bn, dtype=float)
    w = attitude.skew(earth.omega_ie_n(lat_rad))
    A = np.zeros(C_bn.shape[:-2] + (L.n, L.n))
    A[..., L.vel, L.vel] = -2.0 * w
    A[..., L.vel, L.att] = attitude.skew(np.asarray(f_n, dtype=float))
    A[..., L.vel, L.accel_bias] = C_bn
    A[..., L.att, L.att] = -w
    A[..., L.att, L.gyro_bias] = -C_bn
    sel = _selection(layout)
    return A[..., sel[:, None], sel[None, :]]


#: Taylor terms of ``expm(A T)``: ``A^k`` shrinks by ``w_ie T`` per power beyond the second
#: (the only large entries are the ``g`` and ``C_bn`` couplings into velocity), so the
#: sixth term is below 1e-12 of the first for T of seconds
TAYLOR_TERMS = 6


def transition(layout, C_bn, f_n, lat_rad, period_s) -> np.ndarray:
    """``Phi = expm(A T)`` by its Taylor series (a 10x10 Pade ``expm`` costs ~50x more).

    Vectorised over leading epoch axes of ``C_bn`` (..., 3, 3) and ``f_n`` (..., 3): the
    whole run's transitions in one call, (..., n, n).
    """
    AT = system_matrix(layout, C_bn, f_n, lat_rad) * period_s
    Phi = np.broadcast_to(np.eye(AT.shape[-1]), AT.shape).copy()
    term = Phi.copy()
    for k in range(1, TAYLOR_TERMS + 1):
        term = term @ AT / k
        Phi = Phi + term
    return Phi


def measurement_matrix(layout: AlignLayout) -> np.ndarray:
    """``H = [I 0]``: the velocity block."""
    H = np.zeros((layout.size("vel"), layout.n))
    H[:, layout.vel] = np.eye(layout.size("vel"))
    return H
