"""Brute-force reference defuzzification, independent of the engine's algorithms.

The aggregated output set is evaluated on a dense grid; the cell edges are refined by
every kink located numerically (sign changes of set differences and of each set minus
its clip level, then root finding), so that the aggregate is smooth on each cell, and
each cell is integrated with 10-point Gauss-Legendre.  Firing strengths are computed
with plain loops from the document.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from fuzzynav.fuzzy.membership import evaluate_mf

GRID = 4001
GL_X, GL_W = np.polynomial.legendre.leggauss(10)
RTOL = 1e-12  # "equal to the maximum", as documented by the engine


def firing(doc, x: dict) -> list[float]:
    """Firing strength of each rule at the (clamped) input values ``x``."""
    ins = {v["name"]: v for v in doc["inputs"]}
    ops = doc["operators"]
    out = []
    for rule in doc["rules"]:
        vals = []
        for var, cond in rule["if"].items():
            neg = isinstance(cond, dict)
            name = cond["not"] if neg else cond
            term = next(t for t in ins[var]["terms"] if t["name"] == name)
            lo, hi = ins[var]["range"]
            xi = np.array([min(max(x[var], lo), hi)])
            mu = float(evaluate_mf(term["mf"], term["params"], xi)[0])
            vals.append(1.0 - mu if neg else mu)
        acc = vals[0]
        for v in vals[1:]:
            if rule.get("connective", "and") == "and":
                acc = min(acc, v) if ops["and"] == "min" else acc * v
            else:
                acc = max(acc, v) if ops["or"] == "max" else acc + v - acc * v
        out.append(acc * rule.get("weight", 1.0))
    return out


def _roots(g, grid):
    vals = g(grid)
    idx = np.flatnonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0)
    def scalar(t):
        return float(g(np.array([t]))[0])

    return [brentq(scalar, grid[i], grid[i + 1], xtol=1e-16, rtol=1e-15) for i in idx]


def reference_value(doc, x: dict, o: int = 0) -> float:
    """Defuzzified value of output ``o`` at inputs ``x`` (the default when empty)."""
    out = doc["outputs"][o]
    ops = doc["operators"]
    lo, hi = out["range"]
    default = out.get("default", 0.5 * (lo + hi))
    sets = []
    for w, rule in zip(firing(doc, x), doc["rules"]):
        if out["name"] in rule["then"] and w > 0:
            term = next(t for t in out["terms"] if t["name"] == rule["then"][out["name"]])
            sets.append((term, w))
    if not sets:
        return default

    def one(term, w):
        def f(t):
            mu = evaluate_mf(term["mf"], term["params"], np.atleast_1d(t))
            return np.minimum(mu, w) if ops["implication"] == "min" else w * mu
        return f

    fs = [one(t, w) for t, w in sets]

    def agg(t):
        v = np.array([f(t) for f in fs])
        if ops["aggregation"] == "max":
            return v.max(axis=0)
        if ops["aggregation"] == "sum":
            return v.sum(axis=0)
        return 1.0 - np.prod(1.0 - v, axis=0)

    grid = np.linspace(lo, hi, GRID)
    knots = set(grid.tolist())
    for (term, w), f in zip(sets, fs):
        knots.update(p for p in term["params"] if lo < p < hi)
        mu = lambda t, term=term: evaluate_mf(term["mf"], term["params"], np.atleast_1d(t)) - w
        knots.update(_roots(mu, grid))
    for i in range(len(fs)):
        for j in range(i + 1, len(fs)):
            knots.update(_roots(lambda t: fs[i](t) - fs[j](t), grid))
    xs = np.array(sorted(knots))
    return _defuzz(agg, xs, ops["defuzzifier"], default)


def _cell_integrals(agg, xs):
    a, b = xs[:-1], xs[1:]
    t = 0.5 * (a + b)[:, None] + 0.5 * (b - a)[:, None] * GL_X[None, :]
    f = agg(t.ravel()).reshape(t.shape)
    area = 0.5 * (b - a) * (f @ GL_W)
    mom = 0.5 * (b - a) * ((t * f) @ GL_W)
    return area, mom


def _defuzz(agg, xs, method, default):
    if method in ("mom", "som", "lom"):
        v = agg(xs)
        h = v.max()
        if not h > 0:
            return default
        thr = h - RTOL * h
        at = xs[v >= thr]
        if method == "som":
            return float(at[0])
        if method == "lom":
            return float(at[-1])
        mid = agg(0.5 * (xs[:-1] + xs[1:]))
        flat = (v[:-1] >= thr) & (v[1:] >= thr) & (mid >= thr)
        d = np.diff(xs)
        if d[flat].sum() > 0:
            return float(np.sum(d[flat] * 0.5 * (xs[:-1] + xs[1:])[flat]) / d[flat].sum())
        return float(at.mean())
    area, mom = _cell_integrals(agg, xs)
    total = area.sum()
    if not total > 0:
        return default
    if method == "centroid":
        return float(mom.sum() / total)
    cum = np.concatenate([[0.0], np.cumsum(area)])
    k = int(np.flatnonzero(cum[1:] >= 0.5 * total)[0])

    def partial(t):
        return cum[k] + _cell_integrals(agg, np.array([xs[k], t]))[0][0] - 0.5 * total

    if partial(xs[k + 1]) <= 0:
        return float(xs[k + 1])
    return float(brentq(lambda t: float(partial(t)), xs[k], xs[k + 1], xtol=1e-16, rtol=1e-15))

