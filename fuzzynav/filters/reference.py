"""Plain numpy Kalman predict and update: the package's one textbook reference.

The same algebra as the compiled kernels (:mod:`fuzzynav.filters.kalman`), written the
obvious way, for code outside the loop: the alignment filter (:mod:`fuzzynav.align.fine`),
the kernel tests and the numpy benchmark peer (``benchmarks/numpy_reference_filter.py``).
"""
from __future__ import annotations

import numpy as np

__all__ = ["joseph", "predict", "update"]


def predict(x, P, Phi, Qd):
    """``(Phi x, Phi P Phi^T + Qd)``; ``x`` may be None (an error state fed back and zero
    between updates), then so is the first item."""
    return (None if x is None else Phi @ x), Phi @ P @ Phi.T + Qd


def joseph(P, K, H, R):
    """``(I - K H) P (I - K H)^T + K R K^T``, right for any gain ``K`` (not symmetrised)."""
    IKH = np.eye(P.shape[0]) - K @ H
    return IKH @ P @ IKH.T + K @ R @ K.T


def update(x, P, z, H, R):
    """Kalman update of ``(x (n,), P (n, n))`` by ``z (m,) = H (m, n) x + v``, ``v ~ N(0, R)``.

    ``K = P H^T S^-1`` (a linear solve with ``S = H P H^T + R``), ``x + K (z - H x)`` and the
    Joseph form of ``P``, symmetrised so it stays symmetric PSD.  Returns ``(x, P)``.
    """
    S = H @ P @ H.T + R
    K = np.linalg.solve(S, H @ P).T
    P = joseph(P, K, H, R)
    return x + K @ (z - H @ x), 0.5 * (P + P.T)
