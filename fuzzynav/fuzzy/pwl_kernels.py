"""Numba kernels for exact Mamdani defuzzification of piecewise-linear output sets.

A *piece* is one implied set (a tri/trap output term clipped at, or scaled by, its
level), restricted to the output range [lo, hi]; it is stored in the work buffer as a
vertex count followed by triples ``(x, left value, right value)`` (left and right differ
only at the jumps of degenerate shoulders).  Pieces are folded into an *envelope* over
[lo, hi] with the same triple layout:

* max aggregation inserts the crossing of the two linear pieces wherever they swap
  inside an interval, so the envelope is exactly linear between its points;
* sum aggregation adds (a sum of linear functions is linear);
* probor keeps the union of breakpoints; between them the aggregate is the polynomial
  ``1 - prod(1 - l_p(x))`` of the pieces' linear restrictions, handled in
  :mod:`fuzzynav.fuzzy.probor_kernels`.

Every integral is then closed form.  Nothing here allocates: all storage is ``work``.
The small per-vertex helpers are ``inline="always"`` (same bits, ~15 % off a call of a
small system).
"""
from __future__ import annotations

import math

import numba

from fuzzynav.fuzzy.compiled_layout import (AGG_MAX, AGG_SUM, DEF_BISECTOR, DEF_CENTROID, DEF_LOM,
                                   DEF_MOM, DEF_SOM, GAP_RTOL, IMP_MIN, MAX_RTOL)
from fuzzynav.fuzzy.membership import TRAP

__all__ = ["vertex_limits", "build_piece", "merge", "linear_centroid", "linear_bisector",
           "maximum_threshold", "point_maxima", "linear_maxima", "envelope_defuzz"]


# ----------------------------------------------------------------------------- pieces
@numba.njit(cache=True, inline="always", error_model="numpy")
def _put(work, base, k, x, left, right):
    o = base + 3 * k
    work[o] = x
    work[o + 1] = left
    work[o + 2] = right


@numba.njit(cache=True, error_model="numpy", inline="always")
def _append_raw(work, base, n, x, v):
    # consecutive vertices at the same x collapse into one with a jump (left, right)
    if n > 0 and work[base + 3 * (n - 1)] == x:
        work[base + 3 * (n - 1) + 2] = v
        return n
    _put(work, base, n, x, v, v)
    return n + 1


@numba.njit(cache=True, error_model="numpy", inline="always")
def _raw_shape(fp, code, off, work, base):
    """Vertices of the unit tri/trap (0 outside) at ``base``; returns their count."""
    n = 0
    n = _append_raw(work, base, n, fp[off], 0.0)
    n = _append_raw(work, base, n, fp[off + 1], 1.0)
    if code == TRAP:
        n = _append_raw(work, base, n, fp[off + 2], 1.0)
        n = _append_raw(work, base, n, fp[off + 3], 0.0)
    else:
        n = _append_raw(work, base, n, fp[off + 2], 0.0)
    return n


@numba.njit(cache=True, error_model="numpy", inline="always")
def _imply(work, src, n, h, imp, dst):
    """Clip (min) or scale (prod) the vertices at ``src`` by level ``h`` into ``dst``."""
    m = 0
    for k in range(n):
        x = work[src + 3 * k]
        left = work[src + 3 * k + 1]
        right = work[src + 3 * k + 2]
        if imp == IMP_MIN:
            if k > 0:
                x0 = work[src + 3 * (k - 1)]
                y0 = work[src + 3 * (k - 1) + 2]
                if (y0 - h) * (left - h) < 0.0:
                    xc = x0 + (h - y0) / (left - y0) * (x - x0)
                    if x0 < xc < x:
                        _put(work, dst, m, xc, h, h)
                        m += 1
            _put(work, dst, m, x, min(left, h), min(right, h))
        else:
            _put(work, dst, m, x, left * h, right * h)
        m += 1
    return m


@numba.njit(cache=True, error_model="numpy", inline="always")
def vertex_limits(work, base, n, x):
    """Left and right limits at ``x`` of the vertex list at ``base`` (0 outside it)."""
    if n == 0 or x < work[base] or x > work[base + 3 * (n - 1)]:
        return 0.0, 0.0
    for k in range(n):
        xk = work[base + 3 * k]
        if xk == x:
            return work[base + 3 * k + 1], work[base + 3 * k + 2]
        if xk > x:
            x0 = work[base + 3 * (k - 1)]
            y0 = work[base + 3 * (k - 1) + 2]
            v = y0 + (work[base + 3 * k + 1] - y0) * (x - x0) / (xk - x0)
            return v, v
    return 0.0, 0.0


@numba.njit(cache=True, error_model="numpy", inline="always")
def _truncate(work, src, n, lo, hi, dst):
    """Restrict the vertex list to [lo, hi], always starting at lo and ending at hi."""
    left, right = vertex_limits(work, src, n, lo)
    _put(work, dst, 0, lo, left, right)
    m = 1
    for k in range(n):
        x = work[src + 3 * k]
        if lo < x < hi:
            _put(work, dst, m, x, work[src + 3 * k + 1], work[src + 3 * k + 2])
            m += 1
    left, right = vertex_limits(work, src, n, hi)
    _put(work, dst, m, hi, left, right)
    return m + 1


@numba.njit(cache=True, error_model="numpy", inline="always")
def build_piece(fp, code, off, h, imp, lo, hi, work, scratch, dst):
    """Write the implied set of a tri/trap term at level ``h`` to ``work[dst]``.

    ``work[dst]`` receives the vertex count, the triples follow.  ``scratch`` needs 36
    free slots.  Returns the vertex count.
    """
    n = _raw_shape(fp, code, off, work, scratch)
    n = _imply(work, scratch, n, h, imp, scratch + 12)
    n = _truncate(work, scratch + 12, n, lo, hi, dst + 1)
    work[dst] = n
    return n


# --------------------------------------------------------------------------- envelope
@numba.njit(cache=True, inline="always", error_model="numpy")
def _combine(a, b, agg):
    if agg == AGG_MAX:
        return max(a, b)
    if agg == AGG_SUM:
        return a + b
    return a + b - a * b


@numba.njit(cache=True, error_model="numpy", inline="always")
def _interp_inside(work, base, j, x):
    # value at x strictly between vertices j - 1 and j
    if j == 0:
        return work[base + 1]
    x0 = work[base + 3 * (j - 1)]
    y0 = work[base + 3 * (j - 1) + 2]
    x1 = work[base + 3 * j]
    return y0 + (work[base + 3 * j + 1] - y0) * (x - x0) / (x1 - x0)


@numba.njit(cache=True, error_model="numpy")
def merge(work, fo, nf, go, ng, oo, agg):
    """Aggregate two vertex lists spanning the same [lo, hi] into ``work[oo]``.

    Returns the number of output points.  With max aggregation the crossing of the two
    functions inside an interval becomes a point (valued from the flatter function, so a
    plateau level is kept exactly).
    """
    i = 0
    j = 0
    n = 0
    px = 0.0
    pf = 0.0
    pg = 0.0
    while i < nf or j < ng:
        xf = work[fo + 3 * i] if i < nf else math.inf
        xg = work[go + 3 * j] if j < ng else math.inf
        if xf < xg:
            x = xf
            fl = work[fo + 3 * i + 1]
            fr = work[fo + 3 * i + 2]
            gl = _interp_inside(work, go, j, x)
            gr = gl
            i += 1
        elif xg < xf:
            x = xg
            gl = work[go + 3 * j + 1]
            gr = work[go + 3 * j + 2]
            fl = _interp_inside(work, fo, i, x)
            fr = fl
            j += 1
        else:
            x = xf
            fl = work[fo + 3 * i + 1]
            fr = work[fo + 3 * i + 2]
            gl = work[go + 3 * j + 1]
            gr = work[go + 3 * j + 2]
            i += 1
            j += 1
        if n > 0 and agg == AGG_MAX:
            dr = pf - pg
            dl = fl - gl
            if (dr > 0.0 and dl < 0.0) or (dr < 0.0 and dl > 0.0):
                t = dr / (dr - dl)
                xc = px + t * (x - px)
                if px < xc < x:
                    sf = fl - pf
                    sg = gl - pg
                    v = pf + sf * t if abs(sf) <= abs(sg) else pg + sg * t
                    _put(work, oo, n, xc, v, v)
                    n += 1
        _put(work, oo, n, x, _combine(fl, gl, agg), _combine(fr, gr, agg))
        n += 1
        px = x
        pf = fr
        pg = gr
    return n


# ----------------------------------------------------------------- linear envelopes
@numba.njit(cache=True, error_model="numpy")
def _solve_partial(y0, y1, d, r):
    """Offset t in [0, d] where the integral of the linear y0 -> y1 from 0 reaches r."""
    s = (y1 - y0) / d
    disc = y0 * y0 + 2.0 * s * r
    den = y0 + math.sqrt(max(disc, 0.0))
    if den <= 0.0:
        return 0.0
    return min(max(2.0 * r / den, 0.0), d)


@numba.njit(cache=True, error_model="numpy")
def _area(work, e, k):
    d = work[e + 3 * (k + 1)] - work[e + 3 * k]
    return 0.5 * d * (work[e + 3 * k + 2] + work[e + 3 * (k + 1) + 1])


@numba.njit(cache=True, error_model="numpy")
def linear_centroid(work, e, n, c):
    """Centroid of the envelope at ``e`` (n points, linear between); nan if no area."""
    area = 0.0
    mom = 0.0
    for k in range(n - 1):
        x0 = work[e + 3 * k] - c
        x1 = work[e + 3 * (k + 1)] - c
        y0 = work[e + 3 * k + 2]
        y1 = work[e + 3 * (k + 1) + 1]
        d = x1 - x0
        area += 0.5 * d * (y0 + y1)
        mom += d * (x0 * (2.0 * y0 + y1) + x1 * (y0 + 2.0 * y1)) / 6.0
    if not area > 0.0:
        return math.nan
    return c + mom / area


@numba.njit(cache=True, error_model="numpy")
def linear_bisector(work, e, n):
    """Point splitting the envelope's area in halves (middle of a zero gap if any)."""
    total = 0.0
    for k in range(n - 1):
        total += _area(work, e, k)
    if not total > 0.0:
        return math.nan
    half = 0.5 * total
    cum = 0.0
    for k in range(n - 1):
        a = _area(work, e, k)
        if a > 0.0 and cum + a >= half:
            x0 = work[e + 3 * k]
            x1 = work[e + 3 * (k + 1)]
            xb = x0 + _solve_partial(work[e + 3 * k + 2], work[e + 3 * (k + 1) + 1],
                                     x1 - x0, half - cum)
            if cum + a - half <= GAP_RTOL * total:
                k2 = k + 1
                while k2 < n - 1 and _area(work, e, k2) <= 0.0:
                    k2 += 1
                if k2 > k + 1 and k2 < n - 1:
                    return 0.5 * (x1 + work[e + 3 * k2])
            return xb
        cum += a
    return work[e + 3 * (n - 1)]


@numba.njit(cache=True, error_model="numpy")
def maximum_threshold(work, e, n):
    """Lowest envelope value counted as the maximum: its peak less MAX_RTOL relative."""
    h = 0.0
    for k in range(n):
        h = max(h, work[e + 3 * k + 1], work[e + 3 * k + 2])
    return h - MAX_RTOL * h


@numba.njit(cache=True, error_model="numpy")
def point_maxima(work, e, n, method):
    """mom / som / lom from the point values (isolated maxima only) of the envelope."""
    thr = maximum_threshold(work, e, n)
    if not thr > 0.0:  # the envelope's peak is zero: nothing fired
        return math.nan
    first = math.nan
    last = math.nan
    s = 0.0
    cnt = 0
    for k in range(n):
        if max(work[e + 3 * k + 1], work[e + 3 * k + 2]) >= thr:
            x = work[e + 3 * k]
            if cnt == 0:
                first = x
            last = x
            s += x
            cnt += 1
    if method == DEF_SOM:
        return first
    if method == DEF_LOM:
        return last
    return s / cnt


@numba.njit(cache=True, error_model="numpy")
def linear_maxima(work, e, n, method):
    """mom (measure-weighted over plateaus, else mean of maximising points), som, lom."""
    res = point_maxima(work, e, n, method)
    if method != DEF_MOM or math.isnan(res):
        return res
    thr = maximum_threshold(work, e, n)
    meas = 0.0
    mom = 0.0
    for k in range(n - 1):
        if work[e + 3 * k + 2] >= thr and work[e + 3 * (k + 1) + 1] >= thr:
            x0 = work[e + 3 * k]
            x1 = work[e + 3 * (k + 1)]
            meas += x1 - x0
            mom += (x1 - x0) * 0.5 * (x0 + x1)
    if meas > 0.0:
        return mom / meas
    return res


@numba.njit(cache=True, error_model="numpy")
def envelope_defuzz(work, e, n, method, c):
    """Defuzzify a linear envelope (max or sum aggregation)."""
    if method == DEF_CENTROID:
        return linear_centroid(work, e, n, c)
    if method == DEF_BISECTOR:
        return linear_bisector(work, e, n)
    if method == DEF_MOM or method == DEF_SOM or method == DEF_LOM:
        return linear_maxima(work, e, n, method)
    return math.nan

