"""Numba kernels for probor aggregation of piecewise-linear implied sets.

Between consecutive breakpoints of all pieces each piece is linear, so the aggregate
``1 - prod(1 - l_p(x))`` is a polynomial of degree <= (number of active pieces).  Areas
and moments are integrated with a Gauss-Legendre rule of ``ceil((k + 2) / 2)`` nodes,
exact for that degree; the bisector solves the cumulative polynomial with safeguarded
Newton steps; maxima lie on breakpoints (a product of non-negative linear factors is
log-concave, so its minimum on an interval is at an end).
"""
from __future__ import annotations

import math

import numba

from fuzzynav.fuzzy.compiled_layout import DEF_CENTROID, DEF_LOM, DEF_MOM, DEF_SOM
from fuzzynav.fuzzy.pwl_kernels import maximum_threshold, point_maxima, vertex_limits

__all__ = ["probor_defuzz"]


@numba.njit(cache=True, error_model="numpy")
def _probor_prepare(work, pieces, npieces, stride, x0, x1, ab):
    """Store each piece's linear restriction on (x0, x1) at ``ab``; return #active."""
    act = 0
    for p in range(npieces):
        base = pieces + p * stride
        nv = int(work[base])
        a = vertex_limits(work, base + 1, nv, x0)[1]
        b = vertex_limits(work, base + 1, nv, x1)[0]
        work[ab + 2 * p] = a
        work[ab + 2 * p + 1] = b
        if a > 0.0 or b > 0.0:
            act += 1
    return act


@numba.njit(cache=True, error_model="numpy")
def _probor_value(work, npieces, ab, t):
    q = 1.0
    for p in range(npieces):
        a = work[ab + 2 * p]
        b = work[ab + 2 * p + 1]
        if a > 0.0 or b > 0.0:
            q *= 1.0 - (a + (b - a) * t)
    return 1.0 - q


@numba.njit(cache=True, error_model="numpy")
def _gl_integral(fp, fgl, ngl, work, npieces, ab, t_end, weight_x, x0, d, c):
    """Integral over t in [0, t_end] of f(t) (weight_x: times x - c) with d dx = dt."""
    tab = fgl + ngl * (ngl - 1)
    s = 0.0
    for j in range(ngl):
        t = t_end * fp[tab + 2 * j]
        f = _probor_value(work, npieces, ab, t)
        if weight_x:
            f *= x0 + d * t - c
        s += fp[tab + 2 * j + 1] * f
    return s * t_end * d


@numba.njit(cache=True, error_model="numpy")
def _probor_vertex_values(work, e, n, pieces, npieces, stride):
    # merging interpolated the running aggregate linearly, which is wrong between its
    # breakpoints for probor: recompute both limits at every point from the pieces
    for k in range(n):
        x = work[e + 3 * k]
        ql = 1.0
        qr = 1.0
        for p in range(npieces):
            base = pieces + p * stride
            left, right = vertex_limits(work, base + 1, int(work[base]), x)
            ql *= 1.0 - left
            qr *= 1.0 - right
        work[e + 3 * k + 1] = 1.0 - ql
        work[e + 3 * k + 2] = 1.0 - qr


@numba.njit(cache=True, error_model="numpy")
def probor_defuzz(fp, fgl, work, e, n, pieces, npieces, stride, ab, method, c):
    """Defuzzify the probor aggregate of the pieces (breakpoint union in the envelope at e)."""
    _probor_vertex_values(work, e, n, pieces, npieces, stride)
    if method == DEF_SOM or method == DEF_LOM:
        return point_maxima(work, e, n, method)
    if method == DEF_MOM:
        return _probor_mom(work, e, n, pieces, npieces, stride, ab)
    total = 0.0
    mom = 0.0
    for k in range(n - 1):
        x0 = work[e + 3 * k]
        d = work[e + 3 * (k + 1)] - x0
        act = _probor_prepare(work, pieces, npieces, stride, x0, x0 + d, ab)
        if act == 0 or d <= 0.0:
            continue
        ngl = (act + 3) // 2
        total += _gl_integral(fp, fgl, ngl, work, npieces, ab, 1.0, False, x0, d, c)
        if method == DEF_CENTROID:
            mom += _gl_integral(fp, fgl, ngl, work, npieces, ab, 1.0, True, x0, d, c)
    if not total > 0.0:
        return math.nan
    if method == DEF_CENTROID:
        return c + mom / total
    return _probor_bisector(fp, fgl, work, e, n, pieces, npieces, stride, ab, total)


@numba.njit(cache=True, error_model="numpy")
def _probor_bisector(fp, fgl, work, e, n, pieces, npieces, stride, ab, total):
    half = 0.5 * total
    cum = 0.0
    for k in range(n - 1):
        x0 = work[e + 3 * k]
        d = work[e + 3 * (k + 1)] - x0
        act = _probor_prepare(work, pieces, npieces, stride, x0, x0 + d, ab)
        if act == 0 or d <= 0.0:
            continue
        ngl = (act + 3) // 2
        a = _gl_integral(fp, fgl, ngl, work, npieces, ab, 1.0, False, x0, d, 0.0)
        if cum + a >= half:
            return x0 + d * _newton_fraction(fp, fgl, ngl, work, npieces, ab, d, half - cum, a)
        cum += a
    return work[e + 3 * (n - 1)]


@numba.njit(cache=True, error_model="numpy")
def _newton_fraction(fp, fgl, ngl, work, npieces, ab, d, r, a):
    """t in [0, 1] with integral_0^t f = r (f >= 0 polynomial): safeguarded Newton."""
    lo = 0.0
    hi = 1.0
    t = r / a
    for _ in range(100):
        g = _gl_integral(fp, fgl, ngl, work, npieces, ab, t, False, 0.0, d, 0.0) - r
        if g > 0.0:
            hi = t
        else:
            lo = t
        slope = d * _probor_value(work, npieces, ab, t)
        tn = t - g / slope if slope > 0.0 else 0.5 * (lo + hi)
        if not lo < tn < hi:
            tn = 0.5 * (lo + hi)
        if abs(tn - t) <= 1e-16 or hi - lo <= 1e-16:
            return tn
        t = tn
    return t


@numba.njit(cache=True, error_model="numpy")
def _probor_mom(work, e, n, pieces, npieces, stride, ab):
    res = point_maxima(work, e, n, DEF_MOM)
    if math.isnan(res):
        return res
    thr = maximum_threshold(work, e, n)
    meas = 0.0
    mom = 0.0
    for k in range(n - 1):
        x0 = work[e + 3 * k]
        x1 = work[e + 3 * (k + 1)]
        if work[e + 3 * k + 2] >= thr and work[e + 3 * (k + 1) + 1] >= thr:
            # the product of linear factors is log-concave: equal ends and an equal
            # middle mean it is constant on the interval
            _probor_prepare(work, pieces, npieces, stride, x0, x1, ab)
            if _probor_value(work, npieces, ab, 0.5) >= thr:
                meas += x1 - x0
                mom += (x1 - x0) * 0.5 * (x0 + x1)
    if meas > 0.0:
        return mom / meas
    return res
