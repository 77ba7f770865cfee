"""Kalman kernels against textbook numpy formulas."""
import numpy as np

from fuzzynav.filters import kalman, reference


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
    P_ref = reference.joseph(P, K_ref, Hm, np.diag(R[:m]))
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


def test_propagate_with_a_diagonal_tail_matches_numpy():
    """Rows of Phi that only scale their state (sensor-error blocks) take a shortcut."""
    rng = np.random.default_rng(6)
    n = 18
    P, Q = _spd(rng, n), _spd(rng, n)
    Phi = rng.normal(size=(n, n))
    Phi[12:] = 0.0
    Phi[np.arange(12, n), np.arange(12, n)] = rng.uniform(0.9, 1.0, n - 12)
    Phi[14, 14] = 0.0  # a zero on the tail's diagonal is still a (trivial) scaling
    ref = Phi @ P @ Phi.T + Q
    assert kalman.diagonal_tail(Phi) == 12
    kalman.propagate(P, Phi, Q, np.zeros((n, n)))
    np.testing.assert_allclose(P, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())
    np.testing.assert_array_equal(P, P.T)


def test_joseph_update_is_the_joseph_form_for_any_gain():
    """The expanded Joseph form equals (I-KH)P(I-KH)^T + KRK^T for a gain that is not the
    optimal one too (that is what makes the form robust to gain errors)."""
    rng = np.random.default_rng(7)
    n, m, M = 15, 3, 5
    P = _spd(rng, n)
    H = np.zeros((M, n))
    H[0, 6], H[1, 7], H[2, :3] = 1.0, 1.0, rng.normal(size=3)
    R = np.r_[rng.uniform(0.5, 2.0, m), np.zeros(M - m)]
    K = np.zeros((n, M))
    K[:, :m] = rng.normal(size=(n, m))
    Hm = H[:m]
    P_ref = reference.joseph(P, K[:, :m], Hm, np.diag(R[:m]))
    PHt, HPH = np.zeros((n, M)), np.zeros((M, M))
    kalman.innovation_cov(P, H, m, PHt, HPH)
    np.testing.assert_allclose(HPH[:m, :m], Hm @ P @ Hm.T, rtol=1e-13)
    r, x = rng.normal(size=M), np.zeros(n)
    kalman.joseph_update(P, H, R, m, r, PHt, K, x, np.zeros((n, n)), np.zeros((n, M)))
    np.testing.assert_allclose(x, K[:, :m] @ r[:m], rtol=1e-12)
    np.testing.assert_allclose(P, P_ref, rtol=1e-10, atol=1e-10 * np.abs(P_ref).max())
    np.testing.assert_array_equal(P, P.T)
