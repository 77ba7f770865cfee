"""The copy of each covariance kernel compiled with the 15-state sizes as constants against
the copy with run-time sizes, and both against numpy.

The two copies run the same sums in the same order, so they must agree to rounding
(stated: 1e-14 relative to the largest entry; in practice identical); numpy's products sum
in another order (1e-12).
"""
import numba as nb
import numpy as np
import pytest

from fuzzynav.filters import kalman, reference, sized
from fuzzynav.filters.error_model import discretize, discretize_tail

N, D = sized.FIXED_N, sized.FIXED_D


@nb.njit
def _propagate_runtime(P, Phi, Qd, work, n, d):
    sized.propagate_sized(P, Phi, Qd, work, n, d)


@nb.njit
def _discretize_runtime(F, q, dt, Phi, Qd, work, n, d):
    sized.discretize_sized(F, q, dt, Phi, Qd, work, n, d)


@nb.njit
def _joseph_runtime(P, H, R, m, r, PHt, K, x, AP, APHt, n):
    sized.innovation_sized(P, H, m, PHt, AP, n)
    sized.joseph_sized(P, H, R, m, r, PHt, K, x, AP, APHt, n)


def _close(a, b, rel):
    np.testing.assert_allclose(a, b, rtol=0, atol=rel * np.abs(b).max())


def _system(rng):
    """A 15-state system matrix with the phi model's shape: dense navigation rows, the
    sensor-error rows diagonal (Gauss-Markov decay)."""
    F = rng.normal(size=(N, N)) * 0.1
    F[D:] = 0.0
    F[D:, D:] = np.diag(-rng.uniform(0.0, 0.01, N - D))
    return F


def test_fixed_sizes_are_chosen_only_for_the_15_state_shape():
    assert sized.fixed(15, 9)
    assert not sized.fixed(15, 10) and not sized.fixed(16, 9) and not sized.fixed(18, 9)
    assert sized.fixed_count(15) and not sized.fixed_count(18)


def test_propagation_copies_agree_and_match_numpy():
    rng = np.random.default_rng(7)
    A = rng.normal(size=(N, N))
    P0, Qd = A @ A.T, np.diag(rng.uniform(0, 1e-3, N))
    Phi = np.eye(N) + 0.2 * _system(rng)
    assert kalman.diagonal_tail(Phi) == D
    fixed, runtime = P0.copy(), P0.copy()
    kalman.propagate(fixed, Phi, Qd, np.zeros((N, N)))
    _propagate_runtime(runtime, Phi, Qd, np.zeros((N, N)), N, D)
    _close(fixed, runtime, 1e-14)
    _close(fixed, Phi @ P0 @ Phi.T + Qd, 1e-12)


def test_discretization_copies_agree_and_match_the_series():
    rng = np.random.default_rng(8)
    F, q, dt = _system(rng), rng.uniform(0, 1e-4, N), 0.2
    out = {k: (np.zeros((N, N)), np.zeros((N, N))) for k in ("fixed", "runtime")}
    discretize(F, q, dt, *out["fixed"], np.zeros((N, N)))
    _discretize_runtime(F, q, dt, *out["runtime"], np.zeros((N, N)), N, D)
    for a, b in zip(out["fixed"], out["runtime"]):
        _close(a, b, 1e-14)
    Q = np.diag(q)
    Phi = np.eye(N) + F * dt + F @ F * dt**2 / 2
    Qd = Q * dt + (F @ Q + Q @ F.T) * dt**2 / 2 + F @ Q @ F.T * dt**3 / 3
    _close(out["fixed"][0], Phi, 1e-12)
    _close(out["fixed"][1], Qd, 1e-12)


def test_a_tail_given_by_the_caller_is_the_scanned_one_or_dense():
    """The loop passes F's diagonal tail to discretize_tail and propagate_tail: the same
    kernels as the scanning entry points (identical), and a tail past the true one (rows
    treated as dense) agrees to rounding."""
    rng = np.random.default_rng(9)
    F, q, dt = _system(rng), rng.uniform(0, 1e-4, N), 0.2
    A = rng.normal(size=(N, N))
    P0 = A @ A.T
    res = {}
    for d in (None, D, N):
        Phi, Qd, work, P = np.zeros((N, N)), np.zeros((N, N)), np.zeros((N, N)), P0.copy()
        if d is None:
            discretize(F, q, dt, Phi, Qd, work)
            kalman.propagate(P, Phi, Qd, work)
        else:
            discretize_tail(F, q, dt, Phi, Qd, work, d)
            kalman.propagate_tail(P, Phi, Qd, work, d)
        res[d] = (Phi, Qd, P)
    for a, b in zip(res[None], res[D]):
        np.testing.assert_array_equal(a, b)  # same kernel, same tail: the same path
    for a, b in zip(res[None], res[N]):
        _close(a, b, 1e-14)


@pytest.mark.parametrize("m", [1, 2, 6])
def test_update_copies_agree_and_match_the_joseph_form(m):
    rng = np.random.default_rng(m)
    A = rng.normal(size=(N, N))
    P0 = A @ A.T + np.eye(N)
    H = np.zeros((6, N))
    H[:m, :9] = rng.normal(size=(m, 9)) * (rng.random((m, 9)) < 0.5)
    R, r = rng.uniform(0.5, 2.0, 6), rng.normal(size=6)
    K = P0 @ H[:m].T @ np.linalg.inv(H[:m] @ P0 @ H[:m].T + np.diag(R[:m]))
    Kp = np.zeros((N, 6))
    Kp[:, :m] = K * (1 + 1e-3 * rng.normal(size=K.shape))  # a gain with an error
    res = {}
    for name in ("fixed", "runtime"):
        P, PHt, HPH, x = P0.copy(), np.zeros((N, 6)), np.zeros((6, 6)), np.zeros(N)
        if name == "fixed":
            kalman.innovation_cov(P, H, m, PHt, HPH)
            kalman.joseph_update(P, H, R, m, r, PHt, Kp, x, np.zeros((N, N)), np.zeros((N, 6)))
        else:
            _joseph_runtime(P, H, R, m, r, PHt, Kp, x, np.zeros((N, N)), np.zeros((N, 6)), N)
        res[name] = (P, x)
    _close(res["fixed"][0], res["runtime"][0], 1e-14)
    _close(res["fixed"][1], res["runtime"][1], 1e-14)
    Hm, Km = H[:m], Kp[:, :m]
    _close(res["fixed"][0], reference.joseph(P0, Km, Hm, np.diag(R[:m])), 1e-12)
    _close(res["fixed"][1], Km @ r[:m], 1e-12)


@nb.njit
def _correct_runtime(L, P, H, R, m, r, PHt, K, x, AP, APHt, work, n):
    sized.gain_sized(L, m, PHt, K, work, n)
    sized.joseph_sized(P, H, R, m, r, PHt, K, x, AP, APHt, n)


@pytest.mark.parametrize("m", [1, 2, 3, 4, 6, 8])
def test_the_loops_update_copies_agree_and_give_the_optimal_update(m):
    """``kalman.correct`` has copies with ``m`` a constant (2, 3, 6) besides the 15-state
    one: each against the copy with run-time sizes, and against the textbook update."""
    rng = np.random.default_rng(10 + m)
    A = rng.normal(size=(N, N))
    P0 = A @ A.T + np.eye(N)
    H = np.zeros((8, N))
    H[:m, :9] = rng.normal(size=(m, 9)) * (rng.random((m, 9)) < 0.6)
    H[np.arange(m), np.arange(m)] = 1.0  # every row sees some state
    R, r = rng.uniform(0.5, 2.0, 8), rng.normal(size=8)
    res = {}
    for name in ("constant", "runtime"):
        P, PHt, HPH, x, K = P0.copy(), np.zeros((N, 8)), np.zeros((8, 8)), np.zeros(N), \
            np.zeros((N, 8))
        kalman.innovation_cov(P, H, m, PHt, HPH)
        L = np.zeros((8, 8))
        assert kalman.cholesky(HPH + np.diag(R), m, L)
        args = (L, P, H, R, m, r, PHt, K, x, np.zeros((N, N)), np.zeros((N, 8)), np.zeros(N))
        kalman.correct(*args) if name == "constant" else _correct_runtime(*args, N)
        res[name] = (P, x)
    for a, b in zip(res["constant"], res["runtime"]):
        _close(a, b, 1e-14)
    Hm = H[:m]
    K = P0 @ Hm.T @ np.linalg.inv(Hm @ P0 @ Hm.T + np.diag(R[:m]))
    _close(res["constant"][0], (np.eye(N) - K @ Hm) @ P0, 1e-12)
    _close(res["constant"][1], K @ r[:m], 1e-12)
