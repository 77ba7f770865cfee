"""Kalman-filter kernels as pure numba functions on plain arrays.

* :func:`propagate` — ``P <- Phi P Phi^T + Qd``, the diagonal tail of ``Phi`` as scalings
  (:func:`propagate_tail` when the caller knows the tail);
* :func:`innovation_cov` — ``PHt = P H^T``, ``HPH = H P H^T`` for ``m`` rows;
* :func:`cholesky`, :func:`chol_solve`, :func:`nis` — small dense solves on ``S``;
* :func:`joseph_update` — ``x = K r`` and the Joseph-form covariance
  ``P = (I - K H) P (I - K H)^T + K R K^T``, expanded exactly into
  ``P - K (P H^T)^T + (K S - P H^T) K^T`` (one pass over the upper triangle);
* :func:`correct` — :func:`gain` and :func:`joseph_update`, as the filter loop runs them;
* :func:`covariance_ok` — finite, positive diagonal, correlations within [-1, 1].

Shapes: ``n`` states, ``m <= M`` measurement rows; work arrays are passed in so that the
kernels never allocate inside the filter loop.
"""
from __future__ import annotations

import math

import numba as nb

from fuzzynav.filters import sized

__all__ = ["diagonal_tail", "propagate", "propagate_tail", "sparse_left_mul", "square_tail",
           "innovation_cov", "cholesky", "chol_solve_vec", "nis", "gain", "joseph_update",
           "correct", "covariance_ok", "scale_predicted"]


@nb.njit(cache=True, error_model="numpy")
def diagonal_tail(A):
    """First row ``d`` from which every row of square ``A`` is zero off the diagonal.

    The system and transition matrices have this shape: the sensor-error blocks only decay
    (or stay), so their rows hold a diagonal entry at most.  Kernels treat rows ``>= d`` as
    a diagonal and the rows above as dense (they are ~85 % filled).
    """
    n = A.shape[0]
    for i in range(n - 1, -1, -1):
        for j in range(n):
            if j != i and A[i, j] != 0.0:
                return i + 1
    return 0


@nb.njit(cache=True, error_model="numpy")
def propagate(P, Phi, Qd, work):
    """In place ``P <- Phi P Phi^T + Qd`` (``work`` is an n x n scratch array).

    Rows of ``Phi`` from :func:`diagonal_tail` on are scalings; the others are multiplied
    densely (a zero entry adds an exact zero, so the result is the same as skipping it).
    The 15-state model runs a copy compiled with its sizes as constants
    (:mod:`fuzzynav.filters.sized`).
    """
    propagate_tail(P, Phi, Qd, work, diagonal_tail(Phi))


@nb.njit(cache=True, error_model="numpy")
def propagate_tail(P, Phi, Qd, work, d):
    """:func:`propagate` for a ``Phi`` whose rows from ``d`` on are diagonal (a caller that
    knows the tail, e.g. from ``F``, spares the scan; a ``d`` past the true tail is exact)."""
    n = P.shape[0]
    if sized.fixed(n, d):
        sized.propagate_sized(P, Phi, Qd, work, sized.FIXED_N, sized.FIXED_D)
    else:
        sized.propagate_sized(P, Phi, Qd, work, n, d)


@nb.njit(cache=True, error_model="numpy")
def sparse_left_mul(A, B, out):
    """``out = A B`` for square ``A``, skipping the zeros of ``A`` (the system matrices)."""
    n = A.shape[0]
    out[:, :] = 0.0
    for i in range(n):
        _add_rows(A, i, B, n, out)


@nb.njit(cache=True, error_model="numpy")
def _add_rows(A, i, B, k_end, out):
    """``out[i] += sum_k A[i, k] B[k]`` over ``k < k_end``, skipping the zeros of ``A``."""
    for k in range(k_end):
        a = A[i, k]
        if a != 0.0:
            for j in range(B.shape[1]):
                out[i, j] += a * B[k, j]


@nb.njit(cache=True, error_model="numpy")
def square_tail(F, d, out):
    """``out = F F`` for ``F`` whose rows from ``d`` on are diagonal (:func:`diagonal_tail`).

    The rows above ``d`` are multiplied densely over their first ``d`` columns (the tail
    rows contribute their diagonal entry only, added last).
    """
    sized.square_sized(F, d, F.shape[0], out)


@nb.njit(cache=True, error_model="numpy")
def innovation_cov(P, H, m, PHt, HPH):
    """``PHt[:, :m] = P H^T`` and ``HPH[:m, :m] = H P H^T`` for the first ``m`` rows of H."""
    n = P.shape[0]
    if sized.fixed_count(n):
        sized.innovation_sized(P, H, m, PHt, HPH, sized.FIXED_N)
    else:
        sized.innovation_sized(P, H, m, PHt, HPH, n)


@nb.njit(cache=True, error_model="numpy")
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


@nb.njit(cache=True, error_model="numpy")
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


@nb.njit(cache=True, error_model="numpy")
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


@nb.njit(cache=True, error_model="numpy")
def gain(L, m, PHt, K, work):
    """``K = PHt S^-1`` (rows of PHt solved against the Cholesky factor ``L`` of S); see
    :func:`~fuzzynav.filters.sized.gain_sized`."""
    n = PHt.shape[0]
    if sized.fixed_count(n):
        sized.gain_sized(L, m, PHt, K, work, sized.FIXED_N)
    else:
        sized.gain_sized(L, m, PHt, K, work, n)


@nb.njit(cache=True, error_model="numpy")
def joseph_update(P, H, R, m, r, PHt, K, x, AP, APHt):
    """State correction ``x = K r`` and Joseph-form covariance update, in place.

    ``R`` is the diagonal measurement variance (length >= m); ``K`` must hold the gain;
    ``AP`` (n x n, n >= m) and ``APHt`` (n x m) are scratch.  The Joseph form
    ``(I - K H) P (I - K H)^T + K R K^T`` is expanded, exactly for any ``K``, into
    ``P - K (P H^T)^T + V K^T`` with ``V = K S - P H^T`` and ``S = H P H^T + R``: ``V``
    is the gain's residual (zero for the exact optimal gain), so the form keeps Joseph's
    first-order insensitivity to gain errors while costing ``2 m`` products per entry of
    the upper triangle instead of two ``n x n x m`` products; the result is symmetric.
    """
    n = P.shape[0]
    if sized.fixed_count(n):
        sized.joseph_sized(P, H, R, m, r, PHt, K, x, AP, APHt, sized.FIXED_N)
    else:
        sized.joseph_sized(P, H, R, m, r, PHt, K, x, AP, APHt, n)


@nb.njit(cache=True, error_model="numpy")
def correct(L, P, H, R, m, r, PHt, K, x, AP, APHt, work):
    """:func:`gain`, then :func:`joseph_update`: the filter loop's update.

    Besides the 15-state copy, the common row counts have copies with ``m`` a constant
    too (2: an imaging polarization fix; 3: a position or velocity fix; 6: both), whose
    loops over the rows LLVM unrolls (0.7x the time of the copy with ``m`` at run time).
    """
    n = P.shape[0]
    if not sized.fixed_count(n):
        gain(L, m, PHt, K, work)
        joseph_update(P, H, R, m, r, PHt, K, x, AP, APHt)
    elif m == 2:
        sized.gain_sized(L, 2, PHt, K, work, sized.FIXED_N)
        sized.joseph_sized(P, H, R, 2, r, PHt, K, x, AP, APHt, sized.FIXED_N)
    elif m == 3:
        sized.gain_sized(L, 3, PHt, K, work, sized.FIXED_N)
        sized.joseph_sized(P, H, R, 3, r, PHt, K, x, AP, APHt, sized.FIXED_N)
    elif m == 6:
        sized.gain_sized(L, 6, PHt, K, work, sized.FIXED_N)
        sized.joseph_sized(P, H, R, 6, r, PHt, K, x, AP, APHt, sized.FIXED_N)
    else:
        sized.gain_sized(L, m, PHt, K, work, sized.FIXED_N)
        sized.joseph_sized(P, H, R, m, r, PHt, K, x, AP, APHt, sized.FIXED_N)


@nb.njit(cache=True, error_model="numpy")
def covariance_ok(P):
    """True when P is finite with a positive diagonal and |correlations| <= 1 (+1e-9)."""
    n = P.shape[0]
    for i in range(n):
        if not (P[i, i] > 0.0) or not math.isfinite(P[i, i]):
            return False
    ok = True
    for i in range(n):  # no early exit: the comparisons run as one branch-free pass
        for j in range(i + 1, n):
            c = P[i, j]
            ok &= c * c <= P[i, i] * P[j, j] * (1.0 + 1e-9)  # False for NaN, inf
    return ok


@nb.njit(cache=True, error_model="numpy")
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
