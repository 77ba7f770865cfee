"""Autocovariance least squares recovers the noise of a simulated linear system."""
import numpy as np
import pytest

pytest.importorskip("cvxpy")

from fuzzynav.errors import FuzzynavError  # noqa: E402
from fuzzynav.filters.als import als_estimate, innovations, steady_gain  # noqa: E402

# a constant-velocity model: position measured, white acceleration
A = np.array([[1.0, 1.0], [0.0, 1.0]])
G = np.array([[0.5], [1.0]])
C = np.array([[1.0, 0.0]])


def _simulate(q, r, n, seed):
    rng = np.random.default_rng(seed)
    w = rng.normal(0.0, np.sqrt(q), n)
    v = rng.normal(0.0, np.sqrt(r), n)
    x, y = np.zeros(2), np.empty((n, 1))
    for k in range(n):
        y[k] = C @ x + v[k]
        x = A @ x + G[:, 0] * w[k]
    return y


def test_als_recovers_known_q_and_r():
    # Truth Q = 0.1, R = 2; the filter's gain is designed for Q = R = 1 (wrong on purpose).
    # Over 20 seeds of 20000 samples (15 lags) the estimates spread with a standard
    # deviation of about 7 % (Q) and 1 % (R) around the truth; the tolerances are 4 sigma.
    L = steady_gain(A, G, C, 1.0, 1.0)
    e = innovations(A, C, L, _simulate(0.1, 2.0, 20000, seed=7))
    est = als_estimate(A, G, C, L, e, lags=15, skip=100)
    assert est.Q[0, 0] == pytest.approx(0.1, rel=0.28)
    assert est.R[0, 0] == pytest.approx(2.0, rel=0.04)


def test_als_keeps_q_positive_semidefinite_when_there_is_none():
    # No process noise: unconstrained least squares may go negative; the SDP may not.
    L = steady_gain(A, G, C, 1.0, 1.0)
    e = innovations(A, C, L, _simulate(0.0, 1.0, 5000, seed=3))
    est = als_estimate(A, G, C, L, e, lags=10, skip=50, reg=1e-6)
    # (spread of the Q estimate at 5000 samples: about 0.014; bound about 3.5 sigma)
    assert est.Q[0, 0] >= -1e-9 and est.Q[0, 0] < 0.05
    assert est.R[0, 0] == pytest.approx(1.0, rel=0.1)


def test_als_refuses_an_unstable_gain():
    with pytest.raises(FuzzynavError, match="stabilise"):
        als_estimate(A, G, C, np.zeros((2, 1)), np.zeros((100, 1)))
