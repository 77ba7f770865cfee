"""Coarse alignment: attitude from gravity and the earth rate, with its uncertainty.

The package's one coarse alignment, on any IMU log (``time_s``, ``dtheta_b``, ``dv_b``):

* :func:`level` -- pitch and roll from the mean specific force over a rest, which points up:
  ``f_b = |f| (-cos p sin r, sin p, cos p cos r)`` (RFU body); the start from recorded data
  (:mod:`fuzzynav.realdata.coarse_align`) levels with it and takes the heading from the
  motion, the alignment (:mod:`fuzzynav.align.chain`) with :func:`analytic`;
* :func:`body_chain` -- the body attitude relative to its start, ``C_b0_b``, from the gyro
  increments (quaternion products, numba);
* :func:`analytic` (stationary base; PSINS ``alignsb``): the mean specific force ``f_b``
  and rate ``w_b`` over the window are gravity and the earth rate seen in the body;
  ``C_bn`` takes the body triad built on ``f`` and ``f x w`` to the navigation one built on
  ``(0, 0, g)`` and ``(0, w cos L, w sin L)`` (TRIAD: gravity alone sets the level).
* :func:`inertial_frame` (disturbed base; PSINS ``aligni0``): sway averages out of the
  *integrated* specific force in a frame that does not rotate.  The gyros carry the body
  into the frozen initial body frame ``b0``, ``V_b0(t) = int C_b0_b f_b dt``; gravity seen
  from the frozen initial navigation frame ``n0`` turns about the earth axis,
  ``V_n0(t) = int exp([w_ie^n x] s) (0, 0, g) ds``.  Integrated once more, ``S = int V dt``,
  a periodic base velocity stays bounded (centimetres) while the earth-rate bend of ``S``
  grows as ``t^3`` (with ``V`` itself a 5-cm/s surge costs about a degree of azimuth after
  two minutes).  ``C_n0_b0`` is the rotation best taking ``S_n0`` into ``S_b0`` over the
  window (Wahba's problem, SVD) and
  ``C_bn(t) = exp(-[w_ie^n x] t) C_n0_b0^T C_b0_b(t)``.

The uncertainty is the bias- and noise-limited one of a stationary window of length T
(first order): tilt ``sigma = sqrt(b_a^2 + N_a^2 / T) / g``; azimuth
``sigma = sqrt(b_g^2 + N_g^2 / T) / (w_ie cos L)`` plus ``tan L`` times the tilt (the
north accelerometer's bias tilts the earth-rate triad), with ``b`` the a-priori bias per
axis and ``N`` the white-noise density of each triad.
"""
from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from fuzzynav.errors import FuzzynavError
from fuzzynav.nav import attitude, earth
from fuzzynav.nav.earth import OMEGA_IE
from fuzzynav.nav.strapdown import quat_mul, rv2q

__all__ = ["CoarseResult", "uncertainty", "level", "body_chain", "analytic", "inertial_frame"]

#: slack of a window given in seconds on a sample grid (the alignment's windows end on a
#: sample whose time carries rounding): samples within it of the ends are inside
GRID_SLACK_S = 1e-9


@dataclass(frozen=True)
class CoarseResult:
    """Attitude from coarse alignment.

    Attributes
    ----------
    C_bn : ndarray (3, 3)
        Attitude at the end of the window.
    att : ndarray (3,)
        The same as (pitch, roll, heading) [rad].
    cov_phi : ndarray (3, 3)
        Covariance of the misalignment ``phi`` (ENU, [rad^2]).
    time_s : float
        Epoch of the attitude (end of the window) [s].
    method : str
    """

    C_bn: np.ndarray
    att: np.ndarray
    cov_phi: np.ndarray
    time_s: float
    method: str

    @property
    def sigma_phi(self) -> np.ndarray:
        """1-sigma misalignment per ENU axis [rad]."""
        return np.sqrt(np.diag(self.cov_phi))


def _triad(v1_b, v2_b, v1_n, v2_n):
    """``C_bn`` from two vector pairs, the first trusted fully (TRIAD): gravity sets the
    level, the earth rate only the azimuth, so rate errors do not tilt the result."""
    def frame(a, b):
        e1 = a / np.linalg.norm(a)
        e2 = np.cross(a, b)
        e2 /= np.linalg.norm(e2)
        return np.column_stack([e1, e2, np.cross(e1, e2)])

    return frame(v1_n, v2_n) @ frame(v1_b, v2_b).T


def _orthonormal(M):
    u, _, vt = np.linalg.svd(M)
    d = np.sign(np.linalg.det(u @ vt))
    return u @ np.diag([1.0, 1.0, d]) @ vt


def uncertainty(lat_rad, window_s, gyro_bias, accel_bias, arw=0.0, vrw=0.0):
    """Covariance of the coarse-alignment misalignment (ENU) [rad^2].

    Parameters
    ----------
    lat_rad, window_s : float
    gyro_bias, accel_bias : float
        A-priori bias per axis [rad/s], [m/s^2].
    arw, vrw : float
        White-noise densities [rad/sqrt(s)], [m/s/sqrt(s)].
    """
    g = earth.gravity(lat_rad, 0.0)
    tilt = np.sqrt(accel_bias**2 + vrw**2 / window_s) / g
    rate = np.sqrt(gyro_bias**2 + arw**2 / window_s) / (OMEGA_IE * np.cos(lat_rad))
    az = np.hypot(rate, np.tan(lat_rad) * tilt)
    return np.diag([tilt**2, tilt**2, az**2])


def _select(imu, t0, t1, slack_s):
    """The increments inside ``[t0, t1]`` (a boolean mask); at least two."""
    sel = (imu.time_s[:-1] >= t0 - slack_s) & (imu.time_s[1:] <= t1 + slack_s)
    if np.count_nonzero(sel) < 2:
        raise FuzzynavError(f"coarse alignment: fewer than two IMU samples in "
                            f"[{t0}, {t1}] s")
    return sel


def _window(imu, t0, t1, slack_s=GRID_SLACK_S):
    """First and one-past-last increment inside ``[t0, t1]``."""
    k = np.flatnonzero(_select(imu, t0, t1, slack_s))
    return k[0], k[-1] + 1


def level(imu, t0, t1, slack_s=0.0):
    """Pitch, roll [rad], mean specific force [m/s^2] and mean rate [rad/s] over a rest
    ``[t0, t1]`` [s] (increments that end inside it; ``slack_s``: :data:`GRID_SLACK_S`)."""
    sel = _select(imu, t0, t1, slack_s)
    dt = np.sum(np.diff(imu.time_s)[sel])
    f = imu.dv_b[sel].sum(0) / dt
    w = imu.dtheta_b[sel].sum(0) / dt
    pitch = np.arctan2(f[1], np.hypot(f[0], f[2]))
    roll = np.arctan2(-f[0], f[2])
    return float(pitch), float(roll), f, w


@nb.njit(cache=True, error_model="numpy")
def body_chain(dtheta):
    """Quaternions of ``C_b0_bk``, the body at sample k relative to the body at sample 0,
    from the increments ``dtheta`` (K, 3) [rad]: (K+1, 4)."""
    n = dtheta.shape[0]
    q = np.empty((n + 1, 4))
    q[0] = (1.0, 0.0, 0.0, 0.0)
    for k in range(n):
        r = rv2q(dtheta[k, 0], dtheta[k, 1], dtheta[k, 2])
        a = quat_mul(q[k, 0], q[k, 1], q[k, 2], q[k, 3], r[0], r[1], r[2], r[3])
        s = 1.0 / np.sqrt(a[0] ** 2 + a[1] ** 2 + a[2] ** 2 + a[3] ** 2)
        q[k + 1] = (a[0] * s, a[1] * s, a[2] * s, a[3] * s)
    return q


def analytic(imu, lat_rad, h_m, t0, t1, cov_phi) -> CoarseResult:
    """Analytic coarse alignment on a stationary base over ``[t0, t1]``.

    Parameters
    ----------
    imu : ImuData
    lat_rad, h_m : float
    t0, t1 : float
        The window [s].
    cov_phi : ndarray (3, 3)
        Its uncertainty (see :func:`uncertainty`), returned with the attitude.
    """
    _, k1 = _window(imu, t0, t1)
    _, _, f, w = level(imu, t0, t1, GRID_SLACK_S)
    fn = np.array([0.0, 0.0, earth.gravity(lat_rad, h_m)])
    C = _triad(f, w, fn, earth.omega_ie_n(lat_rad))
    return CoarseResult(C, attitude.dcm_to_euler(C), cov_phi, float(imu.time_s[k1]), "analytic")


def _integral(dv, dt):
    """``V`` (running sum of increments) and ``S = int V dt`` (trapezoid), both (K+1, 3)."""
    V = np.vstack([np.zeros(3), np.cumsum(dv, 0)])
    S = np.vstack([np.zeros(3), np.cumsum(0.5 * (V[1:] + V[:-1]) * dt[:, None], 0)])
    return S


def _fit_covariance(S_b0, S_n0, C_b0n0):
    """Extra misalignment variance from the misfit of Wahba's problem [rad^2].

    A residual ``r`` against vectors of size ``|S|`` tilts by about ``|r|/|S|``; the
    azimuth rests on the horizontal bend of ``S_n0`` only.  The tilt term is optimistic
    under sway (the tests check the azimuth term only).
    """
    r2 = np.mean(np.sum((S_b0 - S_n0 @ C_b0n0.T) ** 2, 1))
    up = S_n0[-1] / np.linalg.norm(S_n0[-1])
    bend = S_n0 - np.outer(S_n0 @ up, up)
    tilt = r2 / np.mean(np.sum(S_n0**2, 1))
    return np.diag([tilt, tilt, r2 / max(np.mean(np.sum(bend**2, 1)), 1e-300)])


def inertial_frame(imu, lat_rad, h_m, t0, t1, cov_phi, n_vectors=50) -> CoarseResult:
    """Inertial-frame coarse alignment over ``[t0, t1]`` (tolerates sway and vibration).

    ``n_vectors`` integrated vectors, evenly spread over the second half of the window
    (early ones are short and noisy), enter Wahba's problem.  The returned covariance is
    ``cov_phi`` plus the misfit term of :func:`_fit_covariance` (sway, gusts).
    """
    k0, k1 = _window(imu, t0, t1)
    t = imu.time_s[k0:k1 + 1] - imu.time_s[k0]
    dt = np.diff(t)
    C_b0b = attitude.quat_to_dcm(body_chain(np.ascontiguousarray(imu.dtheta_b[k0:k1])))
    dv_b0 = np.einsum("kij,kj->ki", C_b0b[:-1], imu.dv_b[k0:k1]
                      + 0.5 * np.cross(imu.dtheta_b[k0:k1], imu.dv_b[k0:k1]))
    wn = earth.omega_ie_n(lat_rad)
    g_n = np.array([0.0, 0.0, earth.gravity(lat_rad, h_m)])
    C_n0n = attitude.rotvec_to_dcm(np.outer(0.5 * (t[1:] + t[:-1]), wn))
    S_b0 = _integral(dv_b0, dt)
    S_n0 = _integral(np.einsum("kij,j->ki", C_n0n, g_n) * dt[:, None], dt)
    pick = np.unique(np.linspace(t.size // 2, t.size - 1, n_vectors).astype(int))
    # Wahba: C_b0_n0 maximises sum s_b0 . C s_n0
    C_b0n0 = _orthonormal(S_b0[pick].T @ S_n0[pick])
    C = attitude.rotvec_to_dcm(-wn * t[-1]) @ C_b0n0.T @ C_b0b[-1]
    cov = cov_phi + _fit_covariance(S_b0[pick], S_n0[pick], C_b0n0)
    return CoarseResult(C, attitude.dcm_to_euler(C), cov, float(imu.time_s[k1]),
                        "inertial-frame")
