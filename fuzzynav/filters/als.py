"""Autocovariance least squares (Odelson, Rajamani & Rawlings 2006): Q and R from innovations.

For a linear system ``x+ = A x + G w``, ``y = C x + v`` (``w ~ N(0, Q)``, ``v ~ N(0, R)``)
run with a fixed, stabilising gain ``L`` (``x^+ = x^- + L (y - C x^-)``, ``x^-+ = A x^+``), the
innovations ``e_k = y_k - C x^-_k`` have autocovariances that are linear in ``(Q, R)``::

    C_0 = C P C^T + R,   C_j = C Ab^j P C^T - C Ab^(j-1) A L R   (j >= 1)
    P = Ab P Ab^T + G Q G^T + A L R L^T A^T,   Ab = A - A L C

Stacking ``C_0 .. C_(N-1)`` and vectorising (column-major) gives
``vec(R_N) = A_Q vec(Q) + A_R vec(R)``.  The estimate solves the semidefinite program

    min || A_Q vec(Q) + A_R vec(R) - vec(R_N_hat) ||^2 + reg (tr Q + tr R)
    s.t. Q >= 0, R >= 0 (positive semidefinite)

with cvxpy (Clarabel, else SCS), ``R_N_hat`` the sample autocovariances of the innovations.
cvxpy is imported only here, on use (it is the ``als`` extra, part of ``dev``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.errors import FuzzynavError

__all__ = ["AlsEstimate", "innovations", "sample_autocov", "als_matrices", "als_estimate",
           "steady_gain"]


@dataclass(frozen=True)
class AlsEstimate:
    """Estimated noise covariances and the solver's report."""

    Q: np.ndarray
    R: np.ndarray
    status: str
    residual: float


def innovations(A, C, L, y, x0=None) -> np.ndarray:
    """Innovations ``e_k = y_k - C x^-_k`` of the fixed-gain filter (``y``: (K, p))."""
    A, C, L = (np.atleast_2d(np.asarray(M, float)) for M in (A, C, L))
    y = np.asarray(y, float).reshape(len(y), -1)
    x = np.zeros(A.shape[0]) if x0 is None else np.asarray(x0, float)
    out = np.empty_like(y)
    for k in range(len(y)):
        e = y[k] - C @ x
        out[k] = e
        x = A @ (x + L @ e)
    return out


def sample_autocov(e, lags: int, skip: int = 0) -> np.ndarray:
    """``[C_0; C_1; ...; C_(lags-1)]`` ((lags p, p)): ``C_j = mean(e_(k+j) e_k^T)``."""
    e = np.asarray(e, float)[skip:]
    n, p = e.shape
    if n <= lags:
        raise FuzzynavError(f"ALS: {n} innovations are too few for {lags} lags")
    return np.vstack([e[j:].T @ e[:n - j] / (n - j) for j in range(lags)])


def als_matrices(A, G, C, L, lags: int) -> tuple:
    """``(A_Q, A_R)``: ``vec(R_N) = A_Q vec(Q) + A_R vec(R)`` (column-major ``vec``)."""
    A, G, C, L = (np.atleast_2d(np.asarray(M, float)) for M in (A, G, C, L))
    n, p = A.shape[0], C.shape[0]
    Ab = A - A @ L @ C
    if np.max(np.abs(np.linalg.eigvals(Ab))) >= 1.0:
        raise FuzzynavError("ALS: the gain L does not stabilise the filter (|eig| >= 1)")
    AL = A @ L
    O = np.vstack([C @ np.linalg.matrix_power(Ab, j) for j in range(lags)])
    Gam = np.vstack([np.eye(p)] + [-C @ np.linalg.matrix_power(Ab, j - 1) @ AL
                                   for j in range(1, lags)])
    lyap = np.linalg.inv(np.eye(n * n) - np.kron(Ab, Ab))
    to_RN = np.kron(C, O) @ lyap  # vec(O P C^T) = (C kron O) vec(P)
    AQ = to_RN @ np.kron(G, G)
    AR = to_RN @ np.kron(AL, AL) + np.kron(np.eye(p), Gam)
    return AQ, AR


def als_estimate(A, G, C, L, e, lags: int = 10, reg: float = 0.0, skip: int = 0,
                 diagonal: bool = False) -> AlsEstimate:
    """Estimate ``Q`` (size of ``G``'s columns) and ``R`` from fixed-gain innovations ``e``.

    Parameters
    ----------
    A, G, C, L : array_like
        System, noise input, output and the filter gain that produced ``e``.
    e : array_like, shape (K, p)
        Innovations of that filter (:func:`innovations`).
    lags : int
        Autocovariance lags used (``C_0 .. C_(lags-1)``).
    reg : float
        Trace regularisation weight (0: plain least squares under the PSD constraints).
    skip : int
        Leading innovations dropped (the filter's transient).
    diagonal : bool
        Estimate diagonal ``Q`` and ``R`` only.
    """
    try:
        import cvxpy as cp
    except ImportError:  # an optional extra: say how to get it, not a traceback
        raise FuzzynavError("the als baseline needs cvxpy: pip install 'fuzzynav[als]'") from None

    G, C = np.atleast_2d(np.asarray(G, float)), np.atleast_2d(np.asarray(C, float))
    e = np.asarray(e, float).reshape(len(e), -1)
    AQ, AR = als_matrices(A, G, C, L, lags)
    b = sample_autocov(e, lags, skip).ravel(order="F")
    g, p = G.shape[1], C.shape[0]
    scale = max(float(np.max(np.abs(b))), 1e-300)  # a well-scaled problem for the solver
    if diagonal:
        q, r = cp.Variable(g, nonneg=True), cp.Variable(p, nonneg=True)
        Q, R = cp.diag(q), cp.diag(r)
    else:
        Q, R = cp.Variable((g, g), PSD=True), cp.Variable((p, p), PSD=True)
    fit = AQ @ cp.vec(Q, order="F") + AR @ cp.vec(R, order="F") - b / scale
    prob = cp.Problem(cp.Minimize(cp.sum_squares(fit) + reg * (cp.trace(Q) + cp.trace(R))))
    _solve(prob, cp)
    if Q.value is None or R.value is None:
        raise FuzzynavError(f"ALS: the semidefinite program failed ({prob.status})")
    Qv, Rv = np.asarray(Q.value) * scale, np.asarray(R.value) * scale
    return AlsEstimate((Qv + Qv.T) / 2, (Rv + Rv.T) / 2, prob.status,
                       float(np.sqrt(max(prob.value, 0.0))) * scale)


def _solve(prob, cp) -> None:
    for solver in ("CLARABEL", "SCS"):
        if solver in cp.installed_solvers():
            try:
                prob.solve(solver=solver)
                return
            except cp.error.SolverError:
                continue
    raise FuzzynavError("ALS: no working conic solver (install clarabel or scs)")


def steady_gain(A, G, C, Q, R) -> np.ndarray:
    """The steady-state Kalman gain (filtered form) for assumed ``Q`` and ``R``."""
    from scipy.linalg import solve_discrete_are

    A, G, C = (np.atleast_2d(np.asarray(M, float)) for M in (A, G, C))
    Q, R = np.atleast_2d(Q), np.atleast_2d(R)
    P = solve_discrete_are(A.T, C.T, G @ Q @ G.T, R)
    return P @ C.T @ np.linalg.inv(C @ P @ C.T + R)
