"""Strapdown mechanization in the ENU frame from IMU increments (numba).

One step integrates the increments ``dtheta_b`` [rad] and ``dv_b`` [m/s] of one IMU interval
``dt`` with

* two-sample (previous-sample) coning and sculling corrections and the second-order
  rotation compensation,
  ``phi = dtheta + dtheta_prev x dtheta / 12``,
  ``dv_sf = dv + dtheta x dv / 2 + dtheta x (dtheta x dv) / 6
  + (dtheta_prev x dv + dv_prev x dtheta) / 12``;
* rotation compensation of the navigation frame over the interval,
  ``dv_sf_n = (I - [omega_in_n dt x] / 2) C_bn dv_sf``;
* earth rate, transport rate, gravity and Coriolis evaluated at the interval midpoint
  (velocity and position extrapolated from the previous step);
* trapezoidal position update and the attitude update
  ``q <- q(-omega_in_n dt) * q * q(phi)``.

The navigation state is a float64 array ``nav`` laid out as :mod:`fuzzynav.nav.state_layout` says
(quaternion of ``C_bn``, ENU velocity, latitude, longitude, height).  The step keeps the
previous increments and state in a work array ``prev`` (same module; initialise it with
:func:`init_prev`).
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.nav.earth import OMEGA_IE, radii_gravity_sin_nb
from fuzzynav.nav.state_layout import (LLA_SLICE, NAV_H, NAV_LAT, NAV_LON, NAV_Q, NAV_SIZE, NAV_VEL,
                                 PREV_DTH, PREV_DV, PREV_FLAG, PREV_LLA, PREV_SIZE, PREV_TRIG,
                                 PREV_VEL,
                                 Q_SLICE, VEL_SLICE)

__all__ = ["quat_mul", "rv2q", "quat_to_dcm_into", "dcm_into", "sin_cos_lat", "inv_norm",
           "init_prev", "mech_step", "set_quat", "make_nav", "integrate"]


@nb.njit(cache=True, error_model="numpy")
def quat_mul(a0, a1, a2, a3, b0, b1, b2, b3):
    """Hamilton product of two quaternions given as scalars; returns a 4-tuple."""
    return (a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
            a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
            a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0)


# reciprocals of the series and correction coefficients: a product is several times cheaper
# than a division on the per-sample path (the results differ only in the last bit)
_R6, _R12, _R48, _R384, _R3840 = 1.0 / 6.0, 1.0 / 12.0, 1.0 / 48.0, 1.0 / 384.0, 1.0 / 3840.0


@nb.njit(cache=True, error_model="numpy")
def rv2q(x, y, z):
    """Rotation vector to quaternion, with a series for small angles (full precision)."""
    a2 = x * x + y * y + z * z
    # the first omitted terms, a^6/645120 of sin(a/2)/a and a^6/46080 of cos(a/2), stay under
    # 3e-18 and 2.2e-17 below a^2 = 1e-4, a fraction of an ulp: the series is exact to
    # rounding there and spares sqrt, sin and cos for every IMU step of up to 0.01 rad
    if a2 < 1e-4:
        s = 0.5 - a2 * _R48 + a2 * a2 * _R3840
        c = 1.0 - a2 * 0.125 + a2 * a2 * _R384
    else:
        a = math.sqrt(a2)
        s = math.sin(0.5 * a) / a
        c = math.cos(0.5 * a)
    return c, s * x, s * y, s * z


@nb.njit(cache=True, error_model="numpy")
def quat_to_dcm_into(nav, C):
    """Write ``C_bn`` of the quaternion of ``nav`` into the 3x3 array ``C``."""
    dcm_into(nav[NAV_Q], nav[NAV_Q + 1], nav[NAV_Q + 2], nav[NAV_Q + 3], C)


@nb.njit(cache=True, error_model="numpy")
def dcm_into(w, x, y, z, C):
    """Write ``C_bn`` of the quaternion ``(w, x, y, z)`` into the 3x3 array ``C``."""
    C[0, 0] = w * w + x * x - y * y - z * z
    C[0, 1] = 2.0 * (x * y - w * z)
    C[0, 2] = 2.0 * (x * z + w * y)
    C[1, 0] = 2.0 * (x * y + w * z)
    C[1, 1] = w * w - x * x + y * y - z * z
    C[1, 2] = 2.0 * (y * z - w * x)
    C[2, 0] = 2.0 * (x * z - w * y)
    C[2, 1] = 2.0 * (y * z + w * x)
    C[2, 2] = w * w - x * x - y * y + z * z


#: largest change of the midpoint latitude between steps that :func:`sin_cos_lat` follows
#: by the angle-addition formulas [rad] (~6 m; a step moves it by ~1e-8 rad); and how many
#: steps it follows so before an exact evaluation bounds the accumulated rounding
_TRIG_MAX_STEP, _TRIG_STEPS = 1e-6, 64.0


@nb.njit(inline="always", error_model="numpy")
def sin_cos_lat(lat, prev):
    """Sine and cosine of the midpoint latitude ``lat``, from those of the last step.

    ``sin(a + d) = sin a (1 - d^2/2) + cos a d`` (and cosine alike) is exact to rounding for
    ``|d| < 1e-6`` (the next terms, d^3/6 and d^4/24, are below 2e-19) and takes a few
    products where ``sin`` and ``cos`` take two library calls, and the latitude's chain
    from one step to the next runs through them.  Every :data:`_TRIG_STEPS` steps, after
    a larger jump (a position feedback) and at the first step they are evaluated exactly,
    which keeps them within ~1e-16 of ``math.sin``/``math.cos`` (a few tens of ulp of a
    cosine near zero at most).
    """
    d = lat - prev[PREV_TRIG]
    n = prev[PREV_TRIG + 3]
    if n > 0.0 and abs(d) < _TRIG_MAX_STEP:
        s0, c0 = prev[PREV_TRIG + 1], prev[PREV_TRIG + 2]
        hd2 = 0.5 * d * d
        sl, cl = s0 + (c0 * d - s0 * hd2), c0 - (s0 * d + c0 * hd2)
        n -= 1.0
    else:
        sl, cl = math.sin(lat), math.cos(lat)
        n = _TRIG_STEPS
    prev[PREV_TRIG], prev[PREV_TRIG + 1], prev[PREV_TRIG + 2] = lat, sl, cl
    prev[PREV_TRIG + 3] = n
    return sl, cl


#: how far from 1 a squared quaternion norm may be for :func:`inv_norm`'s Newton step
_NORM_NEWTON = 1e-8


@nb.njit(inline="always", error_model="numpy")
def inv_norm(s):
    """``1 / sqrt(s)`` for the squared norm ``s`` of a quaternion that was unit a step ago.

    A step's products move the norm from 1 by a few ulp (``s = 1 + e``): one Newton step
    from 1, ``1.5 - s / 2 = 1 - e/2``, is then ``1/sqrt(s)`` to rounding (it omits
    ``3 e^2 / 8 < 4e-17``), with no square root and no division on the step's critical path;
    a norm further off is divided out exactly.
    """
    if abs(s - 1.0) < _NORM_NEWTON:
        return 1.5 - 0.5 * s
    return 1.0 / math.sqrt(s)


@nb.njit(cache=True, error_model="numpy")
def init_prev(nav, prev):
    """Prepare the work array for the first step (no previous increments)."""
    prev[PREV_FLAG] = 0.0
    prev[PREV_TRIG + 3] = 0.0  # the first step evaluates sin and cos of its latitude
    for i in range(3):
        prev[PREV_VEL + i] = nav[NAV_VEL + i]
        prev[PREV_LLA + i] = nav[NAV_LAT + i]


@nb.njit(cache=True, error_model="numpy")
def mech_step(nav, prev, dth, dv, dt, dv_sf_n, C):
    """Advance ``nav`` in place by one IMU interval.

    Parameters
    ----------
    nav : float64[NAV_SIZE]
        Navigation state, updated in place.
    prev : float64[PREV_SIZE]
        Work array from :func:`init_prev` / the previous step, updated in place.
    dth, dv : float64[3]
        Angle [rad] and velocity [m/s] increments of this interval (bias-corrected).
    dt : float
        Interval [s].
    dv_sf_n : float64[3]
        Output: the specific-force velocity increment of the interval in the navigation
        frame [m/s] (its mean specific force times ``dt``, for the error model).
    C : float64[3, 3]
        ``C_bn`` of the attitude in ``nav`` on entry (:func:`quat_to_dcm_into`); the step
        replaces it with that of the new attitude.  The caller keeps it current (after a
        feedback too), so no sample forms the matrix twice.
    """
    if prev[PREV_FLAG] == 0.0:  # first step: no previous increments, so no coning/sculling
        for i in range(3):
            prev[PREV_DTH + i] = dth[i]
            prev[PREV_DV + i] = dv[i]
        prev[PREV_FLAG] = 1.0
    px, py, pz = prev[PREV_DTH], prev[PREV_DTH + 1], prev[PREV_DTH + 2]
    ux, uy, uz = prev[PREV_DV], prev[PREV_DV + 1], prev[PREV_DV + 2]
    tx, ty, tz = dth[0], dth[1], dth[2]
    vx, vy, vz = dv[0], dv[1], dv[2]
    # coning: phi = dth + dth_prev x dth / 12
    phx = tx + (py * tz - pz * ty) * _R12
    phy = ty + (pz * tx - px * tz) * _R12
    phz = tz + (px * ty - py * tx) * _R12
    # rotation + sculling: dv + dth x dv / 2 + dth x (dth x dv) / 6
    #                      + (dth_prev x dv + dv_prev x dth) / 12
    # The second-order rotation term (Savage's exact rotation compensation, small-angle
    # coefficient 1/6) is rectified under sustained rotation: without it a 1-h replay
    # with pitch manoeuvres drifts ~0.4 m vertically through the unstable height channel.
    rx = ty * vz - tz * vy
    ry = tz * vx - tx * vz
    rz = tx * vy - ty * vx
    sx = vx + 0.5 * rx + (ty * rz - tz * ry) * _R6 \
        + ((py * vz - pz * vy) + (uy * tz - uz * ty)) * _R12
    sy = vy + 0.5 * ry + (tz * rx - tx * rz) * _R6 \
        + ((pz * vx - px * vz) + (uz * tx - ux * tz)) * _R12
    sz = vz + 0.5 * rz + (tx * ry - ty * rx) * _R6 \
        + ((px * vy - py * vx) + (ux * ty - uy * tx)) * _R12
    # midpoint quantities, extrapolated from the previous step
    ve, vn, vu = nav[NAV_VEL], nav[NAV_VEL + 1], nav[NAV_VEL + 2]
    lat, lon, h = nav[NAV_LAT], nav[NAV_LON], nav[NAV_H]
    vme = 1.5 * ve - 0.5 * prev[PREV_VEL]
    vmn = 1.5 * vn - 0.5 * prev[PREV_VEL + 1]
    vmu = 1.5 * vu - 0.5 * prev[PREV_VEL + 2]
    latm = 1.5 * lat - 0.5 * prev[PREV_LLA]
    hm = 1.5 * h - 0.5 * prev[PREV_LLA + 2]
    sl, cl = sin_cos_lat(latm, prev)  # once for radii, gravity and the rates
    rm, rn, g = radii_gravity_sin_nb(sl, hm)
    wie_n, wie_u = OMEGA_IE * cl, OMEGA_IE * sl
    wen_e = -vmn / (rm + hm)
    wen_n = vme / (rn + hm)
    wen_u = wen_n * (sl / cl)  # v_E tan(L) / (R_N + h)
    wine, winn, winu = wen_e, wie_n + wen_n, wie_u + wen_u
    # body -> navigation with the attitude at the start of the interval (C on entry)
    ne = C[0, 0] * sx + C[0, 1] * sy + C[0, 2] * sz
    nn = C[1, 0] * sx + C[1, 1] * sy + C[1, 2] * sz
    nu = C[2, 0] * sx + C[2, 1] * sy + C[2, 2] * sz
    # (I - [w_in dt x] / 2) applied to the specific-force increment
    hdt = 0.5 * dt
    dse = ne - hdt * (winn * nu - winu * nn)
    dsn = nn - hdt * (winu * ne - wine * nu)
    dsu = nu - hdt * (wine * nn - winn * ne)
    dv_sf_n[0], dv_sf_n[1], dv_sf_n[2] = dse, dsn, dsu
    # Coriolis and gravity at the midpoint: -(2 w_ie + w_en) x v + g
    ae, an, au = wen_e, 2.0 * wie_n + wen_n, 2.0 * wie_u + wen_u
    cor_e = -(an * vmu - au * vmn)
    cor_n = -(au * vme - ae * vmu)
    cor_u = -(ae * vmn - an * vme) - g
    ve1 = ve + dse + cor_e * dt
    vn1 = vn + dsn + cor_n * dt
    vu1 = vu + dsu + cor_u * dt
    # position: trapezoid of velocity with midpoint radii
    h1 = h + 0.5 * (vu + vu1) * dt
    hm2 = 0.5 * (h + h1)
    lat1 = lat + 0.5 * (vn + vn1) * dt / (rm + hm2)
    lon1 = lon + 0.5 * (ve + ve1) * dt / ((rn + hm2) * cl)
    # attitude: q <- q(-w_in dt) * q * q(phi)
    q0, q1, q2, q3 = nav[NAV_Q], nav[NAV_Q + 1], nav[NAV_Q + 2], nav[NAV_Q + 3]
    a0, a1, a2, a3 = rv2q(-wine * dt, -winn * dt, -winu * dt)
    b0, b1, b2, b3 = rv2q(phx, phy, phz)
    q0, q1, q2, q3 = quat_mul(q0, q1, q2, q3, b0, b1, b2, b3)
    q0, q1, q2, q3 = quat_mul(a0, a1, a2, a3, q0, q1, q2, q3)
    qn = inv_norm(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    # keep the previous values for the next step's extrapolation and corrections
    for i in range(3):
        prev[PREV_DTH + i] = dth[i]
        prev[PREV_DV + i] = dv[i]
    prev[PREV_VEL], prev[PREV_VEL + 1], prev[PREV_VEL + 2] = ve, vn, vu
    prev[PREV_LLA], prev[PREV_LLA + 1], prev[PREV_LLA + 2] = lat, lon, h
    q0, q1, q2, q3 = q0 * qn, q1 * qn, q2 * qn, q3 * qn
    set_quat(nav, q0, q1, q2, q3)
    dcm_into(q0, q1, q2, q3, C)
    nav[NAV_VEL], nav[NAV_VEL + 1], nav[NAV_VEL + 2] = ve1, vn1, vu1
    nav[NAV_LAT], nav[NAV_LON], nav[NAV_H] = lat1, lon1, h1


@nb.njit(cache=True, error_model="numpy")
def set_quat(nav, q0, q1, q2, q3):
    """Store the attitude quaternion ``(q0, q1, q2, q3)`` in ``nav``."""
    nav[NAV_Q], nav[NAV_Q + 1], nav[NAV_Q + 2], nav[NAV_Q + 3] = q0, q1, q2, q3


@nb.njit(cache=True, error_model="numpy")
def _integrate(nav0, dtheta_b, dv_b, dt, stride):
    n = dtheta_b.shape[0]
    nav = nav0.copy()
    prev = np.zeros(PREV_SIZE)
    init_prev(nav, prev)
    dv_sf = np.zeros(3)
    C = np.zeros((3, 3))
    quat_to_dcm_into(nav, C)
    out = np.empty((n // stride + 1, NAV_SIZE))
    out[0] = nav
    for k in range(n):
        mech_step(nav, prev, dtheta_b[k], dv_b[k], dt, dv_sf, C)
        if (k + 1) % stride == 0:
            out[(k + 1) // stride] = nav
    return out


def make_nav(lla, vel_n, q_bn) -> np.ndarray:
    """Pack position ``(lat_rad, lon_rad, h_m)``, ENU velocity and quaternion into ``nav``."""
    nav = np.empty(NAV_SIZE)
    nav[Q_SLICE] = q_bn
    nav[VEL_SLICE] = vel_n
    nav[LLA_SLICE] = lla
    return nav


def integrate(lla0, vel_n0, q_bn0, dtheta_b, dv_b, dt, stride=1):
    """Pure-inertial navigation from increments (no aiding).

    Parameters
    ----------
    lla0, vel_n0, q_bn0 : array_like
        Initial position (rad, rad, m), ENU velocity [m/s], attitude quaternion.
    dtheta_b, dv_b : ndarray, shape (N, 3)
        Angle [rad] and velocity [m/s] increments.
    dt : float
        IMU interval [s].
    stride : int
        Keep every ``stride``-th state (memory independent of N otherwise).

    Returns
    -------
    dict
        ``lla`` (M, 3), ``vel_n`` (M, 3), ``q_bn`` (M, 4) with M = N // stride + 1.
    """
    nav0 = make_nav(lla0, vel_n0, q_bn0)
    out = _integrate(nav0, np.ascontiguousarray(dtheta_b, dtype=float),
                     np.ascontiguousarray(dv_b, dtype=float), float(dt), int(stride))
    return {"lla": out[:, LLA_SLICE], "vel_n": out[:, VEL_SLICE], "q_bn": out[:, Q_SLICE]}
