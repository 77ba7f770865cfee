"""Exact defuzzification in Python (the reference path beside the numba kernels).

An output set is given as a list of :class:`Implied` sets (term, level, implication).
For piecewise-linear terms the aggregate is evaluated on *knots*: every breakpoint of
every implied set (term parameters, clip points), refined -- for max aggregation -- by
the pairwise crossings of the sets' linear restrictions inside each interval.  Between
knots the aggregate is then linear (max, sum) or a polynomial (probor), so the integrals
below are closed form or an exact Gauss-Legendre rule.  This is a different algorithm
from the kernel's envelope folding, which makes the two a real cross-check.

Maxima (mom, som, lom): a point belongs to the maximum when its value is within
``MAX_RTOL`` (relative) of it; mom is the mean over the plateaus of the maximum weighted
by length when they have a length, else the mean of the maximising points.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from fuzzynav.fuzzy.compiled_layout import GAP_RTOL, MAX_RTOL
from fuzzynav.fuzzy.membership import evaluate_mf

__all__ = ["Implied", "aggregate", "pwl_knots", "pwl_defuzz", "singleton_defuzz"]


@dataclass(frozen=True)
class Implied:
    """One rule's (or one term's) implied output set: ``imp(level, mf(x))``."""

    mf: str
    params: tuple[float, ...]
    level: float
    implication: str

    def __call__(self, x):
        mu = evaluate_mf(self.mf, self.params, x)
        if self.implication == "min":
            return np.minimum(mu, self.level)
        return mu * self.level

    def breakpoints(self) -> list[float]:
        """Where a tri/trap implied set changes slope (clip points included)."""
        p = list(self.params)
        h = self.level
        if self.implication == "min" and h < 1.0:
            if self.mf == "tri":
                p += [p[0] + h * (p[1] - p[0]), p[2] - h * (p[2] - p[1])]
            elif self.mf == "trap":
                p += [p[0] + h * (p[1] - p[0]), p[3] - h * (p[3] - p[2])]
        return p


def aggregate(values: np.ndarray, agg: str) -> np.ndarray:
    """Aggregate implied-set values stacked on axis 0 (max, sum or probor)."""
    if agg == "max":
        return values.max(axis=0)
    if agg == "sum":
        return values.sum(axis=0)
    return 1.0 - np.prod(1.0 - values, axis=0)


def _crossings(sets, u: float, v: float) -> list[float]:
    # every set is linear on (u, v): intersect the lines pairwise
    t = np.array([u + (v - u) / 3.0, u + 2.0 * (v - u) / 3.0])
    if not t[1] > t[0]:
        return []
    vals = np.array([s(t) for s in sets])
    slope = (vals[:, 1] - vals[:, 0]) / (t[1] - t[0])
    icpt = vals[:, 0] - slope * t[0]
    ds = slope[:, None] - slope[None, :]
    di = icpt[None, :] - icpt[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        x = di / ds
    iu = np.triu_indices(len(sets), 1)
    x = x[iu]
    return sorted(set(x[np.isfinite(x) & (x > u) & (x < v)].tolist()))


def pwl_knots(sets, lo: float, hi: float, agg: str) -> np.ndarray:
    """Sorted knots of the aggregate on [lo, hi] (crossings included for max)."""
    base = {lo, hi}
    for s in sets:
        base.update(x for x in s.breakpoints() if lo < x < hi)
    base = sorted(base)
    if agg != "max" or len(sets) < 2:
        return np.array(base)
    knots = []
    for u, v in zip(base[:-1], base[1:]):
        knots.append(u)
        knots.extend(_crossings(sets, u, v))
    knots.append(base[-1])
    return np.array(knots)


def _limits(sets, x: np.ndarray, agg: str):
    """Right limit at x[k] and left limit at x[k+1] of the aggregate, for every gap.

    Each set is linear on a gap, so its limits follow exactly from two inner samples.
    """
    d = np.diff(x)
    y1 = np.array([s(x[:-1] + d / 3.0) for s in sets])
    y2 = np.array([s(x[:-1] + 2.0 * d / 3.0) for s in sets])
    return aggregate(2.0 * y1 - y2, agg), aggregate(2.0 * y2 - y1, agg)


def _maxima(x, point, y0, y1, method):
    h = max(point.max(), y0.max(initial=0.0), y1.max(initial=0.0))
    if not h > 0.0:
        return math.nan
    thr = h - MAX_RTOL * h
    at = np.flatnonzero(point >= thr)
    if method == "som":
        return float(x[at[0]])
    if method == "lom":
        return float(x[at[-1]])
    flat = (y0 >= thr) & (y1 >= thr)
    d = np.diff(x)
    meas = d[flat].sum()
    if meas > 0.0:
        return float(np.sum(d[flat] * 0.5 * (x[:-1] + x[1:])[flat]) / meas)
    return float(x[at].mean())


def _linear_bisector(x, y0, y1, area):
    total = area.sum()
    half = 0.5 * total
    cum = np.concatenate([[0.0], np.cumsum(area)])
    k = int(np.flatnonzero((cum[1:] >= half) & (area > 0.0))[0])
    r = half - cum[k]
    d = x[k + 1] - x[k]
    s = (y1[k] - y0[k]) / d
    den = y0[k] + math.sqrt(max(y0[k] ** 2 + 2.0 * s * r, 0.0))
    xb = x[k] + (min(max(2.0 * r / den, 0.0), d) if den > 0 else 0.0)
    if cum[k + 1] - half <= GAP_RTOL * total:
        nxt = np.flatnonzero(area[k + 1:] > 0.0)
        if len(nxt) and nxt[0] > 0:
            return 0.5 * (x[k + 1] + x[k + 1 + nxt[0]])
    return float(xb)


def pwl_defuzz(sets, lo: float, hi: float, agg: str, method: str) -> float:
    """Exact defuzzified value of the aggregate of tri/trap implied sets (nan if empty)."""
    sets = [s for s in sets if s.level > 0.0]
    if not sets:
        return math.nan
    x = pwl_knots(sets, lo, hi, agg)

    def f(t):
        return aggregate(np.array([s(t) for s in sets]), agg)

    y0, y1 = _limits(sets, x, agg)
    if agg == "probor":
        return _probor_defuzz(sets, f, x, y0, y1, method, lo, hi)
    d = np.diff(x)
    area = 0.5 * d * (y0 + y1)
    if method in ("mom", "som", "lom"):
        return _maxima(x, f(x), y0, y1, method)
    if not area.sum() > 0.0:
        return math.nan
    if method == "centroid":
        c = 0.5 * (lo + hi)
        u, v = x[:-1] - c, x[1:] - c
        mom = d * (u * (2.0 * y0 + y1) + v * (y0 + 2.0 * y1)) / 6.0
        return float(c + mom.sum() / area.sum())
    return _linear_bisector(x, y0, y1, area)


def _probor_defuzz(sets, f, x, y0, y1, method, lo, hi):
    # between knots the aggregate is a polynomial of degree <= len(sets)
    nodes, weights = np.polynomial.legendre.leggauss(len(sets) // 2 + 2)
    d = np.diff(x)
    c = 0.5 * (lo + hi)
    tx = x[:-1, None] + d[:, None] * 0.5 * (nodes[None, :] + 1.0)
    fx = f(tx.ravel()).reshape(tx.shape)
    area = 0.5 * d * (fx @ weights)
    if method in ("mom", "som", "lom"):
        # a product of linear factors is log-concave: equal ends and middle => constant
        mid = f(x[:-1] + 0.5 * d)
        return _maxima(x, f(x), np.minimum(y0, mid), np.minimum(y1, mid), method)
    total = area.sum()
    if not total > 0.0:
        return math.nan
    if method == "centroid":
        mom = 0.5 * d * (((tx - c) * fx) @ weights)
        return float(c + mom.sum() / total)
    cum = np.concatenate([[0.0], np.cumsum(area)])
    k = int(np.flatnonzero((cum[1:] >= 0.5 * total) & (area > 0.0))[0])

    def partial(t):
        s = x[k] + (t - x[k]) * 0.5 * (nodes + 1.0)
        return cum[k] + 0.5 * (t - x[k]) * (f(s) @ weights) - 0.5 * total

    if partial(x[k + 1]) <= 0.0:
        return float(x[k + 1])
    return float(brentq(partial, x[k], x[k + 1], xtol=1e-15 * (hi - lo), rtol=1e-15))


def singleton_defuzz(positions, levels, method: str) -> float:
    """Defuzzify a discrete set of singletons (positions, aggregated levels)."""
    positions = np.asarray(positions, dtype=float)
    levels = np.asarray(levels, dtype=float)
    h = levels.max(initial=0.0)
    if not h > 0.0:
        return math.nan
    if method == "centroid":
        return float(levels @ positions / levels.sum())
    at = positions[levels >= h - MAX_RTOL * h]
    if method == "som":
        return float(at.min())
    if method == "lom":
        return float(at.max())
    return float(at.mean())
