"""Numba kernels that turn skylight angles of polarization into attitude.

The filter calls these at measurement epochs with plain floats and arrays.  They invert the
measurement model of :mod:`fuzzynav.sim.sensors.polarization` (nominal mounting, sensor axes
= body RFU axes):

* a view direction ``v_b`` (unit, body frame) sees the E-vector ``e ~ v_b x s_b`` with
  ``s_b = C_bn^T sun_n``;
* its angle of polarization is measured from the body x axis (right) projected onto the
  plane perpendicular to ``v_b``, positive about ``v_b`` (:mod:`fuzzynav.sim.skylight`),
  which reduces to ``aop = atan2(s_x - v_x (v.s), v_y s_z - v_z s_y)`` modulo pi;
* for the zenith sensor (``v_b = z_b``), ``aop = atan2(s_bx, -s_by)``, and on level ground
  ``heading = sun_azimuth + aop`` (mod pi).

Euler angles are ``(pitch, roll, heading)`` of :mod:`fuzzynav.nav.attitude`
(``C_bn = R3(-heading) R1(pitch) R2(roll)``), so ``s_b = R2(roll)^T R1(pitch)^T
R3(heading) sun_n``; the kernels apply these elementary rotations one by one, which also
gives the partial derivatives in closed form.

The sign of an E-vector is unknown, hence every solution comes in pairs; the INS prediction
picks one.  Kernels return NaN when no attitude reproduces the measurement (the filter must
skip that update).

The imaging solver :func:`imaging_pitch_heading` lives in
:mod:`fuzzynav.nav.polarization_imaging` and is re-exported here; the primitives both use
(folding, rotations, AoP gradient, sun partials) are in :mod:`fuzzynav.nav.polarization_geometry`.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.nav.attitude import wrap_pi
from fuzzynav.nav.polarization_geometry import (TWO_PI, aop_and_gradient, dot3, fold_half_pi,
                                                rot_x, rot_y, sun_body_partials)
from fuzzynav.nav.polarization_imaging import imaging_pitch_heading

__all__ = ["aop_attitude_jacobian", "aop_euler_partials", "heading_from_zenith_aop",
           "imaging_pitch_heading", "view_aop", "zenith_aop", "zenith_heading_roots",
           "zenith_heading_tilt_partials"]


@nb.njit(cache=True, error_model="numpy")
def view_aop(view_b, sun_b):
    """Angle of polarization [rad] in [-pi/2, pi/2) of a unit view direction.

    Parameters
    ----------
    view_b : ndarray, shape (3,)
        Unit view direction in the sensor (= body) frame.
    sun_b : ndarray, shape (3,)
        Sun direction in the same frame (need not be unit).
    """
    return aop_and_gradient(view_b, sun_b[0], sun_b[1], sun_b[2])[0]


@nb.njit(cache=True, error_model="numpy")
def zenith_aop(C_bn, sun_n):
    """Angle of polarization [rad] seen by a body-fixed zenith sensor.

    Parameters
    ----------
    C_bn : ndarray, shape (3, 3)
        Body-to-navigation DCM (true attitude).
    sun_n : ndarray, shape (3,)
        Unit ENU vector towards the sun.

    Returns
    -------
    float
        ``atan2(s_bx, -s_by)`` folded into [-pi/2, pi/2); NaN if the sun is on the sensor's
        boresight (unpolarized zenith).
    """
    sx = C_bn[0, 0] * sun_n[0] + C_bn[1, 0] * sun_n[1] + C_bn[2, 0] * sun_n[2]
    sy = C_bn[0, 1] * sun_n[0] + C_bn[1, 1] * sun_n[1] + C_bn[2, 1] * sun_n[2]
    if sx * sx + sy * sy < 1e-24:
        return np.nan
    return fold_half_pi(math.atan2(sx, -sy))


@nb.njit(cache=True, error_model="numpy")
def aop_attitude_jacobian(C_bn, view_b, sun_n):
    """AoP of a body view direction and its Jacobian on the attitude error.

    With the attitude error of :func:`fuzzynav.nav.attitude.attitude_error`,
    ``C_calc = (I - [phi x]) C_true``, ``aop(C_calc) = aop(C_true) + H . phi_n`` to first
    order; a filter measuring ``z = aop_meas - aop(C_ins)`` thus has ``z = -H phi + noise``.

    Parameters
    ----------
    C_bn : ndarray, shape (3, 3)
    view_b : ndarray, shape (3,)
        Unit view direction in the body frame (``[0, 0, 1]`` for the zenith sensor).
    sun_n : ndarray, shape (3,)

    Returns
    -------
    aop : float
        [rad] in [-pi/2, pi/2).
    H : ndarray, shape (3,)
        d aop / d phi_n [rad/rad].
    """
    s = C_bn.T @ sun_n
    aop, g0, g1, g2 = aop_and_gradient(view_b, s[0], s[1], s[2])
    g_n = C_bn @ np.array([g0, g1, g2])
    # d s_b / d phi = -C^T [s_n x]  =>  H = s_n x (C grad)
    H = np.empty(3)
    H[0] = sun_n[1] * g_n[2] - sun_n[2] * g_n[1]
    H[1] = sun_n[2] * g_n[0] - sun_n[0] * g_n[2]
    H[2] = sun_n[0] * g_n[1] - sun_n[1] * g_n[0]
    return aop, H


@nb.njit(cache=True, error_model="numpy")
def aop_euler_partials(view_b, sun_n, pitch, roll, heading):
    """AoP of a body view direction and its partials on the Euler angles.

    Returns
    -------
    aop, daop_dpitch, daop_droll, daop_dheading : float
        [rad] and [rad/rad].
    """
    s, ds_dp, ds_dr, ds_dh = sun_body_partials(sun_n, pitch, roll, heading)
    aop, g0, g1, g2 = aop_and_gradient(view_b, s[0], s[1], s[2])
    return aop, dot3(g0, g1, g2, ds_dp), dot3(g0, g1, g2, ds_dr), dot3(g0, g1, g2, ds_dh)


@nb.njit(cache=True, error_model="numpy")
def zenith_heading_roots(aop, sun_n, pitch, roll):
    """Both headings [rad] that make a zenith sensor read ``aop`` at the given tilt.

    Solves ``e_b . s_b = 0`` with ``e_b = [cos aop, sin aop, 0]`` in closed form:
    ``A cos h + B sin h + C = 0``.  On level ground the roots are 180° apart; with tilt
    and a high sun they draw closer (the tilt moves the sensor's view across the sky).

    Returns
    -------
    h1, h2 : float
        Roots in [0, 2 pi); NaN when no heading fits (AoP inconsistent with the tilt, or
        the sun on the sensor's boresight).
    """
    gx, gy, gz = rot_x(pitch, *rot_y(roll, math.cos(aop), math.sin(aop), 0.0))
    a = gx * sun_n[0] + gy * sun_n[1]
    b = gy * sun_n[0] - gx * sun_n[1]
    c = gz * sun_n[2]
    rho = math.hypot(a, b)
    if rho < 1e-12 or abs(c) > rho:
        return np.nan, np.nan
    h0 = math.atan2(b, a)
    d = math.acos(-c / rho)
    return (h0 + d) % TWO_PI, (h0 - d) % TWO_PI


@nb.njit(cache=True, error_model="numpy")
def heading_from_zenith_aop(aop, sun_n, pitch, roll, heading_prior):
    """Heading from a zenith sensor's AoP, the INS tilt and the INS heading prediction.

    Parameters
    ----------
    aop : float
        Measured angle of polarization [rad] (any representative modulo pi).
    sun_n : ndarray, shape (3,)
        Unit ENU vector towards the sun at the epoch.
    pitch, roll : float
        Tilt used for the conversion (the INS's) [rad].
    heading_prior : float
        INS heading prediction [rad]; picks the nearer of the two roots (180° ambiguity).

    Returns
    -------
    heading : float
        [rad] in [0, 2 pi); NaN if no heading reproduces ``aop`` at this tilt.
    dheading_daop : float
        Sensitivity ``d heading / d aop`` [rad/rad] at the solution: maps the AoP variance
        to a heading variance, ``var_h = dheading_daop^2 var_aop``.  It is exactly 1 on
        level ground, where turning the vehicle turns the sensor about its own boresight;
        with tilt the boresight is off the vertical and it departs from 1.
    """
    h1, h2 = zenith_heading_roots(aop, sun_n, pitch, roll)
    if np.isnan(h1):
        return np.nan, np.nan
    h = h1 if abs(wrap_pi(h1 - heading_prior)) <= abs(wrap_pi(h2 - heading_prior)) else h2
    v = np.array([0.0, 0.0, 1.0])
    dh = aop_euler_partials(v, sun_n, pitch, roll, h)[3]
    return h, (1.0 / dh if dh != 0.0 else np.inf)


@nb.njit(cache=True, error_model="numpy")
def zenith_heading_tilt_partials(sun_n, pitch, roll, heading):
    """How the zenith-sensor heading moves with the tilt used to convert it.

    If the INS tilt is off by ``(dpitch, droll)``, the converted heading is off by
    ``dh_dpitch dpitch + dh_droll droll`` (implicit differentiation of the AoP model at
    fixed AoP): the coupling a filter that feeds polarization headings must model.

    Returns
    -------
    dheading_dpitch, dheading_droll : float
        [rad/rad].
    """
    v = np.array([0.0, 0.0, 1.0])
    _, dp, dr, dh = aop_euler_partials(v, sun_n, pitch, roll, heading)
    if dh == 0.0:  # double root: the heading does not follow the tilt smoothly
        return np.inf, np.inf
    return -dp / dh, -dr / dh
