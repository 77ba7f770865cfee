"""The numba evaluation kernels of a compiled fuzzy system.

``eval_compiled(fparams, iparams, x, y, work)`` evaluates one input vector without
allocating; the batch functions loop over rows.  The array layout is described in
:mod:`fuzzynav.fuzzy.compiled_layout` and built by :func:`fuzzynav.fuzzy.compiled.compile_fis`.
"""
from __future__ import annotations

import math

import numba
import numpy as np

from fuzzynav.fuzzy import compiled_layout as L
from fuzzynav.fuzzy.membership import CONSTANT, mf_scalar
from fuzzynav.fuzzy.probor_kernels import probor_defuzz
from fuzzynav.fuzzy.pwl_kernels import build_piece, envelope_defuzz, merge

__all__ = ["eval_compiled", "eval_compiled_into", "eval_compiled_batch", "eval_compiled_parallel"]


@numba.njit(cache=True, error_model="numpy", inline="always")
def _clamp_inputs(fp, ip, x, work):
    status = 0
    n_in = ip[L.N_IN]
    for i in range(n_in):
        if math.isnan(x[i]):
            return L.NAN_INPUT
    wx = ip[L.W_X]
    fr = ip[L.F_INRANGE]
    for i in range(n_in):
        v = x[i]
        lo = fp[fr + 2 * i]
        hi = fp[fr + 2 * i + 1]
        if v < lo:
            v = lo
            status |= L.CLAMPED
        elif v > hi:
            v = hi
            status |= L.CLAMPED
        work[wx + i] = v
    return status


@numba.njit(cache=True, error_model="numpy", inline="always")
def _fire_rules(fp, ip, work):
    """Membership degrees of every input term, then the firing strength of every rule."""
    wx = ip[L.W_X]
    wmu = ip[L.W_MU]
    wfire = ip[L.W_FIRE]
    oiv = ip[L.OFF_INVAR]
    oit = ip[L.OFF_INTERM]
    for i in range(ip[L.N_IN]):
        first = ip[oiv + 2 * i]
        for t in range(first, first + ip[oiv + 2 * i + 1]):
            work[wmu + t] = mf_scalar(ip[oit + 2 * t], fp, ip[oit + 2 * t + 1], work[wx + i])
    op_and = ip[L.OP_AND]
    op_or = ip[L.OP_OR]
    orule = ip[L.OFF_RULE]
    oante = ip[L.OFF_ANTE]
    fw = ip[L.F_WEIGHT]
    for r in range(ip[L.N_RULES]):
        is_or = ip[orule + 3 * r] == 1
        start = ip[orule + 3 * r + 1]
        acc = 0.0 if is_or else 1.0
        for a in range(start, start + ip[orule + 3 * r + 2]):
            mu = work[wmu + ip[oante + 3 * a + 1]]
            if ip[oante + 3 * a + 2] == 1:
                mu = 1.0 - mu
            if is_or:
                acc = max(acc, mu) if op_or == L.OR_MAX else acc + mu - acc * mu
            else:
                acc = min(acc, mu) if op_and == L.AND_MIN else acc * mu
        work[wfire + r] = acc * fp[fw + r]


@numba.njit(cache=True, error_model="numpy")
def _sugeno_output(fp, ip, o, work):
    """Weighted average (or sum) of the rule outputs of output ``o``; nan if none fired."""
    ptr = ip[L.OFF_OUTPTR]
    ocons = ip[L.OFF_CONS]
    oot = ip[L.OFF_OUTTERM]
    wfire = ip[L.W_FIRE]
    wx = ip[L.W_X]
    n_in = ip[L.N_IN]
    num = 0.0
    den = 0.0
    for c in range(ip[ptr + o], ip[ptr + o + 1]):
        w = work[wfire + ip[ocons + 2 * c]]
        if w <= 0.0:
            continue
        t = ip[ocons + 2 * c + 1]
        off = ip[oot + 2 * t + 1]
        if ip[oot + 2 * t] == CONSTANT:
            z = fp[off]
        else:
            z = fp[off + n_in]
            for i in range(n_in):
                z += fp[off + i] * work[wx + i]
        num += w * z
        den += w
    if not den > 0.0:
        return math.nan
    if ip[L.OP_DEFUZZ] == L.DEF_WTSUM:
        return num
    return num / den


@numba.njit(cache=True, error_model="numpy")
def _term_levels(ip, o, work, agg):
    """Aggregate the firing strengths per output term of ``o`` (max, sum or probor)."""
    ptr = ip[L.OFF_OUTPTR]
    ocons = ip[L.OFF_CONS]
    wl = ip[L.W_LEVEL]
    wfire = ip[L.W_FIRE]
    first = ip[ip[L.OFF_OUTVAR] + 4 * o]
    for t in range(first, first + ip[ip[L.OFF_OUTVAR] + 4 * o + 1]):
        work[wl + t] = 0.0
    for c in range(ip[ptr + o], ip[ptr + o + 1]):
        t = ip[ocons + 2 * c + 1]
        w = work[wfire + ip[ocons + 2 * c]]
        a = work[wl + t]
        if agg == L.AGG_MAX:
            work[wl + t] = max(a, w)
        elif agg == L.AGG_SUM:
            work[wl + t] = a + w
        else:
            work[wl + t] = a + w - a * w


@numba.njit(cache=True, error_model="numpy")
def _singleton_output(fp, ip, o, work):
    """Defuzzify the discrete set of singleton terms of output ``o``."""
    _term_levels(ip, o, work, ip[L.OP_AGG])
    wl = ip[L.W_LEVEL]
    oot = ip[L.OFF_OUTTERM]
    first = ip[ip[L.OFF_OUTVAR] + 4 * o]
    n = ip[ip[L.OFF_OUTVAR] + 4 * o + 1]
    h = 0.0
    for t in range(first, first + n):
        h = max(h, work[wl + t])
    if not h > 0.0:
        return math.nan
    method = ip[L.OP_DEFUZZ]
    thr = h - L.MAX_RTOL * h
    num = 0.0
    den = 0.0
    best = math.nan
    cnt = 0
    for t in range(first, first + n):
        x = fp[ip[oot + 2 * t + 1]]
        w = work[wl + t]
        if method == L.DEF_CENTROID:
            num += w * x
            den += w
        elif w >= thr:
            if method == L.DEF_MOM:
                num += x
                den += 1.0
            elif cnt == 0 or (method == L.DEF_SOM and x < best) or (
                    method == L.DEF_LOM and x > best):
                best = x
            cnt += 1
    if method == L.DEF_CENTROID or method == L.DEF_MOM:
        return num / den
    return best


@numba.njit(cache=True, error_model="numpy")
def _collect_pieces(fp, ip, o, work):
    """Build the implied sets of output ``o`` in the piece table; return their count."""
    lo = fp[ip[L.F_OUTRANGE] + 2 * o]
    hi = fp[ip[L.F_OUTRANGE] + 2 * o + 1]
    imp = ip[L.OP_IMP]
    oot = ip[L.OFF_OUTTERM]
    wp = ip[L.W_PIECE]
    scratch = ip[L.W_SCRATCH]
    npieces = 0
    if ip[L.MERGE_BY_TERM] == 1:
        _term_levels(ip, o, work, ip[L.OP_AGG])
        first = ip[ip[L.OFF_OUTVAR] + 4 * o]
        for t in range(first, first + ip[ip[L.OFF_OUTVAR] + 4 * o + 1]):
            h = work[ip[L.W_LEVEL] + t]
            if h > 0.0:
                build_piece(fp, ip[oot + 2 * t], ip[oot + 2 * t + 1], h, imp, lo, hi, work,
                            scratch, wp + npieces * L.PIECE_STRIDE)
                npieces += 1
        return npieces
    ptr = ip[L.OFF_OUTPTR]
    ocons = ip[L.OFF_CONS]
    for c in range(ip[ptr + o], ip[ptr + o + 1]):
        h = work[ip[L.W_FIRE] + ip[ocons + 2 * c]]
        if h > 0.0:
            t = ip[ocons + 2 * c + 1]
            build_piece(fp, ip[oot + 2 * t], ip[oot + 2 * t + 1], h, imp, lo, hi, work,
                        scratch, wp + npieces * L.PIECE_STRIDE)
            npieces += 1
    return npieces


@numba.njit(cache=True, error_model="numpy")
def _mamdani_output(fp, ip, o, work):
    """Exact defuzzified value of Mamdani output ``o``; nan when its set is empty."""
    kind = ip[ip[L.OFF_OUTVAR] + 4 * o + 2]
    if kind == L.OUT_SINGLETON:
        return _singleton_output(fp, ip, o, work)
    npieces = _collect_pieces(fp, ip, o, work)
    if npieces == 0:
        return math.nan
    agg = ip[L.OP_AGG]
    wp = ip[L.W_PIECE]
    cap = ip[L.ENV_CAP]
    env_a = ip[L.W_ENV]
    env_b = env_a + 3 * cap
    n = int(work[wp])
    for k in range(3 * n):
        work[env_a + k] = work[wp + 1 + k]
    cur = env_a
    nxt = env_b
    for p in range(1, npieces):
        base = wp + p * L.PIECE_STRIDE
        n = merge(work, cur, n, base + 1, int(work[base]), nxt, agg)
        cur, nxt = nxt, cur
    lo = fp[ip[L.F_OUTRANGE] + 2 * o]
    hi = fp[ip[L.F_OUTRANGE] + 2 * o + 1]
    c = 0.5 * (lo + hi)
    if agg == L.AGG_PROBOR:
        return probor_defuzz(fp, ip[L.F_GL], work, cur, n, wp, npieces, L.PIECE_STRIDE,
                             ip[L.W_SCRATCH], ip[L.OP_DEFUZZ], c)
    return envelope_defuzz(work, cur, n, ip[L.OP_DEFUZZ], c)


@numba.njit(cache=True, error_model="numpy")
def eval_compiled(fparams, iparams, x, y, work):
    """Evaluate a compiled fuzzy system on one input vector, without allocating.

    Parameters
    ----------
    fparams : float64[:]
        Every float of the system (``CompiledFIS.fparams``).
    iparams : int64[:]
        Every integer of the system (``CompiledFIS.iparams``).
    x : float64[n_inputs]
        Inputs in the system's input order (unclamped).
    y : float64[n_outputs]
        Written: the outputs.
    work : float64[work_size]
        Scratch space (``CompiledFIS.work_size``), reusable across calls.

    Returns
    -------
    int
        Bitmask: 1 an input was clamped to its range, 2 an output had no rule fire (it
        holds its default), 4 an input was NaN (every output is NaN).
    """
    n_out = iparams[L.N_OUT]
    status = _clamp_inputs(fparams, iparams, x, work)
    if status & L.NAN_INPUT:
        for o in range(n_out):
            y[o] = math.nan
        return status
    _fire_rules(fparams, iparams, work)
    sugeno = iparams[L.KIND] == L.SUGENO
    for o in range(n_out):
        if sugeno:
            v = _sugeno_output(fparams, iparams, o, work)
        else:
            v = _mamdani_output(fparams, iparams, o, work)
        if math.isnan(v):
            v = fparams[iparams[L.F_DEFAULT] + o]
            status |= L.NO_RULE
        y[o] = v
    return status


@numba.njit(cache=True, error_model="numpy")
def eval_compiled_into(fparams, iparams, X, Y, status):
    """Evaluate every row of ``X`` (n, n_inputs) into ``Y`` (n, n_outputs) and ``status``.

    Returns the number of rows with a clamped input.
    """
    work = np.empty(iparams[L.WORK_SIZE])
    n_clamped = 0
    for s in range(X.shape[0]):
        st = eval_compiled(fparams, iparams, X[s], Y[s], work)
        status[s] = st
        if st & L.CLAMPED:
            n_clamped += 1
    return n_clamped


@numba.njit(cache=True, error_model="numpy")
def eval_compiled_batch(fparams, iparams, X):
    """Evaluate every row of ``X`` (float64[n, n_inputs]).

    Returns
    -------
    Y : float64[n, n_outputs]
    n_clamped : int
        Number of rows in which at least one input was clamped to its range.
    """
    Y = np.empty((X.shape[0], iparams[L.N_OUT]))
    status = np.empty(X.shape[0], dtype=np.int64)
    n_clamped = eval_compiled_into(fparams, iparams, X, Y, status)
    return Y, n_clamped


@numba.njit(cache=True, parallel=True, error_model="numpy")
def eval_compiled_parallel(fparams, iparams, X, Y, status, n_chunks):
    """Like :func:`eval_compiled_into`, split into ``n_chunks`` parallel row blocks."""
    n = X.shape[0]
    for c in numba.prange(n_chunks):
        work = np.empty(iparams[L.WORK_SIZE])
        for s in range(c * n // n_chunks, (c + 1) * n // n_chunks):
            status[s] = eval_compiled(fparams, iparams, X[s], Y[s], work)
