"""Exact Gauss-Markov / random-walk discretisation against closed forms (statistical)."""
import numpy as np
import pytest
from scipy import stats

from fuzzynav.sim import gauss_markov as gm

#: two-sided tail probability of each statistical check (false alarm rate per test)
ALPHA = 1e-6


def chi2_ok(sample_var, true_var, dof):
    """Whether a sample variance (known zero mean) is consistent with ``true_var``."""
    lo, hi = stats.chi2.ppf([ALPHA / 2, 1 - ALPHA / 2], dof) / dof
    return lo * true_var <= sample_var <= hi * true_var


def integrated_ou_var(sigma, tau, t):
    """Variance of the integral over ``t`` of a stationary OU process (textbook form)."""
    x = t / tau
    return 2.0 * sigma**2 * tau**2 * (x - 1.0 + np.exp(-x))


@pytest.mark.parametrize("h_over_tau", [1e-5, 1e-2, 0.5, 3.0])
def test_stationary_variance_of_value_and_integral(h_over_tau):
    sigma, tau, n_ch = 2.0, 10.0, 40000
    rng = np.random.default_rng(1)
    coef = gm.gm_coefficients(np.full(3, h_over_tau * tau), sigma, tau)
    b, integral = gm.propagate(coef, sigma * rng.standard_normal(n_ch), rng)
    assert chi2_ok(np.mean(b[-1] ** 2), sigma**2, n_ch)
    assert chi2_ok(np.mean(integral[-1] ** 2), integrated_ou_var(sigma, tau, h_over_tau * tau),
                   n_ch)
    # the integral over several steps checks the cross-covariance of value and integral
    total = integral.sum(axis=0)
    assert chi2_ok(np.mean(total**2), integrated_ou_var(sigma, tau, 3 * h_over_tau * tau), n_ch)


def test_autocorrelation_at_lag_tau_is_1_over_e():
    sigma, tau, h = 1.0, 1.0, 0.01
    lag, n_steps, n_ch = 100, 20000, 200
    rng = np.random.default_rng(2)
    coef = gm.gm_coefficients(np.full(n_steps, h), sigma, tau)
    b, _ = gm.propagate(coef, sigma * rng.standard_normal(n_ch), rng)
    rho = np.sum(b[:-lag] * b[lag:]) / np.sum(b[:-lag] ** 2)
    # Bartlett: var(rho_k) ~ [(1+p^2)(1-p^2k)/(1-p^2) - 2k p^2k] / N for an AR(1) with pole p
    p = np.exp(-h / tau)
    var = ((1 + p**2) * (1 - p ** (2 * lag)) / (1 - p**2) - 2 * lag * p ** (2 * lag)) \
        / (n_steps * n_ch)
    assert abs(rho - np.exp(-1.0)) < 5.0 * np.sqrt(var)


def test_random_walk_value_and_integral_variances():
    k, h, n_steps, n_ch = 0.3, 0.1, 50, 40000
    rng = np.random.default_rng(3)
    b, integral = gm.propagate(gm.rw_coefficients(np.full(n_steps, h), k), np.zeros(n_ch), rng)
    t = n_steps * h
    assert chi2_ok(np.mean(b[-1] ** 2), k**2 * t, n_ch)
    # integrated Brownian motion: var = k^2 t^3 / 3
    assert chi2_ok(np.mean(integral.sum(0) ** 2), k**2 * t**3 / 3.0, n_ch)


def test_small_step_series_matches_closed_form_where_both_are_accurate():
    x = np.array([2e-4, 5e-4, 9.9e-4])
    e = -np.expm1(-x)
    closed = x - e - 0.5 * e * e
    np.testing.assert_allclose(gm._var_integral_shape(x), closed, rtol=1e-6)
    np.testing.assert_allclose(gm._var_integral_shape(np.array([1e-6])), [1e-18 / 3], rtol=1e-5)


def test_series_sampled_on_irregular_times_keeps_stationary_variance():
    rng = np.random.default_rng(4)
    t = np.cumsum(rng.uniform(0.1, 2.0, 60))
    x = gm.gauss_markov_series(t, 1.5, 5.0, rng, m=30000)
    assert x.shape == (60, 30000)
    assert chi2_ok(np.mean(x[-1] ** 2), 1.5**2, 30000)
