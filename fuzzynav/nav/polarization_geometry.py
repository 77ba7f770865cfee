"""Numba primitives of the skylight AoP model shared by the polarization solvers.

Angle folding, the elementary rotations of the Euler sequence of :mod:`fuzzynav.nav.attitude`,
the AoP of a body view direction with its gradient on the body sun direction, and the body
sun direction with its partials on the Euler angles.  The model and its conventions are
described in :mod:`fuzzynav.nav.polarization_solver`.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.nav.attitude import mod_pos

__all__ = ["HALF_PI", "TWO_PI", "atan_small", "fold_half_pi", "rot_z", "rot_x", "rot_y",
           "rot_x_cs", "rot_y_cs", "aop_unfolded_and_gradient", "aop_unfolded_and_gradient3",
           "aop_residual_and_gradient3", "aop_gradient", "aop_and_gradient",
           "sun_body_partials", "sun_body_partials_cs", "dot3"]

HALF_PI = 0.5 * math.pi
TWO_PI = 2.0 * math.pi


#: below this |t| :func:`atan_small` sums the Taylor series; its first omitted term,
#: t^13 / 13, is then under 2e-17 of the result: a fraction of an ulp
_ATAN_SERIES = 0.05
_R3, _R7, _R9, _R11 = 1.0 / 3.0, 1.0 / 7.0, 1.0 / 9.0, 1.0 / 11.0


@nb.njit(cache=True, error_model="numpy")
def atan_small(t):
    """``atan(t)``, by its Taylor series through ``t^11`` for ``|t| <`` :data:`_ATAN_SERIES`.

    The AoP residuals of a converging fit are such small tangents: a few products where the
    library call costs several times more (equal to it within a few ulp).
    """
    if abs(t) < _ATAN_SERIES:
        t2 = t * t
        return t - t * t2 * (_R3 - t2 * (0.2 - t2 * (_R7 - t2 * (_R9 - t2 * _R11))))
    return math.atan(t)


@nb.njit(cache=True, error_model="numpy")
def fold_half_pi(a):
    """Axial angle folded into [-pi/2, pi/2)."""
    return mod_pos(a + HALF_PI, math.pi) - HALF_PI


@nb.njit(cache=True, error_model="numpy")
def rot_z(ang, x, y, z):
    """Active rotation by ``ang`` about z (R3)."""
    c, s = math.cos(ang), math.sin(ang)
    return c * x - s * y, s * x + c * y, z


@nb.njit(cache=True, error_model="numpy")
def rot_x(ang, x, y, z):
    """Active rotation by ``ang`` about x (R1)."""
    return rot_x_cs(math.cos(ang), math.sin(ang), x, y, z)


@nb.njit(cache=True, error_model="numpy")
def rot_y(ang, x, y, z):
    """Active rotation by ``ang`` about y (R2)."""
    return rot_y_cs(math.cos(ang), math.sin(ang), x, y, z)


@nb.njit(cache=True, error_model="numpy")
def rot_x_cs(c, s, x, y, z):
    """:func:`rot_x` by the angle of cosine ``c`` and sine ``s`` (shared by several calls)."""
    return x, c * y - s * z, s * y + c * z


@nb.njit(cache=True, error_model="numpy")
def rot_y_cs(c, s, x, y, z):
    """:func:`rot_y` by the angle of cosine ``c`` and sine ``s`` (shared by several calls)."""
    return c * x + s * z, y, -s * x + c * z


@nb.njit(cache=True, error_model="numpy")
def _num_den(v, sx, sy, sz):
    """Numerator and denominator of the AoP ``atan2`` of view ``v`` for sun ``s``."""
    return _num_den3(v[0], v[1], v[2], sx, sy, sz)


@nb.njit(cache=True, error_model="numpy")
def _num_den3(vx, vy, vz, sx, sy, sz):
    c = vx * sx + vy * sy + vz * sz
    return sx - vx * c, vy * sz - vz * sy


@nb.njit(cache=True, error_model="numpy")
def _gradient(v, num, den):
    """d aop / d s from the ``atan2`` arguments (``num`` and ``den`` not both zero)."""
    return _gradient3(v[0], v[1], v[2], num, den)


@nb.njit(cache=True, error_model="numpy")
def _gradient3(vx, vy, vz, num, den):
    inv_q = 1.0 / (num * num + den * den)
    # d num/ds = e_x - v_x v ; d den/ds = (0, -v_z, v_y)
    g0 = den * (1.0 - vx * vx) * inv_q
    g1 = (den * (-vx * vy) + num * vz) * inv_q
    g2 = (den * (-vx * vz) - num * vy) * inv_q
    return g0, g1, g2


@nb.njit(cache=True, error_model="numpy")
def aop_unfolded_and_gradient(v, sx, sy, sz):
    """AoP of view ``v`` for sun ``s`` (body frame) in (-pi, pi] and d aop / d s.

    The angle is not folded: a caller forming a residual folds the difference once.
    """
    return aop_unfolded_and_gradient3(v[0], v[1], v[2], sx, sy, sz)


@nb.njit(cache=True, error_model="numpy")
def aop_unfolded_and_gradient3(vx, vy, vz, sx, sy, sz):
    """:func:`aop_unfolded_and_gradient` of the view ``(vx, vy, vz)`` given as scalars."""
    num, den = _num_den3(vx, vy, vz, sx, sy, sz)
    if num * num + den * den == 0.0:  # sun on the view axis: unpolarized, no angle
        return np.nan, np.nan, np.nan, np.nan
    g0, g1, g2 = _gradient3(vx, vy, vz, num, den)
    return math.atan2(num, den), g0, g1, g2


@nb.njit(cache=True, error_model="numpy")
def aop_residual_and_gradient3(c_meas, s_meas, vx, vy, vz, sx, sy, sz):
    """Residual ``aop_meas - aop`` folded into [-pi/2, pi/2] and d aop / d s.

    ``c_meas, s_meas`` are the cosine and sine of the measured angle.  The residual is the
    ``atan`` of its tangent, ``(s_m den - c_m num) / (c_m den + s_m num)``: the fold modulo
    pi comes with it, and ``atan`` of a quotient costs about half an ``atan2`` (a fit
    evaluates one per view and iterate).  NaN when the sun is on the view axis.
    """
    num, den = _num_den3(vx, vy, vz, sx, sy, sz)
    if num * num + den * den == 0.0:
        return np.nan, np.nan, np.nan, np.nan
    g0, g1, g2 = _gradient3(vx, vy, vz, num, den)
    r = atan_small((s_meas * den - c_meas * num) / (c_meas * den + s_meas * num))
    return r, g0, g1, g2


@nb.njit(cache=True, error_model="numpy")
def aop_gradient(v, sx, sy, sz):
    """d aop / d s alone (no ``atan2``: callers that only need the slope skip its cost)."""
    num, den = _num_den(v, sx, sy, sz)
    if num * num + den * den == 0.0:
        return np.nan, np.nan, np.nan
    return _gradient(v, num, den)


@nb.njit(cache=True, error_model="numpy")
def aop_and_gradient(v, sx, sy, sz):
    """AoP of view ``v`` for sun ``s`` (body frame) in [-pi/2, pi/2) and d aop / d s."""
    a, g0, g1, g2 = aop_unfolded_and_gradient(v, sx, sy, sz)
    return fold_half_pi(a), g0, g1, g2


@nb.njit(cache=True, error_model="numpy")
def sun_body_partials(sun_n, pitch, roll, heading):
    """Sun in the body frame and its partials on pitch, roll and heading (four 3-tuples).

    ``s_b = R2(roll)^T R1(pitch)^T R3(heading) sun_n``, applied rotation by rotation.
    """
    return sun_body_partials_cs(sun_n, pitch, math.cos(-roll), math.sin(-roll), heading)


@nb.njit(cache=True, error_model="numpy")
def sun_body_partials_cs(sun_n, pitch, c_roll, s_roll, heading):
    """:func:`sun_body_partials` with ``c_roll, s_roll = cos(-roll), sin(-roll)`` given.

    A fit at fixed roll evaluates the sun many times: its roll rotation is computed once.
    """
    tx, ty, tz = rot_z(heading, sun_n[0], sun_n[1], sun_n[2])
    cp, sp = math.cos(-pitch), math.sin(-pitch)
    ux, uy, uz = rot_x_cs(cp, sp, tx, ty, tz)
    s = rot_y_cs(c_roll, s_roll, ux, uy, uz)
    # d/dheading: R3' = [e_z x] R3 ; d/dpitch: R1(-p)' = -[e_x x] R1(-p) ; same for roll
    ds_dh = rot_y_cs(c_roll, s_roll, *rot_x_cs(cp, sp, -ty, tx, 0.0))
    ds_dp = rot_y_cs(c_roll, s_roll, 0.0, uz, -uy)
    ds_dr = (-s[2], 0.0, s[0])
    return s, ds_dp, ds_dr, ds_dh


@nb.njit(cache=True, error_model="numpy")
def dot3(g0, g1, g2, d):
    """``(g0, g1, g2) . d`` for a 3-tuple ``d``."""
    return g0 * d[0] + g1 * d[1] + g2 * d[2]
