"""The plain numpy Kalman predict/update against forms derived independently of it."""
import numpy as np

from fuzzynav.filters import reference


def test_scalar_update_by_hand():
    # x ~ N(1, 4), z = 3 with variance 1: K = 4/5, x+ = 1 + 0.8 * 2, P+ = 4 * 1/5
    x, P = reference.update(np.array([1.0]), np.array([[4.0]]), np.array([3.0]),
                            np.array([[1.0]]), np.array([[1.0]]))
    assert np.isclose(x[0], 2.6) and np.isclose(P[0, 0], 0.8)


def test_update_equals_the_information_form():
    """``P+^-1 = P^-1 + H^T R^-1 H`` and ``x+ = P+ (P^-1 x + H^T R^-1 z)``."""
    rng = np.random.default_rng(3)
    n, m = 6, 3
    A = rng.normal(size=(n, n))
    P = A @ A.T + np.eye(n)
    H, x, z = rng.normal(size=(m, n)), rng.normal(size=n), rng.normal(size=m)
    R = np.diag(rng.uniform(0.5, 2.0, m))
    x1, P1 = reference.update(x, P, z, H, R)
    info = np.linalg.inv(P) + H.T @ np.linalg.inv(R) @ H
    np.testing.assert_allclose(P1, np.linalg.inv(info), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(x1, np.linalg.solve(info, np.linalg.solve(P, x)
                                                   + H.T @ np.linalg.solve(R, z)), rtol=1e-10)
    np.testing.assert_array_equal(P1, P1.T)


def test_predict_and_joseph_of_a_suboptimal_gain():
    rng = np.random.default_rng(4)
    P, Phi, Q = np.diag([1.0, 2.0]), np.array([[1.0, 0.5], [0.0, 1.0]]), 0.1 * np.eye(2)
    x, Pp = reference.predict(np.array([1.0, 2.0]), P, Phi, Q)
    np.testing.assert_allclose(x, [2.0, 2.0])
    np.testing.assert_allclose(Pp, [[1.6, 1.0], [1.0, 2.1]])     # by hand
    assert reference.predict(None, P, Phi, Q)[0] is None
    # a gain off the optimum costs covariance: the Joseph form, not (I - K H) P, shows it
    H, R = np.array([[1.0, 0.0]]), np.array([[0.5]])
    K_opt = np.linalg.solve(H @ Pp @ H.T + R, H @ Pp).T
    K_bad = K_opt * (1 + 0.3 * rng.normal(size=K_opt.shape))
    assert np.trace(reference.joseph(Pp, K_bad, H, R)) > np.trace(reference.joseph(Pp, K_opt,
                                                                                H, R))
    np.testing.assert_allclose(reference.joseph(Pp, K_opt, H, R), (np.eye(2) - K_opt @ H) @ Pp,
                               rtol=1e-12)
