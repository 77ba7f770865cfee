"""Membership-function shapes: registry, parameter checks, numpy and numba evaluation.

Shapes and parameters follow MATLAB's Fuzzy Logic Toolbox (same names in ``.fis`` files,
same parameter order, same values at the edges):

============  ==============================  ====================================
name          params                          definition
============  ==============================  ====================================
tri           a <= b <= c                     0 outside (a, c), 1 at b, linear
trap          a <= b <= c <= d                0 outside (a, d), 1 on [b, c], linear
gauss         sigma > 0, c                    exp(-(x-c)^2 / (2 sigma^2))
gauss2        s1 > 0, c1, s2 > 0, c2          left Gaussian for x < c1, right for x > c2
gbell         a > 0, b > 0, c                 1 / (1 + |(x-c)/a|^(2b))
sigmoid       a, c                            1 / (1 + exp(-a (x-c)))
smf           a <= b                          quadratic S-spline from 0 at a to 1 at b
zmf           a <= b                          quadratic Z-spline from 1 at a to 0 at b
pimf          a <= b <= c <= d                smf(a, b) * zmf(c, d)
singleton     x0                              1 at x0, 0 elsewhere
constant      c                               Sugeno output z = c
linear        k_1 .. k_n, c                   Sugeno output z = sum k_i x_i + c
============  ==============================  ====================================

Degenerate triangles and trapezoids (``a == b`` or ``b == c``) are shoulders with a jump,
exactly as MATLAB's ``trimf``/``trapmf`` (the value at the jump is 1).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from fuzzynav.fuzzy._where import fail

__all__ = ["Shape", "SHAPES", "FUZZY_SHAPES", "SUGENO_SHAPES", "check_params", "evaluate_mf",
           "mf_scalar", "knots", "peak_interval"]

# kernel codes (stored in the compiled iparams; never renumber, only append)
TRI, TRAP, GAUSS, GAUSS2, GBELL, SIGMOID, SMF, ZMF, PIMF, SINGLETON = range(1, 11)
CONSTANT, LINEAR = 20, 21


@dataclass(frozen=True)
class Shape:
    """Static description of one membership-function shape.

    Attributes
    ----------
    name : str
        Name in rule files.
    code : int
        Integer code of the compiled form.
    n_params : int or None
        Number of parameters (``None``: one per system input plus one, ``linear``).
    kind : str
        ``"pwl"`` (piecewise linear), ``"curved"``, ``"singleton"`` or ``"sugeno"``.
    matlab : str or None
        MATLAB ``.fis`` name (``None``: no MATLAB equivalent).
    """

    name: str
    code: int
    n_params: int | None
    kind: str
    matlab: str | None


SHAPES: dict[str, Shape] = {
    s.name: s
    for s in (
        Shape("tri", TRI, 3, "pwl", "trimf"),
        Shape("trap", TRAP, 4, "pwl", "trapmf"),
        Shape("gauss", GAUSS, 2, "curved", "gaussmf"),
        Shape("gauss2", GAUSS2, 4, "curved", "gauss2mf"),
        Shape("gbell", GBELL, 3, "curved", "gbellmf"),
        Shape("sigmoid", SIGMOID, 2, "curved", "sigmf"),
        Shape("smf", SMF, 2, "curved", "smf"),
        Shape("zmf", ZMF, 2, "curved", "zmf"),
        Shape("pimf", PIMF, 4, "curved", "pimf"),
        Shape("singleton", SINGLETON, 1, "singleton", None),
        Shape("constant", CONSTANT, 1, "sugeno", "constant"),
        Shape("linear", LINEAR, None, "sugeno", "linear"),
    )
}

#: shapes usable on inputs and on Mamdani outputs
FUZZY_SHAPES = tuple(n for n, s in SHAPES.items() if s.kind != "sugeno")
#: shapes of Sugeno outputs
SUGENO_SHAPES = ("constant", "linear")


def _ordered(params, names: str, where: str):
    for i in range(len(params) - 1):
        if params[i] > params[i + 1]:
            fail(where, f"parameters must satisfy {names}, got {list(params)}")


def check_params(mf: str, params, n_inputs: int | None = None, where: str = "params"):
    """Validate the parameters of one term; raise :class:`FisError` naming ``where``.

    Parameters
    ----------
    mf : str
        Shape name (must be a key of :data:`SHAPES`).
    params : sequence of float
        Parameters in MATLAB order.
    n_inputs : int, optional
        Number of system inputs (needed for ``linear``).
    where : str
        JSON path of the parameter list, used in the error message.
    """
    shape = SHAPES[mf]
    n = shape.n_params if shape.n_params is not None else (n_inputs or 0) + 1
    if shape.n_params is None and n_inputs is None:
        return
    if len(params) != n:
        extra = " (one coefficient per input, then the offset)" if mf == "linear" else ""
        fail(where, f"'{mf}' takes {n} parameters{extra}, got {len(params)}")
    for i, p in enumerate(params):
        if not math.isfinite(p):
            fail(f"{where}[{i}]", f"parameter must be finite, got {p!r}")
    if mf == "tri":
        _ordered(params, "a <= b <= c", where)
    elif mf in ("trap", "pimf"):
        _ordered(params, "a <= b <= c <= d", where)
    elif mf in ("smf", "zmf"):
        _ordered(params, "a <= b", where)
    elif mf == "gauss" and params[0] <= 0:
        fail(f"{where}[0]", f"gauss sigma must be > 0, got {params[0]!r}")
    elif mf == "gauss2":
        for i in (0, 2):
            if params[i] <= 0:
                fail(f"{where}[{i}]", f"gauss2 sigma must be > 0, got {params[i]!r}")
    elif mf == "gbell":
        for i, nm in ((0, "a"), (1, "b")):
            if params[i] <= 0:
                fail(f"{where}[{i}]", f"gbell {nm} must be > 0, got {params[i]!r}")


# ----------------------------------------------------------------------------- numpy
def _sig(z):
    # split by sign so that exp never overflows
    out = np.empty_like(z)
    pos = z >= 0
    out[pos] = 1.0 / (1.0 + np.exp(-z[pos]))
    ez = np.exp(z[~pos])
    out[~pos] = ez / (1.0 + ez)
    return out


def _smf(x, a, b):
    if a >= b:
        return (x >= a).astype(float)
    m = 0.5 * (a + b)
    y = np.where(x <= a, 0.0, 1.0)
    lo = (x > a) & (x <= m)
    hi = (x > m) & (x < b)
    y[lo] = 2.0 * ((x[lo] - a) / (b - a)) ** 2
    y[hi] = 1.0 - 2.0 * ((x[hi] - b) / (b - a)) ** 2
    return y


def _zmf(x, a, b):
    if a >= b:
        return (x <= a).astype(float)
    m = 0.5 * (a + b)
    y = np.where(x <= a, 1.0, 0.0)
    lo = (x > a) & (x <= m)
    hi = (x > m) & (x < b)
    y[lo] = 1.0 - 2.0 * ((x[lo] - a) / (b - a)) ** 2
    y[hi] = 2.0 * ((x[hi] - b) / (b - a)) ** 2
    return y


def _ramp_up(x, a, b):
    # 0 for x < a, 1 for x >= b, linear between (a == b: step at a, value 1 at a)
    if a == b:
        return (x >= a).astype(float)
    return np.clip((x - a) / (b - a), 0.0, 1.0)


def _ramp_down(x, c, d):
    if c == d:
        return (x <= d).astype(float)
    return np.clip((d - x) / (d - c), 0.0, 1.0)


def evaluate_mf(mf: str, params, x) -> np.ndarray:
    """Membership degrees of ``x`` (array) in a fuzzy term, vectorised.

    Parameters
    ----------
    mf : str
        Shape name (not a Sugeno shape).
    params : sequence of float
        Parameters in MATLAB order.
    x : array_like
        Points, in the variable's unit.

    Returns
    -------
    numpy.ndarray
        Degrees in [0, 1], same shape as ``x``.
    """
    x = np.asarray(x, dtype=float)
    p = [float(v) for v in params]
    if mf == "tri":
        a, b, c = p
        y = np.minimum(_ramp_up(x, a, b), _ramp_down(x, b, c))
        y = np.where((x < a) | (x > c), 0.0, y)
        return np.where(x == b, 1.0, y)
    if mf == "trap":
        a, b, c, d = p
        y = np.minimum(_ramp_up(x, a, b), _ramp_down(x, c, d))
        return np.where((x < a) | (x > d), 0.0, y)
    if mf == "gauss":
        s, c = p
        return np.exp(-((x - c) ** 2) / (2.0 * s * s))
    if mf == "gauss2":
        s1, c1, s2, c2 = p
        left = np.where(x < c1, np.exp(-((x - c1) ** 2) / (2.0 * s1 * s1)), 1.0)
        right = np.where(x > c2, np.exp(-((x - c2) ** 2) / (2.0 * s2 * s2)), 1.0)
        return left * right
    if mf == "gbell":
        a, b, c = p
        return 1.0 / (1.0 + np.abs((x - c) / a) ** (2.0 * b))
    if mf == "sigmoid":
        a, c = p
        return _sig(np.atleast_1d(a * (x - c))).reshape(x.shape)
    if mf == "smf":
        return _smf(np.atleast_1d(x), *p).reshape(x.shape)
    if mf == "zmf":
        return _zmf(np.atleast_1d(x), *p).reshape(x.shape)
    if mf == "pimf":
        a, b, c, d = p
        xs = np.atleast_1d(x)
        return (_smf(xs, a, b) * _zmf(xs, c, d)).reshape(x.shape)
    if mf == "singleton":
        return np.where(x == p[0], 1.0, 0.0)
    raise ValueError(f"not a fuzzy membership shape: {mf!r}")


# ----------------------------------------------------------------------------- numba
@numba.njit(cache=True, error_model="numpy")
def _sig_scalar(z):
    if z >= 0.0:
        return 1.0 / (1.0 + math.exp(-z))
    ez = math.exp(z)
    return ez / (1.0 + ez)


@numba.njit(cache=True, error_model="numpy")
def _smf_scalar(x, a, b):
    if a >= b:
        return 1.0 if x >= a else 0.0
    if x <= a:
        return 0.0
    if x >= b:
        return 1.0
    t = (x - a) / (b - a)
    if x <= 0.5 * (a + b):
        return 2.0 * t * t
    u = (x - b) / (b - a)
    return 1.0 - 2.0 * u * u


@numba.njit(cache=True, error_model="numpy")
def _zmf_scalar(x, a, b):
    return 1.0 - _smf_scalar(x, a, b) if a < b else (1.0 if x <= a else 0.0)


@numba.njit(cache=True, error_model="numpy")
def mf_scalar(code, fp, off, x):
    """Membership degree of scalar ``x`` for the term of ``code`` with params ``fp[off:]``.

    Same values as :func:`evaluate_mf`; used inside the compiled kernels.
    """
    if code == TRI:
        a, b, c = fp[off], fp[off + 1], fp[off + 2]
        if x == b:
            return 1.0
        if x <= a or x >= c:
            return 0.0
        if x < b:
            return (x - a) / (b - a)
        return (c - x) / (c - b)
    if code == TRAP:
        a, b, c, d = fp[off], fp[off + 1], fp[off + 2], fp[off + 3]
        if x < a or x > d:
            return 0.0
        if x < b:
            return (x - a) / (b - a)
        if x > c:
            return (d - x) / (d - c)
        return 1.0
    if code == GAUSS:
        s, c = fp[off], fp[off + 1]
        return math.exp(-((x - c) ** 2) / (2.0 * s * s))
    if code == GAUSS2:
        s1, c1, s2, c2 = fp[off], fp[off + 1], fp[off + 2], fp[off + 3]
        y = 1.0
        if x < c1:
            y *= math.exp(-((x - c1) ** 2) / (2.0 * s1 * s1))
        if x > c2:
            y *= math.exp(-((x - c2) ** 2) / (2.0 * s2 * s2))
        return y
    if code == GBELL:
        a, b, c = fp[off], fp[off + 1], fp[off + 2]
        return 1.0 / (1.0 + abs((x - c) / a) ** (2.0 * b))
    if code == SIGMOID:
        return _sig_scalar(fp[off] * (x - fp[off + 1]))
    if code == SMF:
        return _smf_scalar(x, fp[off], fp[off + 1])
    if code == ZMF:
        return _zmf_scalar(x, fp[off], fp[off + 1])
    if code == PIMF:
        return _smf_scalar(x, fp[off], fp[off + 1]) * _zmf_scalar(x, fp[off + 2], fp[off + 3])
    if code == SINGLETON:
        return 1.0 if x == fp[off] else 0.0
    return math.nan


# ------------------------------------------------------------------ shape geometry
def knots(mf: str, params) -> list[float]:
    """Points where the shape may be non-smooth or peaks (quadrature split points)."""
    p = [float(v) for v in params]
    if mf in ("tri", "trap", "smf", "zmf", "pimf", "singleton"):
        extra = []
        if mf in ("smf", "zmf"):
            extra = [0.5 * (p[0] + p[1])]
        elif mf == "pimf":
            extra = [0.5 * (p[0] + p[1]), 0.5 * (p[2] + p[3])]
        return sorted(p + extra)
    if mf == "gauss":
        return [p[1]]
    if mf == "gauss2":
        return sorted([p[1], p[3]])
    if mf == "gbell":
        return [p[2]]
    if mf == "sigmoid":
        return [p[1]]
    return []


def peak_interval(mf: str, params) -> tuple[float, float]:
    """Interval where the (quasi-concave) shape attains its supremum over the real line.

    Monotone shapes return an infinite end (sigmoid with ``a > 0`` -> ``(inf, inf)``).
    """
    p = [float(v) for v in params]
    inf = math.inf
    if mf == "tri":
        return p[1], p[1]
    if mf == "trap":
        return p[1], p[2]
    if mf == "pimf":
        return p[1], p[2]
    if mf in ("gauss", "gbell"):
        c = p[1] if mf == "gauss" else p[2]
        return c, c
    if mf == "gauss2":
        s1, c1, s2, c2 = p
        if c1 <= c2:
            return c1, c2
        m = (c1 * s2 * s2 + c2 * s1 * s1) / (s1 * s1 + s2 * s2)
        return m, m
    if mf == "sigmoid":
        if p[0] > 0:
            return inf, inf
        if p[0] < 0:
            return -inf, -inf
        return -inf, inf
    if mf == "smf":
        return p[1], inf
    if mf == "zmf":
        return -inf, p[0]
    if mf == "singleton":
        return p[0], p[0]
    raise ValueError(f"not a fuzzy membership shape: {mf!r}")
