"""Covariance kernels with the state count as an argument, for compiling with constants.

The kernels here take the state count ``n`` and the diagonal tail ``d`` (the first row
from which the transition or system matrix is diagonal, :func:`~fuzzynav.filters.kalman.
diagonal_tail`) as arguments and are inlined into their callers (numba
``inline="always"``).  A caller that passes the constants :data:`FIXED_N` and
:data:`FIXED_D` gets its own copy in which every loop has a fixed trip count, which LLVM
unrolls (the per-call costs of a paper000 run, against the base revision, are in the
breakdown of ``benchmarks/bench_ekf.py`` in docs/benchmarks.md).  Callers use
:func:`fixed` or :func:`fixed_count` to choose.

Products of two matrices run in register tiles of two rows by four columns
(:func:`rows_times`): eight independent sums share every load, where one dot product at a
time waits on each addition.

Every entry is one sum in ascending index order, whichever copy runs, so both give the
same numbers.
"""
from __future__ import annotations

import numba as nb

from fuzzynav.filters.layout import N_CORE

__all__ = ["fixed", "fixed_count", "rows_times", "propagate_sized", "square_sized",
           "discretize_sized", "times_Ht_sized", "innovation_sized", "gain_sized", "joseph_sized"]

#: state count and diagonal tail compiled as constants: the 15-state phi model, the
#: navigation error states and then gyro and accelerometer biases (3 each), which only decay
FIXED_N, FIXED_D = N_CORE + 6, N_CORE


@nb.njit(inline="always", error_model="numpy")
def fixed(n, d):
    """True when an ``n``-state matrix with diagonal tail ``d`` has the fixed copy's sizes."""
    return fixed_count(n) and d == FIXED_D


@nb.njit(inline="always", error_model="numpy")
def fixed_count(n):
    """True when ``n`` states have the fixed copy's size (kernels without a diagonal tail)."""
    return n == FIXED_N


@nb.njit(inline="always", error_model="numpy")
def rows_times(A, B, i, i1, K, n, out):
    """``out[r, :n] = A[r, :K] B[:K, :n]`` for rows ``r = i, i1``, two rows by four columns
    at a time (``i1 == i`` for a single row); sums from zero in ascending ``k``."""
    j0 = 0
    while j0 + 4 <= n:
        a0 = a1 = a2 = a3 = 0.0
        b0 = b1 = b2 = b3 = 0.0
        for k in range(K):
            u, v = A[i, k], A[i1, k]
            p0, p1, p2, p3 = B[k, j0], B[k, j0 + 1], B[k, j0 + 2], B[k, j0 + 3]
            a0 += u * p0
            a1 += u * p1
            a2 += u * p2
            a3 += u * p3
            b0 += v * p0
            b1 += v * p1
            b2 += v * p2
            b3 += v * p3
        out[i, j0], out[i, j0 + 1], out[i, j0 + 2], out[i, j0 + 3] = a0, a1, a2, a3
        out[i1, j0], out[i1, j0 + 1], out[i1, j0 + 2], out[i1, j0 + 3] = b0, b1, b2, b3
        j0 += 4
    for j in range(j0, n):
        a0 = b0 = 0.0
        for k in range(K):
            p = B[k, j]
            a0 += A[i, k] * p
            b0 += A[i1, k] * p
        out[i, j], out[i1, j] = a0, b0


@nb.njit(inline="always", error_model="numpy")
def propagate_sized(P, Phi, Qd, work, n, d):
    """``P <- Phi P Phi^T + Qd`` in place (:func:`fuzzynav.filters.kalman.propagate`)."""
    for i in range(0, d, 2):  # work[:d] = Phi[:d] P
        rows_times(Phi, P, i, i + 1 if i + 1 < d else i, n, n, work)
    for i in range(d, n):
        a = Phi[i, i]
        for j in range(n):
            work[i, j] = a * P[i, j]
    for r in range(d):  # upper triangle of work Phi^T + Qd; rows of Phi >= d are diagonal
        for j in range(r, d):
            s = Qd[r, j]
            for k in range(n):
                s += work[r, k] * Phi[j, k]
            P[r, j] = s
        for j in range(d, n):
            P[r, j] = Qd[r, j] + work[r, j] * Phi[j, j]
    for r in range(d, n):
        for j in range(r, n):
            P[r, j] = Qd[r, j] + work[r, j] * Phi[j, j]
    for r in range(n):
        for j in range(r + 1, n):
            P[j, r] = P[r, j]


@nb.njit(inline="always", error_model="numpy")
def square_sized(F, d, n, out):
    """``out = F F`` for ``F`` whose rows from ``d`` on are diagonal: the rows above ``d``
    from the first ``d`` columns of ``F``, then the diagonal tail's own entries added
    (:func:`fuzzynav.filters.kalman.square_tail`)."""
    for i in range(0, d, 2):
        rows_times(F, F, i, i + 1 if i + 1 < d else i, d, n, out)
    for i in range(d):
        for j in range(d, n):
            out[i, j] += F[i, j] * F[j, j]
    for i in range(d, n):
        for j in range(n):
            out[i, j] = 0.0
        out[i, i] = F[i, i] * F[i, i]


@nb.njit(inline="always", error_model="numpy")
def discretize_sized(F, q_diag, dt, Phi, Qd, work, n, d):
    """Second-order ``Phi`` and ``Qd`` over ``dt`` (:func:`fuzzynav.filters.error_model.
    discretize`): ``F`` has rows ``>= d`` diagonal, ``q_diag`` is the diagonal of Q."""
    square_sized(F, d, n, work)
    h2 = 0.5 * dt * dt
    for i in range(n):
        for j in range(n):
            Phi[i, j] = F[i, j] * dt + work[i, j] * h2
        Phi[i, i] += 1.0
    # Qd = Q dt + (F Q + Q F^T) dt^2/2 + F Q F^T dt^3/3; (F Q F^T)[i, j] = F[i, j] q_j F[j, j]
    # where row j of F is diagonal, a dense sum over k above
    h3 = dt * dt * dt / 3.0
    for i in range(d):
        for k in range(n):
            work[i, k] = F[i, k] * q_diag[k]  # F Q, row by row
    for i in range(d):
        for j in range(i, d):
            s = 0.0
            for k in range(n):
                s += work[i, k] * F[j, k]
            Qd[i, j] = s
    for i in range(n):
        for j in range(i, n):
            acc = Qd[i, j] if j < d else F[i, j] * q_diag[j] * F[j, j]
            s = (F[i, j] * q_diag[j] + q_diag[i] * F[j, i]) * h2
            s += acc * h3
            if i == j:
                s += q_diag[i] * dt
            Qd[i, j] = s
            Qd[j, i] = s


@nb.njit(inline="always", error_model="numpy")
def times_Ht_sized(A, H, m, out, n):
    """``out[:, :m] = A H^T`` for the first ``m`` rows of H, skipping H's zeros."""
    for r in range(m):
        for i in range(n):
            out[i, r] = 0.0
        for k in range(n):  # a measurement row touches a few states: test each once
            h = H[r, k]
            if h != 0.0:
                for i in range(n):
                    out[i, r] += A[i, k] * h


@nb.njit(inline="always", error_model="numpy")
def innovation_sized(P, H, m, PHt, HPH, n):
    """``PHt[:, :m] = P H^T`` and ``HPH[:m, :m] = H P H^T`` (:func:`fuzzynav.filters.kalman.
    innovation_cov`)."""
    times_Ht_sized(P, H, m, PHt, n)
    for a in range(m):
        for b in range(a, m):
            HPH[a, b] = 0.0
        for k in range(n):
            h = H[a, k]
            if h != 0.0:
                for b in range(a, m):
                    HPH[a, b] += h * PHt[k, b]
        for b in range(a + 1, m):
            HPH[b, a] = HPH[a, b]


@nb.njit(inline="always", error_model="numpy")
def gain_sized(L, m, PHt, K, work, n):
    """``K = PHt S^-1`` (:func:`fuzzynav.filters.kalman.gain`): the rows of ``PHt`` solved
    against the Cholesky factor ``L`` of ``S``, all rows one substitution step at a time
    (the rows are independent, so the steps overlap), with ``1 / L[r, r]`` formed once
    into ``work[:m]``."""
    for r in range(m):
        work[r] = 1.0 / L[r, r]
    for r in range(m):  # L Y^T = PHt^T
        for i in range(n):
            s = PHt[i, r]
            for k in range(r):
                s -= L[r, k] * K[i, k]
            K[i, r] = s * work[r]
    for r in range(m - 1, -1, -1):  # L^T K^T = Y^T
        for i in range(n):
            s = K[i, r]
            for k in range(r + 1, m):
                s -= L[k, r] * K[i, k]
            K[i, r] = s * work[r]


@nb.njit(inline="always", error_model="numpy")
def joseph_sized(P, H, R, m, r, PHt, K, x, AP, APHt, n):
    """Gain correction and Joseph-form update (:func:`fuzzynav.filters.kalman.
    joseph_update`): ``x = K r``, ``P <- P - K (P H^T)^T + V K^T``, ``V = K S - P H^T``."""
    for i in range(n):
        s = 0.0
        for a in range(m):
            s += K[i, a] * r[a]
        x[i] = s
    S = AP  # S[:m, :m] = H P H^T + R from the sparse rows of H
    for a in range(m):
        for b in range(m):
            S[a, b] = 0.0
        for k in range(n):
            h = H[a, k]
            if h != 0.0:
                for b in range(m):
                    S[a, b] += h * PHt[k, b]
        S[a, a] += R[a]
    V = APHt
    for i in range(n):
        for a in range(m):
            s = -PHt[i, a]
            for b in range(m):
                s += K[i, b] * S[b, a]
            V[i, a] = s
    for i in range(n):  # upper triangle, then its mirror
        for j in range(i, n):
            s = P[i, j]
            for k in range(m):
                s += V[i, k] * K[j, k] - K[i, k] * PHt[j, k]
            P[i, j] = s
            P[j, i] = s
