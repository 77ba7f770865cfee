"""Kalman kernels against textbook numpy formulas."""
import numpy as np

from fuzzynav.filters import kalman


def _spd(rng, n):
    A = rng.normal(size=(n, n))
    return A @ A.T + n * np.eye(n)


def test_propagate_matches_numpy():
    rng = np.random.default_rng(1)
    P, Phi, Q = _spd(rng, 15), rng.normal(size=(15, 15)), _spd(rng, 15)
    Phi[rng.random((15, 15)) < 0.6] = 0.0
    ref = Phi @ P @ Phi.T + Q
    kalman.propagate(P, Phi, Q, np.zeros((15, 15)))
    np.testing.assert_allclose(P, ref, rtol=1e-12)


def test_joseph_update_matches_textbook():
    rng = np.random.default_rng(2)
    n, m, M = 15, 4, 6
    P = _spd(rng, n)
    H = np.zeros((M, n))
    H[:m] = rng.normal(size=(m, n)) * (rng.random((m, n)) < 0.3)
    H[np.arange(m), np.arange(m)] = 1.0
    R = np.r_[rng.uniform(0.5, 2.0, m), np.zeros(M - m)]
    r = rng.normal(size=M)
    Hm = H[:m]
    S = Hm @ P @ Hm.T + np.diag(R[:m])
    K_ref = P @ Hm.T @ np.linalg.inv(S)
    A = np.eye(n) - K_ref @ Hm
    P_ref = A @ P @ A.T + K_ref @ np.diag(R[:m]) @ K_ref.T
    PHt, HPH, L = np.zeros((n, M)), np.zeros((M, M)), np.zeros((M, M))
    kalman.innovation_cov(P, H, m, PHt, HPH)
    Sm = HPH.copy()
    Sm[np.arange(m), np.arange(m)] += R[:m]
    assert kalman.cholesky(Sm, m, L)
    np.testing.assert_allclose(L[:m, :m] @ L[:m, :m].T, S, rtol=1e-12)
    assert np.isclose(kalman.nis(L, m, r, np.zeros(M)), r[:m] @ np.linalg.solve(S, r[:m]))
    K, x = np.zeros((n, M)), np.zeros(n)
    kalman.gain(L, m, PHt, K, np.zeros(M))
    np.testing.assert_allclose(K[:, :m], K_ref, rtol=1e-10)
    kalman.joseph_update(P, H, R, m, r, PHt, K, x, np.zeros((n, n)), np.zeros((n, M)))
    np.testing.assert_allclose(x, K_ref @ r[:m], rtol=1e-10)
    np.testing.assert_allclose(P, P_ref, rtol=1e-9, atol=1e-12)


def test_cholesky_rejects_indefinite_and_checks_flag_bad_covariance():
    S = np.array([[1.0, 2.0], [2.0, 1.0]])
    assert not kalman.cholesky(S, 2, np.zeros((2, 2)))
    P = np.eye(3)
    assert kalman.covariance_ok(P)
    P[0, 1] = P[1, 0] = 1.5
    assert not kalman.covariance_ok(P)
    P = np.eye(3)
    P[2, 2] = -1e-20
    assert not kalman.covariance_ok(P)


def test_scale_predicted_weights_only_the_propagated_part_of_the_seen_states():
    rng = np.random.default_rng(4)
    P, Q = _spd(rng, 4) + 4 * np.eye(4), np.eye(4)
    H = np.zeros((2, 4))
    H[0, 1] = 1.0
    H[1, 2] = -0.5
    D = np.diag([1.0, 1.1, 1.1, 1.0])
    ref = D @ (P - Q) @ D + Q
    all_seen = 1.21 * (P - Q) + Q
    P2 = P.copy()
    kalman.scale_predicted(P, Q, 1.21, H, 2, np.zeros(4))
    np.testing.assert_allclose(P, ref, rtol=1e-14)
    kalman.scale_predicted(P2, Q, 1.21, np.ones((1, 4)), 1, np.zeros(4))
    np.testing.assert_allclose(P2, all_seen, rtol=1e-14)
