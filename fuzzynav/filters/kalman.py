"""Kalman-filter kernels as pure numba functions on plain arrays.

* :func:`propagate` — ``P <- Phi P Phi^T + Qd`` skipping the zeros of ``Phi``;
* :func:`innovation_cov` — ``PHt = P H^T``, ``HPH = H P H^T`` for ``m`` rows;
* :func:`cholesky`, :func:`chol_solve`, :func:`nis` — small dense solves on ``S``;
* :func:`joseph_update` — ``x = K r`` and the Joseph-form covariance
  ``P = (I - K H) P (I - K H)^T + K R K^T`` (evaluated as ``A P - (A P H^T) K^T + K R K^T``
  with ``A P = P - K (P H^T)^T``), then symmetrised;
* :func:`covariance_ok` — finite, positive diagonal, correlations within [-1, 1].

Shapes: ``n`` states, ``m <= M`` measurement rows; work arrays are passed in so that the
kernels never allocate inside the filter loop.
"""
from __future__ import annotations

import math

import numba as nb


@nb.njit(cache=True)
def propagate(P, Phi, Qd, work):
    """In place ``P <- Phi P Phi^T + Qd`` (``work`` is an n x n scratch array)."""
    n = P.shape[0]
    work[:, :] = 0.0
    for i in range(n):
        for k in range(n):
            a = Phi[i, k]
            if a != 0.0:
                for j in range(n):
                    work[i, j] += a * P[k, j]
    for i in range(n):
        for j in range(i, n):
            s = Qd[i, j]
            for k in range(n):
                b = Phi[j, k]
                if b != 0.0:
                    s += work[i, k] * b
            P[i, j] = s
            P[j, i] = s


@nb.njit(cache=True)
def sparse_left_mul(A, B, out):
    """``out = A B`` for square ``A``, skipping the zeros of ``A`` (the system matrices)."""
    n = A.shape[0]
    out[:, :] = 0.0
    for i in range(n):
        for k in range(n):
            a = A[i, k]
            if a != 0.0:
                for j in range(n):
                    out[i, j] += a * B[k, j]


@nb.njit(cache=True)
def times_Ht(A, H, m, out):
    """``out[:, :m] = A H^T`` for the first ``m`` rows of H, skipping H's zeros."""
    n = A.shape[0]
    for i in range(n):
        for r in range(m):
            s = 0.0
            for k in range(n):
                h = H[r, k]
                if h != 0.0:
                    s += A[i, k] * h
            out[i, r] = s


@nb.njit(cache=True)
def innovation_cov(P, H, m, PHt, HPH):
    """``PHt[:, :m] = P H^T`` and ``HPH[:m, :m] = H P H^T`` for the first ``m`` rows of H."""
    n = P.shape[0]
    times_Ht(P, H, m, PHt)
    for a in range(m):
        for b in range(a, m):
            s = 0.0
            for k in range(n):
                h = H[a, k]
                if h != 0.0:
                    s += h * PHt[k, b]
            HPH[a, b] = s
            HPH[b, a] = s


@nb.njit(cache=True)
def cholesky(S, m, L):
    """Lower Cholesky factor of ``S[:m, :m]`` into ``L``; False if not positive definite."""
    for j in range(m):
        s = S[j, j]
        for k in range(j):
            s -= L[j, k] * L[j, k]
        if not s > 0.0:
            return False
        d = math.sqrt(s)
        L[j, j] = d
        for i in range(j + 1, m):
            t = S[i, j]
            for k in range(j):
                t -= L[i, k] * L[j, k]
            L[i, j] = t / d
        for i in range(j):
            L[i, j] = 0.0
    return True


@nb.njit(cache=True)
def chol_solve_vec(L, m, b, out):
    """Solve ``L L^T out = b`` for a vector (first ``m`` entries); ``out`` may be ``b``."""
    for i in range(m):
        s = b[i]
        for k in range(i):
            s -= L[i, k] * out[k]
        out[i] = s / L[i, i]
    for i in range(m - 1, -1, -1):
        s = out[i]
        for k in range(i + 1, m):
            s -= L[k, i] * out[k]
        out[i] = s / L[i, i]


@nb.njit(cache=True)
def nis(L, m, r, work):
    """Normalised innovation squared ``r^T S^-1 r`` from the Cholesky factor of S."""
    acc = 0.0
    for i in range(m):
        s = r[i]
        for k in range(i):
            s -= L[i, k] * work[k]
        work[i] = s / L[i, i]
        acc += work[i] * work[i]
    return acc


@nb.njit(cache=True)
def gain(L, m, PHt, K, work):
    """``K = PHt S^-1`` (rows of PHt solved against the Cholesky factor of S)."""
    for i in range(PHt.shape[0]):
        for r in range(m):
            work[r] = PHt[i, r]
        chol_solve_vec(L, m, work, work)  # safe in place: see chol_solve_vec
        for r in range(m):
            K[i, r] = work[r]


@nb.njit(cache=True)
def joseph_update(P, H, R, m, r, PHt, K, x, AP, APHt):
    """State correction ``x = K r`` and Joseph-form covariance update, in place.

    ``R`` is the diagonal measurement variance (length >= m); ``K`` must hold the gain.
    """
    n = P.shape[0]
    for i in range(n):
        s = 0.0
        for a in range(m):
            s += K[i, a] * r[a]
        x[i] = s
    # A P = P - K (P H^T)^T
    for i in range(n):
        for j in range(n):
            s = P[i, j]
            for a in range(m):
                s -= K[i, a] * PHt[j, a]
            AP[i, j] = s
    times_Ht(AP, H, m, APHt)
    # P = A P - (A P H^T) K^T + K R K^T, symmetrised
    for i in range(n):
        for j in range(i, n):
            s = AP[i, j]
            for a in range(m):
                s += -APHt[i, a] * K[j, a] + K[i, a] * R[a] * K[j, a]
            t = AP[j, i]
            for a in range(m):
                t += -APHt[j, a] * K[i, a] + K[j, a] * R[a] * K[i, a]
            v = 0.5 * (s + t)
            P[i, j] = v
            P[j, i] = v


@nb.njit(cache=True)
def covariance_ok(P):
    """True when P is finite with a positive diagonal and |correlations| <= 1 (+1e-9)."""
    n = P.shape[0]
    for i in range(n):
        if not (P[i, i] > 0.0) or not math.isfinite(P[i, i]):
            return False
    for i in range(n):
        for j in range(i + 1, n):
            c = P[i, j]
            if not math.isfinite(c) or c * c > P[i, i] * P[j, j] * (1.0 + 1e-9):
                return False
    return True


@nb.njit(cache=True)
def scale_predicted(P, Qacc, factor, H, m, d):
    """Weight the propagated part of P on the states the measurement sees directly.

    ``P <- D (P - Qacc) D + Qacc`` with ``D_ii = sqrt(factor)`` for the states with a non-zero
    column in the first ``m`` rows of ``H`` and 1 elsewhere (``d`` is an n-vector scratch).
    With every state seen this is ``factor (P - Qacc) + Qacc`` (alpha^2 or lambda of a
    fading filter); restricting it keeps one sensor's weighting from inflating the states
    only another sensor corrects — the single-filter form of the papers' sub-filters.
    """
    n = P.shape[0]
    s = math.sqrt(factor)
    for j in range(n):
        d[j] = 1.0
        for a in range(m):
            if H[a, j] != 0.0:
                d[j] = s
                break
    for i in range(n):
        for j in range(n):
            P[i, j] = d[i] * d[j] * (P[i, j] - Qacc[i, j]) + Qacc[i, j]
