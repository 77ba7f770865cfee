"""The bank's information fusion as it was before the triangular inverse (revision 35a4406):
each ``P_i^-1`` column by column, two triangular solves per column.  Kept here only as the
peer that ``bench_bank.py`` times the shipped :func:`fuzzynav.filters.bank_fusion.fuse`
against (same scaling, same arithmetic otherwise)."""
from __future__ import annotations

import math

import numba as nb

from fuzzynav.filters import kalman


@nb.njit(cache=True)
def _inverse_by_columns(A, out, L, col):
    n = A.shape[0]
    if not kalman.cholesky(A, n, L):
        return False
    for j in range(n):
        for i in range(n):
            col[i] = 0.0
        col[j] = 1.0
        kalman.chol_solve_vec(L, n, col, col)
        for i in range(n):
            out[i, j] = col[i]
    for i in range(n):
        for j in range(i + 1, n):
            v = 0.5 * (out[i, j] + out[j, i])
            out[i, j] = v
            out[j, i] = v
    return True


@nb.njit(cache=True)
def fuse_by_columns(P, x, Pg, xg, work):
    """``Pg = (sum P_i^-1)^-1``, ``xg = Pg sum P_i^-1 x_i`` with explicit column inverses."""
    d, Y, y, A, Ai, L, col, _ = work
    nl, n = x.shape
    for i in range(n):
        d[i] = math.sqrt(P[0, i, i])
        y[i] = 0.0
        for j in range(n):
            Y[i, j] = 0.0
    for k in range(nl):
        for i in range(n):
            for j in range(n):
                A[i, j] = P[k, i, j] / (d[i] * d[j])
        if not _inverse_by_columns(A, Ai, L, col):
            return False
        for i in range(n):
            s = 0.0
            for j in range(n):
                Y[i, j] += Ai[i, j]
                s += Ai[i, j] * (x[k, j] / d[j])
            y[i] += s
    if not _inverse_by_columns(Y, Ai, L, col):
        return False
    kalman.chol_solve_vec(L, n, y, y)
    for i in range(n):
        xg[i] = d[i] * y[i]
        for j in range(n):
            Pg[i, j] = d[i] * Ai[i, j] * d[j]
    return True


@nb.njit(cache=True)
def repeat_fusions(fn, P, x, Pg, xg, work, times):
    """Call ``fn`` ``times`` times in a compiled loop (no Python call per fusion)."""
    ok = True
    for _ in range(times):
        ok = fn(P, x, Pg, xg, work) and ok
    return ok
