"""Plain numpy Kalman predict and update: the package's one textbook reference.

The compiled loop (:mod:`fuzzynav.filters.kalman`) works in place on scratch arrays; this
module is the same algebra written the obvious way, for code that runs outside the loop (the
alignment filter, :mod:`fuzzynav.align.fine`), for the tests that check the compiled kernels
and for the numpy benchmark peer (``benchmarks/numpy_reference_filter.py``).

* :func:`predict` — ``x <- Phi x``, ``P <- Phi P Phi^T + Qd``;
* :func:`update` — ``K = P H^T S^-1`` with ``S = H P H^T + R`` (a linear solve, no inverse),
  ``x <- x + K (z - H x)`` and the Joseph form
  ``P <- (I - K H) P (I - K H)^T + K R K^T``, symmetrised, so ``P`` stays symmetric PSD for
  any gain.
"""
from __future__ import annotations

import numpy as np

__all__ = ["predict", "update", "joseph"]


def predict(x, P, Phi, Qd):
    """``(Phi x, Phi P Phi^T + Qd)``; ``x`` may be None (an error-state filter whose state
    is fed back and zero between updates), then so is the first item."""
    return (None if x is None else Phi @ x), Phi @ P @ Phi.T + Qd


def joseph(P, K, H, R):
    """``(I - K H) P (I - K H)^T + K R K^T`` for any gain ``K`` (not symmetrised)."""
    IKH = np.eye(P.shape[0]) - K @ H
    return IKH @ P @ IKH.T + K @ R @ K.T


def update(x, P, z, H, R):
    """The Kalman update of ``(x, P)`` with measurement ``z = H x + v``, ``v ~ N(0, R)``.

    Parameters
    ----------
    x : ndarray (n,)
    P : ndarray (n, n)
    z : ndarray (m,)
    H : ndarray (m, n)
    R : ndarray (m, m)

    Returns
    -------
    x, P : ndarray
        The updated state and its covariance (Joseph form, symmetrised).
    """
    r = z - H @ x
    S = H @ P @ H.T + R
    K = np.linalg.solve(S, H @ P).T
    return x + K @ r, _symmetric(joseph(P, K, H, R))


def _symmetric(P):
    return 0.5 * (P + P.T)
