"""Error-state model of the ENU strapdown INS (numba kernels).

State layout (``n = 15`` or ``18``)::

    0:3   phi_n      attitude error [rad], C_bn_calc = (I - [phi x]) C_bn_true
    3:6   dvel_n     velocity error calc - true [m/s]
    6:9   dpos_n     position error calc - true, ENU metres
    then the sensor-error blocks of :class:`ErrorModel` (3 states each): every gyro block
    adds to the residual gyro bias [rad/s], every accelerometer block to the residual
    accelerometer bias [m/s^2]; a block is a random constant (tau = inf) or a first-order
    Gauss-Markov process with correlation time tau [s].

The dynamics are the classical phi-angle model (Savage; Yan Gongmin's PSINS ``etm``) written
with the position error in metres: with ``D = diag((R_N+h) cos L, R_M+h, 1)`` the metric
error is ``D [dlon, dlat, dh]`` and its system matrix ``D F D^-1 + dD/dt D^-1``.
Discretisation: ``Phi = I + F dt + (F dt)^2 / 2`` and
``Qd = Q dt + (F Q + Q F^T) dt^2 / 2 + F Q F^T dt^3 / 3`` (second-order Van Loan series).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from fuzzynav.nav.earth import E2, OMEGA_IE, gravity_nb, radii_nb

PHI, DVEL, DPOS = 0, 3, 6
NAV_STATES = 9


@dataclass(frozen=True)
class ErrorModel:
    """Layout of the sensor-error states.

    Parameters
    ----------
    gyro_tau_s : tuple of float
        One entry per gyro block: ``inf`` for a random constant, else the Gauss-Markov
        correlation time [s].
    accel_tau_s : tuple of float
        Same for the accelerometer blocks.
    """

    gyro_tau_s: tuple = (math.inf,)
    accel_tau_s: tuple = (math.inf,)

    @property
    def n_states(self) -> int:
        """Total number of error states."""
        return NAV_STATES + 3 * (len(self.gyro_tau_s) + len(self.accel_tau_s))

    def block_arrays(self):
        """``(start, kind, inv_tau)`` arrays per block: kind 0 gyro, 1 accelerometer."""
        taus = list(self.gyro_tau_s) + list(self.accel_tau_s)
        kinds = [0] * len(self.gyro_tau_s) + [1] * len(self.accel_tau_s)
        start = NAV_STATES + 3 * np.arange(len(taus))
        inv_tau = np.array([0.0 if math.isinf(t) else 1.0 / t for t in taus])
        return start.astype(np.int64), np.array(kinds, dtype=np.int64), inv_tau

    def labels(self):
        """State names for tables and plots."""
        names = [f"phi_{a}" for a in "enu"] + [f"dvel_{a}" for a in "enu"] + \
            [f"dpos_{a}" for a in "enu"]
        for i, _ in enumerate(self.gyro_tau_s):
            names += [f"gyro{i}_{a}" for a in "xyz"]
        for i, _ in enumerate(self.accel_tau_s):
            names += [f"accel{i}_{a}" for a in "xyz"]
        return names


#: the 15-state model (random-constant biases)
MODEL_15 = ErrorModel()


@nb.njit(cache=True)
def _dgravity_dlat(lat, h):
    """Derivative of normal gravity with latitude [m/s^2/rad] (height factor neglected)."""
    s, c = math.sin(lat), math.cos(lat)
    s2 = s * s
    w = 1.0 - E2 * s2
    ge, k = 9.7803253359, 0.00193185265241
    dg_du = ge * (k / math.sqrt(w) + 0.5 * E2 * (1.0 + k * s2) / (w * math.sqrt(w)))
    return dg_du * 2.0 * s * c


@nb.njit(cache=True)
def fill_F(F, nav, C_bn, f_n, blk_start, blk_kind, blk_inv_tau):
    """Write the continuous system matrix into ``F`` (n x n, overwritten).

    ``nav`` is the strapdown state, ``C_bn`` the (mean) attitude over the interval and
    ``f_n`` the mean specific force in the navigation frame.
    """
    F[:, :] = 0.0
    ve, vn, vu = nav[4], nav[5], nav[6]
    lat, h = nav[7], nav[9]
    rm, rn = radii_nb(lat)
    rmh, rnh = rm + h, rn + h
    sl, cl = math.sin(lat), math.cos(lat)
    tl = sl / cl
    wie_n, wie_u = OMEGA_IE * cl, OMEGA_IE * sl
    # omega_in = omega_ie + omega_en
    wie = (0.0, wie_n, wie_u)
    wen = (-vn / rmh, ve / rnh, ve * tl / rnh)
    win = (wen[0], wie_n + wen[1], wie_u + wen[2])
    # --- in radian position units (dlat, dlon, dh) first: columns 6, 7, 8 ---
    # d(omega_ie)/dp and d(omega_en)/dp
    Mp1 = np.zeros((3, 3))
    Mp1[1, 0] = -wie_u
    Mp1[2, 0] = wie_n
    Mp2 = np.zeros((3, 3))
    Mp2[0, 2] = vn / rmh**2
    Mp2[1, 2] = -ve / rnh**2
    Mp2[2, 0] = ve / (rnh * cl * cl)
    Mp2[2, 2] = -ve * tl / rnh**2
    Mav = np.zeros((3, 3))
    Mav[0, 1] = -1.0 / rmh
    Mav[1, 0] = 1.0 / rnh
    Mav[2, 0] = tl / rnh
    # attitude rows: phi' = -win x phi + Mav dv + (Mp1 + Mp2) dp - C_bn eps
    _skew_into(F, 0, 0, -win[0], -win[1], -win[2])
    for i in range(3):
        for j in range(3):
            F[i, 3 + j] = Mav[i, j]
            F[i, 6 + j] = Mp1[i, j] + Mp2[i, j]
    # velocity rows: dv' = f x phi + ([v x] Mav - [(2wie + wen) x]) dv + [v x](2Mp1 + Mp2) dp
    _skew_into(F, 3, 0, f_n[0], f_n[1], f_n[2])
    ax, ay, az = 2.0 * wie[0] + wen[0], 2.0 * wie[1] + wen[1], 2.0 * wie[2] + wen[2]
    for i in range(3):
        for j in range(3):
            vm = _skew_elem(ve, vn, vu, i, 0) * Mav[0, j] + \
                _skew_elem(ve, vn, vu, i, 1) * Mav[1, j] + \
                _skew_elem(ve, vn, vu, i, 2) * Mav[2, j]
            F[3 + i, 3 + j] = vm - _skew_elem(ax, ay, az, i, j)
            vp = 0.0
            for k in range(3):
                vp += _skew_elem(ve, vn, vu, i, k) * (2.0 * Mp1[k, j] + Mp2[k, j])
            F[3 + i, 6 + j] = vp
    # gravity: up component of dg with latitude and height
    F[5, 6] += -_dgravity_dlat(lat, h)
    F[5, 8] += -(gravity_nb(lat, h + 0.5) - gravity_nb(lat, h - 0.5))
    # position rows (dlat, dlon, dh)
    F[6, 4] = 1.0 / rmh
    F[6, 8] = -vn / rmh**2
    F[7, 3] = 1.0 / (rnh * cl)
    F[7, 6] = ve * tl / (rnh * cl)
    F[7, 8] = -ve / (rnh**2 * cl)
    F[8, 5] = 1.0
    # --- metric position error: D F D^-1 + dD/dt D^-1, D = diag of the dpos_n order ---
    _to_metric(F, lat, rmh, rnh, vn, vu, tl, cl)
    # --- sensor-error blocks ---
    for b in range(blk_start.size):
        s0 = blk_start[b]
        row = 0 if blk_kind[b] == 0 else 3
        sign = -1.0 if blk_kind[b] == 0 else 1.0
        for i in range(3):
            for j in range(3):
                F[row + i, s0 + j] = sign * C_bn[i, j]
            F[s0 + i, s0 + i] = -blk_inv_tau[b]


@nb.njit(cache=True)
def _to_metric(F, lat, rmh, rnh, vn, vu, tl, cl):
    """Convert columns/rows 6:9 from (dlat, dlon, dh) to ENU metres in place."""
    n = F.shape[0]
    # radian state r = (dlat, dlon, dh) -> metres m = (dE, dN, dU) = (D1 dlon, D0 dlat, dh)
    d_lat, d_lon = rmh, rnh * cl
    # new columns: F[:, m] = F[:, r] / D  (permuting lat/lon into N/E order)
    for i in range(n):
        c_lat, c_lon = F[i, 6], F[i, 7]
        F[i, 6] = c_lon / d_lon   # dE column
        F[i, 7] = c_lat / d_lat   # dN column
    for j in range(n):
        r_lat, r_lon = F[6, j], F[7, j]
        F[6, j] = r_lon * d_lon   # dE row
        F[7, j] = r_lat * d_lat   # dN row
    # dD/dt D^-1 terms (heights change the radii of the metric map)
    F[6, 6] += vu / rnh - tl * vn / rmh
    F[7, 7] += vu / rmh


@nb.njit(cache=True)
def _skew_elem(x, y, z, i, j):
    """Element (i, j) of [v x] for v = (x, y, z)."""
    if i == j:
        return 0.0
    if i == 0:
        return -z if j == 1 else y
    if i == 1:
        return z if j == 0 else -x
    return -y if j == 0 else x


@nb.njit(cache=True)
def _skew_into(F, r0, c0, x, y, z):
    F[r0, c0 + 1] += -z
    F[r0, c0 + 2] += y
    F[r0 + 1, c0] += z
    F[r0 + 1, c0 + 2] += -x
    F[r0 + 2, c0] += -y
    F[r0 + 2, c0 + 1] += x


@nb.njit(cache=True)
def discretize(F, q_diag, dt, Phi, Qd, work):
    """Second-order transition matrix and process noise over ``dt``.

    Parameters
    ----------
    F : (n, n) continuous system matrix.
    q_diag : (n,) continuous white-noise spectral densities (per state).
    dt : float
    Phi, Qd : (n, n) outputs.
    work : (n, n) scratch.
    """
    n = F.shape[0]
    # work = F @ F (F is sparse: skip zero entries)
    work[:, :] = 0.0
    for i in range(n):
        for k in range(n):
            fik = F[i, k]
            if fik != 0.0:
                for j in range(n):
                    work[i, j] += fik * F[k, j]
    h2 = 0.5 * dt * dt
    for i in range(n):
        for j in range(n):
            Phi[i, j] = F[i, j] * dt + work[i, j] * h2
        Phi[i, i] += 1.0
    # Qd = Q dt + (F Q + Q F^T) dt^2/2 + F Q F^T dt^3/3 with diagonal Q
    h3 = dt * dt * dt / 3.0
    for i in range(n):
        for j in range(i, n):
            s = (F[i, j] * q_diag[j] + q_diag[i] * F[j, i]) * h2
            acc = 0.0
            for k in range(n):
                if q_diag[k] != 0.0:
                    acc += F[i, k] * q_diag[k] * F[j, k]
            s += acc * h3
            if i == j:
                s += q_diag[i] * dt
            Qd[i, j] = s
            Qd[j, i] = s
