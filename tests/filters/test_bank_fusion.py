"""Information fusion through triangular inverses agrees with explicit inverses.

Reference: scipy's Cholesky solves for every column of each scaled ``P_i^-1`` -- the
algorithm the fusion used before the triangular inverse -- and numpy's LU inverses, on
covariances shaped like the filter's (position variances ~1 m^2, bias variances ~1e-10 of
them, correlated).
"""
import numpy as np
import pytest
from scipy.linalg import cho_factor, cho_solve

from fuzzynav.filters.bank_fusion import fuse, fusion_work, spd_inverse

N = 15
#: relative agreement asked of the fusion (issue 9); rounding of these inverses is ~1e-13
RTOL = 1e-9


def _covariances(rng, n_local):
    scale = np.r_[np.full(3, 1e-2), np.full(3, 1e-1), np.full(3, 3.0), np.full(3, 1e-5),
                  np.full(3, 1e-4)]
    out = []
    for _ in range(n_local):
        B = rng.normal(size=(N, N))
        C = B @ B.T / N + 0.2 * np.eye(N)  # well inside the positive-definite cone
        out.append(scale[:, None] * C * scale[None, :])
    return np.array(out), rng.normal(size=(n_local, N)) * scale


def _reference(P, x):
    d = np.sqrt(P[0].diagonal())
    Y, y = np.zeros((N, N)), np.zeros(N)
    for Pi, xi in zip(P, x):
        info = cho_solve(cho_factor(Pi / np.outer(d, d), lower=True), np.eye(N))
        Y += info
        y += info @ (xi / d)
    Pg = np.linalg.inv(Y)
    return np.outer(d, d) * Pg, d * (Pg @ y)


@pytest.mark.parametrize("n_local", [1, 2, 3])
def test_fusion_agrees_with_explicit_inverses(n_local):
    rng = np.random.default_rng(n_local)
    for _ in range(5):
        P, x = _covariances(rng, n_local)
        Pg, xg = np.zeros((N, N)), np.zeros(N)
        assert fuse(P, x, Pg, xg, fusion_work(N))
        Pr, xr = _reference(P, x)
        scale = np.sqrt(np.outer(Pr.diagonal(), Pr.diagonal()))
        np.testing.assert_allclose(Pg / scale, Pr / scale, rtol=0, atol=RTOL)
        np.testing.assert_allclose(xg / np.sqrt(Pr.diagonal()), xr / np.sqrt(Pr.diagonal()),
                                   rtol=0, atol=RTOL)
        assert np.array_equal(Pg, Pg.T)  # exactly symmetric


def test_one_local_fuses_to_itself():
    P, x = _covariances(np.random.default_rng(7), 1)
    Pg, xg = np.zeros((N, N)), np.zeros(N)
    assert fuse(P, x, Pg, xg, fusion_work(N))
    np.testing.assert_allclose(Pg, P[0], rtol=1e-10, atol=1e-10 * np.abs(P[0]).max())
    np.testing.assert_allclose(xg, x[0], rtol=1e-10, atol=1e-10 * np.abs(x[0]).max())


def test_a_covariance_that_is_not_positive_definite_is_refused():
    P, x = _covariances(np.random.default_rng(8), 2)
    P[1, 4, 4] = -1.0
    assert not fuse(P, x, np.zeros((N, N)), np.zeros(N), fusion_work(N))
    A = np.eye(4)
    A[2, 2] = 0.0
    assert not spd_inverse(A, np.zeros((4, 4)), np.zeros((4, 4)), np.zeros((4, 4)))


def test_spd_inverse_is_the_inverse():
    B = np.random.default_rng(9).normal(size=(6, 6))
    A = B @ B.T + np.eye(6)
    out = np.zeros((6, 6))
    assert spd_inverse(A, out, np.zeros((6, 6)), np.zeros((6, 6)))
    np.testing.assert_allclose(out @ A, np.eye(6), atol=1e-12)
    assert np.array_equal(out, out.T)
