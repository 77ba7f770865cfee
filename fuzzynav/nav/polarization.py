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
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

_HALF_PI = 0.5 * math.pi
_TWO_PI = 2.0 * math.pi
#: how far (sine of elevation) a noisy sun direction may miss the reachable elevations
_FOLD_SLACK = 0.05


@nb.njit(cache=True)
def _fold(a):
    """Axial angle folded into [-pi/2, pi/2)."""
    return (a + _HALF_PI) % math.pi - _HALF_PI


@nb.njit(cache=True)
def _wrap(a):
    """Angle wrapped into [-pi, pi)."""
    return (a + math.pi) % _TWO_PI - math.pi


@nb.njit(cache=True)
def _rot_z(ang, x, y, z):
    """Active rotation by ``ang`` about z (R3)."""
    c, s = math.cos(ang), math.sin(ang)
    return c * x - s * y, s * x + c * y, z


@nb.njit(cache=True)
def _rot_x(ang, x, y, z):
    """Active rotation by ``ang`` about x (R1)."""
    c, s = math.cos(ang), math.sin(ang)
    return x, c * y - s * z, s * y + c * z


@nb.njit(cache=True)
def _rot_y(ang, x, y, z):
    """Active rotation by ``ang`` about y (R2)."""
    c, s = math.cos(ang), math.sin(ang)
    return c * x + s * z, y, -s * x + c * z


@nb.njit(cache=True)
def _aop_and_gradient(v, sx, sy, sz):
    """AoP of view ``v`` for sun ``s`` (body frame) and its gradient d aop / d s."""
    c = v[0] * sx + v[1] * sy + v[2] * sz
    num = sx - v[0] * c
    den = v[1] * sz - v[2] * sy
    q = num * num + den * den
    if q == 0.0:  # sun on the view axis: unpolarized, no angle
        return np.nan, np.nan, np.nan, np.nan
    # d num/ds = e_x - v_x v ; d den/ds = (0, -v_z, v_y)
    g0 = (den * (1.0 - v[0] * v[0])) / q
    g1 = (den * (-v[0] * v[1]) + num * v[2]) / q
    g2 = (den * (-v[0] * v[2]) - num * v[1]) / q
    return _fold(math.atan2(num, den)), g0, g1, g2


@nb.njit(cache=True)
def view_aop(view_b, sun_b):
    """Angle of polarization [rad] in [-pi/2, pi/2) of a unit view direction.

    Parameters
    ----------
    view_b : ndarray, shape (3,)
        Unit view direction in the sensor (= body) frame.
    sun_b : ndarray, shape (3,)
        Sun direction in the same frame (need not be unit).
    """
    return _aop_and_gradient(view_b, sun_b[0], sun_b[1], sun_b[2])[0]


@nb.njit(cache=True)
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
    return _fold(math.atan2(sx, -sy))


@nb.njit(cache=True)
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
    aop, g0, g1, g2 = _aop_and_gradient(view_b, s[0], s[1], s[2])
    g_n = C_bn @ np.array([g0, g1, g2])
    # d s_b / d phi = -C^T [s_n x]  =>  H = s_n x (C grad)
    H = np.empty(3)
    H[0] = sun_n[1] * g_n[2] - sun_n[2] * g_n[1]
    H[1] = sun_n[2] * g_n[0] - sun_n[0] * g_n[2]
    H[2] = sun_n[0] * g_n[1] - sun_n[1] * g_n[0]
    return aop, H


@nb.njit(cache=True)
def aop_euler_partials(view_b, sun_n, pitch, roll, heading):
    """AoP of a body view direction and its partials on the Euler angles.

    Returns
    -------
    aop, daop_dpitch, daop_droll, daop_dheading : float
        [rad] and [rad/rad].
    """
    tx, ty, tz = _rot_z(heading, sun_n[0], sun_n[1], sun_n[2])
    ux, uy, uz = _rot_x(-pitch, tx, ty, tz)
    sx, sy, sz = _rot_y(-roll, ux, uy, uz)
    aop, g0, g1, g2 = _aop_and_gradient(view_b, sx, sy, sz)
    # d/dheading: R3' = [e_z x] R3 ; d/dpitch: R1(-p)' = -[e_x x] R1(-p) ; same for roll
    hx, hy, hz = _rot_y(-roll, *_rot_x(-pitch, -ty, tx, 0.0))
    px, py, pz = _rot_y(-roll, 0.0, uz, -uy)
    rx, ry, rz = -sz, 0.0, sx
    return (aop, g0 * px + g1 * py + g2 * pz, g0 * rx + g1 * ry + g2 * rz,
            g0 * hx + g1 * hy + g2 * hz)


@nb.njit(cache=True)
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
    gx, gy, gz = _rot_x(pitch, *_rot_y(roll, math.cos(aop), math.sin(aop), 0.0))
    a = gx * sun_n[0] + gy * sun_n[1]
    b = gy * sun_n[0] - gx * sun_n[1]
    c = gz * sun_n[2]
    rho = math.hypot(a, b)
    if rho < 1e-12 or abs(c) > rho:
        return np.nan, np.nan
    h0 = math.atan2(b, a)
    d = math.acos(-c / rho)
    return (h0 + d) % _TWO_PI, (h0 - d) % _TWO_PI


@nb.njit(cache=True)
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
    h = h1 if abs(_wrap(h1 - heading_prior)) <= abs(_wrap(h2 - heading_prior)) else h2
    v = np.array([0.0, 0.0, 1.0])
    dh = aop_euler_partials(v, sun_n, pitch, roll, h)[3]
    return h, (1.0 / dh if dh != 0.0 else np.inf)


@nb.njit(cache=True)
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


@nb.njit(cache=True)
def _image_e_vectors(aops, views_b):
    """Measured E-vectors in the body frame from AoPs (NaN rows skipped); count used."""
    n = aops.shape[0]
    e = np.zeros((n, 3))
    k = 0
    for i in range(n):
        if np.isnan(aops[i]):
            continue
        vx, vy, vz = views_b[i, 0], views_b[i, 1], views_b[i, 2]
        # local reference: x_b projected perpendicular to v, then y = v x x_ref
        xx, xy, xz = 1.0 - vx * vx, -vx * vy, -vx * vz
        nx = math.sqrt(xx * xx + xy * xy + xz * xz)
        xx, xy, xz = xx / nx, xy / nx, xz / nx
        yx, yy, yz = vy * xz - vz * xy, vz * xx - vx * xz, vx * xy - vy * xx
        ca, sa = math.cos(aops[i]), math.sin(aops[i])
        e[k, 0], e[k, 1], e[k, 2] = ca * xx + sa * yx, ca * xy + sa * yy, ca * xz + sa * yz
        k += 1
    return e[:k], k


@nb.njit(cache=True)
def _pitch_heading_candidates(s_b, sun_n, roll):
    """(pitch, heading) pairs with ``C_bn(pitch, roll, heading) s_b = sun_n``, up to 2.

    Near the fold (sun abeam) noise can lift the sun's elevation just out of reach of any
    pitch; up to ``_FOLD_SLACK`` the fold point itself is returned and Gauss-Newton refines.
    """
    out = np.full((2, 2), np.nan)
    ux, uy, uz = _rot_y(roll, s_b[0], s_b[1], s_b[2])
    rho = math.hypot(uy, uz)
    if rho < 1e-12 or abs(sun_n[2]) > rho + _FOLD_SLACK:
        return out
    p0 = math.atan2(uy, uz)
    d = math.acos(min(1.0, max(-1.0, sun_n[2] / rho)))
    for j in range(2):
        p = _wrap(p0 + d if j == 0 else p0 - d)
        if abs(p) > _HALF_PI:
            continue
        wx, wy, _ = _rot_x(p, ux, uy, uz)
        out[j, 0] = p
        out[j, 1] = (math.atan2(wy, wx) - math.atan2(sun_n[1], sun_n[0])) % _TWO_PI
    return out


@nb.njit(cache=True)
def imaging_pitch_heading(aops, views_b, sun_n, roll, pitch_prior, heading_prior,
                          pitch_prior_std, heading_prior_std, sigma_aop):
    """Pitch and heading from the AoPs of several view directions, given the roll.

    The sun direction in the body frame is perpendicular to every E-vector: it is the
    eigenvector of ``sum e e^T`` with the smallest eigenvalue (exact for noise-free data).
    Its sign and the two pitch roots give up to four attitudes; the one nearest the INS
    prior (in prior standard deviations) starts a Gauss-Newton least-squares fit of all
    AoPs (residuals folded mod pi).  The two pitch roots can lie close together (their
    headings then differ little), so the pitch prior does most of the choosing.

    Parameters
    ----------
    aops : ndarray, shape (k,)
        Measured AoPs [rad]; NaN entries (view below the DoP threshold) are skipped.
    views_b : ndarray, shape (k, 3)
        Unit view directions in the body frame (nominal mounting), none along +-x_b.
    sun_n : ndarray, shape (3,)
    roll : float
        Roll taken from the INS [rad] (not estimated, as in paper 000).
    pitch_prior, heading_prior : float
        INS prediction [rad], resolves the ambiguities.
    pitch_prior_std, heading_prior_std : float
        1-sigma of that prediction [rad] (e.g. from the filter covariance): weights of the
        distance to the candidates.
    sigma_aop : float
        1-sigma AoP noise [rad] for the covariance.

    Returns
    -------
    pitch, heading : float
        [rad]; heading in [0, 2 pi).  NaN if fewer than two valid views or no attitude
        fits.
    cov : ndarray, shape (2, 2)
        Covariance of (pitch, heading) [rad^2], ``sigma^2 (J^T J)^-1``; NaN when failed.
    n_used : int
        Number of views used.
    """
    cov = np.full((2, 2), np.nan)
    e, k = _image_e_vectors(aops, views_b)
    if k < 2:
        return np.nan, np.nan, cov, k
    _, vecs = np.linalg.eigh(e.T @ e)
    best_p, best_h, best_d = np.nan, np.nan, np.inf
    for sign in (1.0, -1.0):
        cand = _pitch_heading_candidates(sign * vecs[:, 0], sun_n, roll)
        for j in range(2):
            if np.isnan(cand[j, 0]):
                continue
            d = ((_wrap(cand[j, 0] - pitch_prior) / pitch_prior_std) ** 2
                 + (_wrap(cand[j, 1] - heading_prior) / heading_prior_std) ** 2)
            if d < best_d:
                best_p, best_h, best_d = cand[j, 0], cand[j, 1], d
    if np.isnan(best_p):
        return np.nan, np.nan, cov, k
    p, h, jtj = _gauss_newton(aops, views_b, sun_n, roll, best_p, best_h)
    det = jtj[0, 0] * jtj[1, 1] - jtj[0, 1] * jtj[1, 0]
    if not det > 0.0:
        return np.nan, np.nan, cov, k
    s2 = sigma_aop * sigma_aop / det
    cov[0, 0], cov[1, 1] = s2 * jtj[1, 1], s2 * jtj[0, 0]
    cov[0, 1] = cov[1, 0] = -s2 * jtj[0, 1]
    return p, h % _TWO_PI, cov, k


@nb.njit(cache=True)
def _normal_equations(aops, views_b, sun_n, roll, p, h):
    """``J^T J`` (3 entries), ``J^T r`` and the cost ``r^T r`` of the AoP residuals."""
    n00 = n01 = n11 = g0 = g1 = cost = 0.0
    for i in range(aops.shape[0]):
        if np.isnan(aops[i]):
            continue
        a, dp, _, dh = aop_euler_partials(views_b[i], sun_n, p, roll, h)
        r = _fold(aops[i] - a)
        n00 += dp * dp
        n01 += dp * dh
        n11 += dh * dh
        g0 += dp * r
        g1 += dh * r
        cost += r * r
    return n00, n01, n11, g0, g1, cost


@nb.njit(cache=True)
def _gauss_newton(aops, views_b, sun_n, roll, p, h):
    """Least-squares (pitch, heading) of the AoP residuals; returns J^T J at the end.

    Gauss-Newton with Levenberg damping: the start can sit on the fold where J^T J is
    singular (noisy sun abeam); the damping steps off it and fades as the fit converges.
    """
    n00, n01, n11, g0, g1, cost = _normal_equations(aops, views_b, sun_n, roll, p, h)
    lam = 1e-9
    for _ in range(200):
        damp = lam * 0.5 * (n00 + n11)
        d00, d11 = n00 + damp, n11 + damp
        det = d00 * d11 - n01 * n01
        if not det > 0.0:
            break
        step_p = (d11 * g0 - n01 * g1) / det
        step_h = (d00 * g1 - n01 * g0) / det
        trial = _normal_equations(aops, views_b, sun_n, roll, p + step_p, h + step_h)
        if trial[5] <= cost:
            p, h = p + step_p, h + step_h
            n00, n01, n11, g0, g1, cost = trial
            lam = max(lam * 0.1, 1e-12)
            if abs(step_p) + abs(step_h) < 1e-13:
                break
        else:
            lam *= 10.0
            if lam > 1e10:
                break
    jtj = np.empty((2, 2))
    jtj[0, 0], jtj[0, 1], jtj[1, 0], jtj[1, 1] = n00, n01, n01, n11
    return p, h, jtj
