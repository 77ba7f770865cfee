"""Defuzzification of output sets with curved terms (gauss, gbell, sigmoid...).

These aggregates have no closed-form integral, so they are integrated with adaptive
Gauss-Kronrod quadrature (``scipy.integrate.quad``) split at every knot of every term
(peaks, centres, breakpoints) and every clip point, each piece to a requested relative
error of 1e-12.  The reported error estimates are summed and checked: the centroid is
then within ``QUAD_RTOL`` x (range width) of the exact value, and the bisector splits
the area to ``QUAD_RTOL`` relative.  Maxima methods use the shapes' unimodality: the
maximising set of a clipped or scaled term is an interval found by bracketed root
finding to machine precision.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq

from fuzzynav.fuzzy.defuzz import aggregate
from fuzzynav.fuzzy.compiled_layout import MAX_RTOL
from fuzzynav.fuzzy.membership import evaluate_mf, knots, peak_interval

__all__ = ["QUAD_RTOL", "curved_maxima", "curved_defuzz"]

#: documented bound: centroid error / range width, bisector area split (relative)
QUAD_RTOL = 1e-9
_PIECE_RTOL = 1e-12


def _mu(s, x: float) -> float:
    return float(evaluate_mf(s.mf, s.params, np.array([x]))[0])


def _argmax_mu(s, lo: float, hi: float):
    """(max of mu on [lo, hi], interval where it is attained)."""
    p1, p2 = peak_interval(s.mf, s.params)
    a, b = max(p1, lo), min(p2, hi)
    if a <= b:
        return _mu(s, a), (a, b)
    x = lo if p2 < lo else hi
    return _mu(s, x), (x, x)


def _level_interval(s, t: float, lo: float, hi: float, inside):
    """Interval of [lo, hi] where mu >= t, around the point ``inside`` (mu(inside) >= t)."""
    tol = 1e-15 * (hi - lo)

    def g(x):
        return _mu(s, x) - t

    left = lo if g(lo) >= 0 else brentq(g, lo, inside[0], xtol=tol, rtol=1e-15)
    right = hi if g(hi) >= 0 else brentq(g, inside[1], hi, xtol=tol, rtol=1e-15)
    return left, right


def _height_and_argmax(s, lo, hi):
    top, where = _argmax_mu(s, lo, hi)
    if s.implication == "min" and s.level < top:
        return s.level, _level_interval(s, s.level, lo, hi, where)
    scale = s.level if s.implication == "prod" else 1.0
    return top * scale, where


def curved_maxima(sets, lo: float, hi: float, method: str) -> float:
    """mom / som / lom of the max-aggregate of unimodal implied sets."""
    info = [_height_and_argmax(s, lo, hi) for s in sets]
    h = max((v for v, _ in info), default=0.0)
    if not h > 0.0:
        return math.nan
    thr = h - MAX_RTOL * h
    spans = sorted(iv for v, iv in info if v >= thr)
    if method == "som":
        return spans[0][0]
    if method == "lom":
        return max(b for _, b in spans)
    merged = []
    for a, b in spans:
        if merged and a <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    meas = sum(b - a for a, b in merged)
    if meas > 0.0:
        return sum((b - a) * 0.5 * (a + b) for a, b in merged) / meas
    return float(np.mean([a for a, _ in merged]))


def _split_points(sets, lo, hi) -> list[float]:
    pts = {lo, hi}
    for s in sets:
        pts.update(k for k in knots(s.mf, s.params) if lo < k < hi)
        if s.implication == "min":
            top, where = _argmax_mu(s, lo, hi)
            if s.level < top:
                pts.update(x for x in _level_interval(s, s.level, lo, hi, where)
                           if lo < x < hi)
    return sorted(pts)


def _integrate(f, pts):
    total, err = 0.0, 0.0
    for a, b in zip(pts[:-1], pts[1:]):
        if b > a:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                v, e = quad(f, a, b, epsabs=0.0, epsrel=_PIECE_RTOL, limit=400)
            total += v
            err += e
    return total, err


def curved_defuzz(sets, lo: float, hi: float, agg: str, method: str) -> float:
    """Defuzzified value of an aggregate with curved terms (nan when it is empty)."""
    sets = [s for s in sets if s.level > 0.0]
    if not sets:
        return math.nan
    if method in ("mom", "som", "lom"):
        return curved_maxima(sets, lo, hi, method)

    def f(x):
        return float(aggregate(np.array([s(np.array([x]))[0] for s in sets]), agg))

    pts = _split_points(sets, lo, hi)
    area, err_a = _integrate(f, pts)
    if not area > 0.0:
        return math.nan
    c = 0.5 * (lo + hi)
    if method == "centroid":
        mom, err_m = _integrate(lambda x: (x - c) * f(x), pts)
        _check(err_a / area + err_m / (area * (hi - lo)), method)
        return c + mom / area
    _check(err_a / area, method)
    return _bisect_area(f, pts, area, lo, hi)


def _bisect_area(f, pts, area, lo, hi):
    half = 0.5 * area
    cum = 0.0
    for a, b in zip(pts[:-1], pts[1:]):
        part = _integrate(f, [a, b])[0]
        if cum + part >= half:
            def g(x, a=a, cum=cum):
                return cum + _integrate(f, [a, x])[0] - half

            if g(b) <= 0.0:
                return b
            return brentq(g, a, b, xtol=1e-14 * (hi - lo), rtol=1e-15)
        cum += part
    return hi


def _check(rel_err: float, method: str):
    if rel_err > QUAD_RTOL:
        warnings.warn(f"{method}: quadrature error estimate {rel_err:.1e} exceeds the "
                      f"documented bound {QUAD_RTOL:.0e}", RuntimeWarning, stacklevel=3)
