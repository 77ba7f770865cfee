"""Pitch and heading from an imaging polarization sensor (several view directions), given roll.

The numba kernel :func:`imaging_pitch_heading` (re-exported by :mod:`fuzzynav.nav.polarization_solver`,
whose docstring states the measurement model) runs at every imaging epoch inside the compiled
filter as :func:`imaging_fit_sun` (the data rows carry the AoPs' cosines and sines and the
sun's body direction of :func:`sun_from_aops`,
:mod:`fuzzynav.filters.measurements.polarization_rows`), so it works on plain floats and
allocates nothing: the views' reference frames computed once per run (:func:`view_frames`),
the smallest eigenvector of a symmetric 3x3 in closed form, candidates skipped before their
trigonometry when they cannot win, the roll rotation computed once per fit and the sun's body
direction and its partials once per Gauss-Newton iterate (shared by all views), a stop as
soon as the step falls below :data:`_STEP_TOL` (the last undamped step below
:data:`_STEP_LAST` taken without evaluating after it), and the solution's roll sensitivity
from the sums of the fit's last evaluation.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.nav.attitude import mod_pos, wrap_pi
from fuzzynav.nav.polarization_geometry import (HALF_PI, TWO_PI, aop_residual_and_gradient3,
                                                dot3, rot_x, rot_y_cs, sun_body_partials_cs)

__all__ = ["FRAME", "view_frames", "aop_trig", "imaging_pitch_heading", "imaging_fit",
           "imaging_fit_frames", "sun_from_aops", "imaging_fit_sun"]

#: entries per view in a frames array (:func:`view_frames`): view, x reference, y reference
FRAME = 9

#: how far (sine of elevation) a noisy sun direction may miss the reachable elevations
_FOLD_SLACK = 0.05
#: Gauss-Newton stops when the step [rad] (|pitch| + |heading|), or the change it makes to
#: the fitted AoPs (root sum of squares), is below this
_STEP_TOL = 1e-12
#: an undamped step below this [rad] is taken without evaluating the residuals after it:
#: Gauss-Newton converges at least linearly there, so the fit ends within a fraction of it
#: of the minimum (AoP noise is ~1e-3 rad), and J^T J from before the step differs from
#: the one after it in the tenth digit
_STEP_LAST = 1e-10
#: relative round-off of the cost: how much a nearly undamped step may raise it
_COST_RTOL = 1e-10
#: Levenberg damping (relative to the mean diagonal of J^T J): start, floor, give-up, and
#: the level up to which a step counts as undamped
_LAM_START, _LAM_MIN, _LAM_MAX, _LAM_UNDAMPED = 1e-9, 1e-12, 1e10, 1e-6
_MAX_ITER = 200


@nb.njit(cache=True, error_model="numpy")
def view_frames(views_b):
    """Per-view constants of a sensor, flat: ``[v, x_ref, y_ref]`` (9 entries a view).

    ``x_ref`` is the body x axis projected perpendicular to ``v`` (where each AoP is measured
    from) and ``y_ref = v x x_ref``; a filter computes them once per run (its sensor
    parameters), not at every epoch.
    """
    k = views_b.shape[0]
    out = np.empty(FRAME * k)
    for i in range(k):
        vx, vy, vz = views_b[i, 0], views_b[i, 1], views_b[i, 2]
        xx, xy, xz = 1.0 - vx * vx, -vx * vy, -vx * vz
        nx = math.sqrt(xx * xx + xy * xy + xz * xz)
        xx, xy, xz = xx / nx, xy / nx, xz / nx
        yx, yy, yz = vy * xz - vz * xy, vz * xx - vx * xz, vx * xy - vy * xx
        o = FRAME * i
        out[o], out[o + 1], out[o + 2] = vx, vy, vz
        out[o + 3], out[o + 4], out[o + 5] = xx, xy, xz
        out[o + 6], out[o + 7], out[o + 8] = yx, yy, yz
    return out


@nb.njit(cache=True, error_model="numpy")
def aop_trig(aops):
    """``[cos aop_1..k, sin aop_1..k]`` of one epoch (NaN where the AoP is NaN).

    The fit needs them for the E-vectors and for every residual (where they spare an
    ``atan2`` per view and iterate); one small array per epoch.
    """
    k = aops.shape[0]
    out = np.empty(2 * k)
    for i in range(k):
        out[i], out[k + i] = math.cos(aops[i]), math.sin(aops[i])
    return out


@nb.njit(cache=True, error_model="numpy")
def _e_vector_scatter(aops, trig, frames):
    """``sum e e^T`` (6 entries) of the measured body-frame E-vectors; count used (no NaN)."""
    m00 = m01 = m02 = m11 = m12 = m22 = 0.0
    k, k_all = 0, aops.shape[0]
    for i in range(aops.shape[0]):
        if np.isnan(aops[i]):
            continue
        o = FRAME * i
        ca, sa = trig[i], trig[k_all + i]
        ex = ca * frames[o + 3] + sa * frames[o + 6]
        ey = ca * frames[o + 4] + sa * frames[o + 7]
        ez = ca * frames[o + 5] + sa * frames[o + 8]
        m00 += ex * ex
        m01 += ex * ey
        m02 += ex * ez
        m11 += ey * ey
        m12 += ey * ez
        m22 += ez * ez
        k += 1
    return m00, m01, m02, m11, m12, m22, k


@nb.njit(cache=True, error_model="numpy")
def _smallest_eigenvector(m00, m01, m02, m11, m12, m22):
    """Unit eigenvector (sign arbitrary) of a symmetric 3x3 for its smallest eigenvalue.

    The eigenvalue in closed form (trigonometric solution of the characteristic cubic), the
    vector as the largest cross product of two rows of ``M - lambda I`` (they span the plane
    perpendicular to it).  If the smallest eigenvalue is double (E-vectors all parallel) the
    rows are parallel and their cross product is still some vector of that eigenspace, as an
    iterative solver would return; NaN only for ``M = q I`` (no preferred direction at all).
    """
    q = (m00 + m11 + m22) / 3.0
    b00, b11, b22 = m00 - q, m11 - q, m22 - q
    p2 = (b00 * b00 + b11 * b11 + b22 * b22
          + 2.0 * (m01 * m01 + m02 * m02 + m12 * m12)) / 6.0
    if not p2 > 0.0:
        return np.nan, np.nan, np.nan
    p = math.sqrt(p2)
    det_b = (b00 * (b11 * b22 - m12 * m12) - m01 * (m01 * b22 - m12 * m02)
             + m02 * (m01 * m12 - b11 * m02))
    phi = math.acos(min(1.0, max(-1.0, 0.5 * det_b / (p2 * p)))) / 3.0
    lam = q + 2.0 * p * math.cos(phi + TWO_PI / 3.0)
    a00, a11, a22 = m00 - lam, m11 - lam, m22 - lam
    best_x = best_y = best_z = best_n = 0.0
    for rx, ry, rz, tx, ty, tz in ((a00, m01, m02, m01, a11, m12),
                                   (a00, m01, m02, m02, m12, a22),
                                   (m01, a11, m12, m02, m12, a22)):
        cx, cy, cz = ry * tz - rz * ty, rz * tx - rx * tz, rx * ty - ry * tx
        n = cx * cx + cy * cy + cz * cz
        if n > best_n:
            best_x, best_y, best_z, best_n = cx, cy, cz, n
    if not best_n > 0.0:
        return np.nan, np.nan, np.nan
    inv = 1.0 / math.sqrt(best_n)
    return best_x * inv, best_y * inv, best_z * inv


@nb.njit(cache=True, error_model="numpy")
def _nearest_candidate(sx, sy, sz, sun_n, sun_azimuth, c_roll, s_roll, pitch_prior,
                       heading_prior, pitch_prior_std, heading_prior_std):
    """Of the up to four attitudes with ``C_bn (+-s_b) = sun_n``, the nearest to the prior.

    ``u = R2(roll) s_b`` must rise to the sun's elevation under ``R1(pitch)``:
    ``rho cos(pitch - p0) = sun_U``, roots ``p0 +- d``; ``-u`` has them shifted by pi.  Near the
    fold (sun abeam) noise can lift the sun's elevation just out of reach of any pitch; up to
    ``_FOLD_SLACK`` the fold point itself is a candidate and Gauss-Newton refines.  Distances
    in prior standard deviations; NaN when no candidate exists.  ``c_roll, s_roll`` are
    ``cos(-roll), sin(-roll)`` (shared with the fit).  The heading term of a
    distance only adds to its pitch term (rounding is monotonic), so a candidate whose pitch
    alone is no nearer than the best so far is skipped before its trigonometry: the same
    choice, fewer ``cos``/``sin``/``atan2``.
    """
    ux, uy, uz = rot_y_cs(c_roll, -s_roll, sx, sy, sz)  # R2(roll): c_roll, s_roll of -roll
    rho = math.hypot(uy, uz)
    if rho < 1e-12 or abs(sun_n[2]) > rho + _FOLD_SLACK:
        return np.nan, np.nan
    p0 = math.atan2(uy, uz)
    d = math.acos(min(1.0, max(-1.0, sun_n[2] / rho)))
    best_p, best_h, best_d = np.nan, np.nan, np.inf
    for sign, shift in ((1.0, 0.0), (-1.0, math.pi)):
        for root in (p0 + shift + d, p0 + shift - d):
            p = wrap_pi(root)
            if abs(p) > HALF_PI:
                continue  # no attitude with this pitch
            dist_p = (wrap_pi(p - pitch_prior) / pitch_prior_std) ** 2
            if not dist_p < best_d:  # cannot win (or NaN)
                continue
            wx, wy, _ = rot_x(p, sign * ux, sign * uy, sign * uz)
            h = mod_pos(math.atan2(wy, wx) - sun_azimuth, TWO_PI)
            dist = dist_p + (wrap_pi(h - heading_prior) / heading_prior_std) ** 2
            if dist < best_d:  # False for an absent (NaN) candidate
                best_p, best_h, best_d = p, h, dist
    return best_p, best_h


@nb.njit(cache=True, error_model="numpy")
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
    p, h, c00, c01, c11, k = imaging_fit(aops, views_b, sun_n, roll, pitch_prior,
                                         heading_prior, pitch_prior_std, heading_prior_std,
                                         sigma_aop)
    cov = np.empty((2, 2))
    cov[0, 0], cov[1, 1] = c00, c11
    cov[0, 1] = cov[1, 0] = c01
    return p, h, cov, k


@nb.njit(cache=True, error_model="numpy")
def imaging_fit(aops, views_b, sun_n, roll, pitch_prior, heading_prior, pitch_prior_std,
                heading_prior_std, sigma_aop):
    """:func:`imaging_pitch_heading` with the covariance as three scalars:
    ``pitch, heading, c_pp, c_ph, c_hh, n_used``."""
    return imaging_fit_frames(aops, aop_trig(aops), view_frames(views_b), sun_n,
                              math.atan2(sun_n[1], sun_n[0]), roll, pitch_prior,
                              heading_prior, pitch_prior_std, heading_prior_std,
                              sigma_aop)[:6]


@nb.njit(cache=True, error_model="numpy")
def imaging_fit_frames(aops, trig, frames, sun_n, sun_azimuth, roll, pitch_prior,
                       heading_prior, pitch_prior_std, heading_prior_std, sigma_aop):
    """:func:`imaging_fit` on precomputed :func:`view_frames` and :func:`aop_trig`, without
    allocation, and how the solution moves with the roll.

    Returns ``pitch, heading, c_pp, c_ph, c_hh, n_used, dpitch_droll, dheading_droll``; the
    last two by implicit differentiation of the normal equations at fixed AoPs,
    ``-(J^T J)^-1 J^T d aop/d roll``, from the sums of the fit's last evaluation.
    ``sun_azimuth`` is ``atan2(sun_n[1], sun_n[0])``.  :func:`sun_from_aops` and
    :func:`imaging_fit_sun` are its two halves.
    """
    sx, sy, sz, k = sun_from_aops(aops, trig, frames)
    return imaging_fit_sun(aops, trig, frames, sun_n, sun_azimuth, sx, sy, sz, k, roll,
                           pitch_prior, heading_prior, pitch_prior_std, heading_prior_std,
                           sigma_aop)


@nb.njit(cache=True, error_model="numpy")
def sun_from_aops(aops, trig, frames):
    """The sun's body direction (sign arbitrary) from the AoPs alone, and the views used:
    ``sx, sy, sz, n_used`` (NaN direction with fewer than two views).  It depends on the
    data only, so the filter's data rows carry it (:mod:`fuzzynav.filters.measurements.
    polarization_rows`)."""
    m00, m01, m02, m11, m12, m22, k = _e_vector_scatter(aops, trig, frames)
    if k < 2:
        return np.nan, np.nan, np.nan, k
    sx, sy, sz = _smallest_eigenvector(m00, m01, m02, m11, m12, m22)
    return sx, sy, sz, k


@nb.njit(cache=True, error_model="numpy")
def imaging_fit_sun(aops, trig, frames, sun_n, sun_azimuth, sx, sy, sz, k, roll, pitch_prior,
                    heading_prior, pitch_prior_std, heading_prior_std, sigma_aop):
    """:func:`imaging_fit_frames` from the sun's body direction ``sx, sy, sz`` and the view
    count ``k`` of :func:`sun_from_aops`: the candidates nearest the prior, then the fit."""
    nan = np.nan
    if k < 2:
        return nan, nan, nan, nan, nan, k, nan, nan
    c_roll, s_roll = math.cos(-roll), math.sin(-roll)  # fixed for the whole fit
    p, h = _nearest_candidate(sx, sy, sz, sun_n, sun_azimuth, c_roll, s_roll, pitch_prior,
                              heading_prior, pitch_prior_std, heading_prior_std)
    if np.isnan(p):
        return nan, nan, nan, nan, nan, k, nan, nan
    p, h, n00, n01, n11, b0, b1 = _gauss_newton(aops, trig, frames, sun_n, c_roll, s_roll, p, h)
    det = n00 * n11 - n01 * n01
    if not det > 0.0:
        return nan, nan, nan, nan, nan, k, nan, nan
    s2 = sigma_aop * sigma_aop / det
    h_out = mod_pos(h, TWO_PI)
    if h_out != h:  # the sensitivity at the heading reported (differs in the last digits)
        n00r, n01r, n11r, _, _, _, b0, b1 = _normal_equations(aops, trig, frames, sun_n, c_roll,
                                                              s_roll, p, h_out)
        dp_dr, dh_dr = _roll_sensitivity(n00r, n01r, n11r, b0, b1)
    else:
        dp_dr, dh_dr = _roll_sensitivity(n00, n01, n11, b0, b1)
    return p, h_out, s2 * n11, -s2 * n01, s2 * n00, k, dp_dr, dh_dr


@nb.njit(cache=True, error_model="numpy")
def _roll_sensitivity(a00, a01, a11, b0, b1):
    """``d(pitch, heading)/d(roll)`` from ``J^T J`` and ``J^T d aop/d roll``; NaN if singular."""
    det = a00 * a11 - a01 * a01
    if not det > 0.0:
        return np.nan, np.nan
    return -(a11 * b0 - a01 * b1) / det, -(a00 * b1 - a01 * b0) / det


@nb.njit(cache=True, error_model="numpy")
def _normal_equations(aops, trig, frames, sun_n, c_roll, s_roll, p, h):
    """``J^T J`` (3 entries), ``J^T r``, the cost ``r^T r`` of the AoP residuals and
    ``J^T d aop/d roll`` (2 entries; a few products a view, spares a separate pass)."""
    # the sun's body direction and its partials are the same for every view
    s, ds_dp, ds_dr, ds_dh = sun_body_partials_cs(sun_n, p, c_roll, s_roll, h)
    n00 = n01 = n11 = g0 = g1 = cost = b0 = b1 = 0.0
    k = aops.shape[0]
    for i in range(k):
        if np.isnan(aops[i]):
            continue
        o = FRAME * i
        r, ga, gb, gc = aop_residual_and_gradient3(trig[i], trig[k + i], frames[o],
                                                   frames[o + 1], frames[o + 2], s[0], s[1],
                                                   s[2])
        dp, dh = dot3(ga, gb, gc, ds_dp), dot3(ga, gb, gc, ds_dh)
        dr = dot3(ga, gb, gc, ds_dr)
        n00 += dp * dp
        n01 += dp * dh
        n11 += dh * dh
        g0 += dp * r
        g1 += dh * r
        cost += r * r
        b0 += dp * dr
        b1 += dh * dr
    return n00, n01, n11, g0, g1, cost, b0, b1


@nb.njit(cache=True, error_model="numpy")
def _gauss_newton(aops, trig, frames, sun_n, c_roll, s_roll, p, h):
    """Least-squares (pitch, heading) of the AoP residuals; ``J^T J``, ``J^T d aop/d roll``.

    Gauss-Newton with Levenberg damping: the start can sit on the fold where J^T J is
    singular (noisy sun abeam); the damping steps off it and fades as the fit converges.
    Near the minimum a Gauss-Newton step changes the cost by less than the cost's round-off,
    so a nearly undamped step is accepted unless it raises the cost by more than
    ``_COST_RTOL`` (rejecting it would only inflate the damping and stall the fit short of the
    minimum); damped steps must lower the cost.  A fit whose minimum lies on the fold itself
    creeps along a flat valley until the damped steps vanish (tens of iterations, at most
    ``_MAX_ITER``); its covariance then says the attitude is undetermined.
    """
    n00, n01, n11, g0, g1, cost, b0, b1 = _normal_equations(aops, trig, frames, sun_n, c_roll,
                                                             s_roll, p, h)
    lam = _LAM_START
    for _ in range(_MAX_ITER):
        damp = lam * 0.5 * (n00 + n11)
        d00, d11 = n00 + damp, n11 + damp
        det = d00 * d11 - n01 * n01
        if not det > 0.0:
            break
        step_p = (d11 * g0 - n01 * g1) / det
        step_h = (d00 * g1 - n01 * g0) / det
        # |J step|^2: how far the step would move the fitted AoPs
        moved = step_p * (n00 * step_p + 2.0 * n01 * step_h) + n11 * step_h * step_h
        if abs(step_p) + abs(step_h) < _STEP_TOL or moved < _STEP_TOL * _STEP_TOL:
            break
        if abs(step_p) + abs(step_h) < _STEP_LAST and lam <= _LAM_UNDAMPED:
            return p + step_p, h + step_h, n00, n01, n11, b0, b1
        trial = _normal_equations(aops, trig, frames, sun_n, c_roll, s_roll, p + step_p,
                                  h + step_h)
        slack = _COST_RTOL if lam <= _LAM_UNDAMPED else 0.0
        if trial[5] <= cost * (1.0 + slack):
            p, h = p + step_p, h + step_h
            n00, n01, n11, g0, g1, cost, b0, b1 = trial
            lam = max(lam * 0.1, _LAM_MIN)
        else:
            lam *= 10.0
            if lam > _LAM_MAX:
                break
    return p, h, n00, n01, n11, b0, b1
