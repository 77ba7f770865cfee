"""Closed-loop feedback of an error-state estimate into the navigation and sensor estimates,
and the total IMU biases the mechanization subtracts (numba kernels of the filter loop)."""
from __future__ import annotations

import math

import numba as nb

from fuzzynav.filters.layout import COUPLE_ACCEL, COUPLE_GYRO, N_CORE, X_ATT, X_POS, X_VEL
from fuzzynav.nav.earth import radii_nb
from fuzzynav.nav.state_layout import NAV_H, NAV_LAT, NAV_LON, NAV_Q, NAV_VEL, PREV_LLA, PREV_VEL
from fuzzynav.nav.strapdown import quat_mul, rv2q, set_quat

__all__ = ["feedback", "bias_totals"]


@nb.njit(cache=True, error_model="numpy")
def feedback(nav, prev, xs, x):
    """Apply the error-state estimate to the navigation and sensor estimates (then x = 0)."""
    a0, a1, a2, a3 = rv2q(x[X_ATT], x[X_ATT + 1], x[X_ATT + 2])
    q0, q1, q2, q3 = quat_mul(a0, a1, a2, a3, nav[NAV_Q], nav[NAV_Q + 1], nav[NAV_Q + 2],
                              nav[NAV_Q + 3])
    qn = 1.0 / math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    set_quat(nav, q0 * qn, q1 * qn, q2 * qn, q3 * qn)
    rm, rn = radii_nb(nav[NAV_LAT])
    de, dn, du = x[X_POS], x[X_POS + 1], x[X_POS + 2]  # ENU metres
    dlat = dn / (rm + nav[NAV_H])
    dlon = de / ((rn + nav[NAV_H]) * math.cos(nav[NAV_LAT]))
    for i in range(3):
        nav[NAV_VEL + i] -= x[X_VEL + i]
        prev[PREV_VEL + i] -= x[X_VEL + i]  # keep the midpoint extrapolation free of the jump
    nav[NAV_LAT] -= dlat
    nav[NAV_LON] -= dlon
    nav[NAV_H] -= du
    prev[PREV_LLA] -= dlat
    prev[PREV_LLA + 1] -= dlon
    prev[PREV_LLA + 2] -= du
    for j in range(xs.size):
        xs[j] += x[N_CORE + j]


@nb.njit(cache=True, error_model="numpy")
def bias_totals(xs, blk_start, blk_kind, bg, ba):
    """Sum the sensor-error blocks into total gyro and accelerometer bias estimates."""
    for i in range(3):
        bg[i] = 0.0
        ba[i] = 0.0
    for b in range(blk_start.size):
        s0 = blk_start[b] - N_CORE
        for i in range(3):
            if blk_kind[b] == COUPLE_GYRO:
                bg[i] += xs[s0 + i]
            elif blk_kind[b] == COUPLE_ACCEL:
                ba[i] += xs[s0 + i]

