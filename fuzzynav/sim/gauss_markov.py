"""Exact discretisation of first-order Gauss-Markov processes and random walks.

A first-order Gauss-Markov (Ornstein-Uhlenbeck) process with stationary standard
deviation ``sigma`` and correlation time ``tau``,

    db = -b / tau dt + q dW,   q^2 = 2 sigma^2 / tau,

sampled at ``t_k`` with steps ``h_k`` has, given ``b_k``, a jointly Gaussian next value
``b_k+1`` and interval integral ``I_k = int_{t_k}^{t_k+1} b dt`` (what an IMU increment
collects).  With ``x = h / tau`` and ``e = 1 - exp(-x)``:

    E[b_k+1] = (1 - e) b_k,                  E[I_k] = tau e b_k,
    var(b_k+1) = sigma^2 e (2 - e),
    cov(b_k+1, I_k) = sigma^2 tau e^2,
    var(I_k) = 2 sigma^2 tau^2 (x - e - e^2 / 2).

A random walk ``db = K dW`` (rate random walk) is the limit ``tau -> inf``:
``var(b_k+1) = K^2 h``, ``cov = K^2 h^2 / 2``, ``var(I_k) = K^2 h^3 / 3``.

These are exact for any step, so no discretisation error enters the simulated sensors.
"""
from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["gm_coefficients", "rw_coefficients", "propagate", "gauss_markov_series"]

#: below this x = h / tau the closed form of var(I) loses digits; its series is used
_SERIES_X = 1e-3


def _var_integral_shape(x):
    """``x - e - e^2/2`` with ``e = 1 - exp(-x)``, accurate for small x (~ x^3 / 3)."""
    x = np.asarray(x, dtype=float)
    e = -np.expm1(-x)
    closed = x - e - 0.5 * e * e
    series = x**3 / 3.0 - x**4 / 4.0 + 7.0 * x**5 / 60.0
    return np.where(x < _SERIES_X, series, closed)


def gm_coefficients(h_s, sigma, tau_s):
    """Transition coefficients of a Gauss-Markov process over steps ``h_s``.

    Parameters
    ----------
    h_s : array_like, shape (N,)
        Step lengths [s].
    sigma : float
        Stationary standard deviation [unit].
    tau_s : float
        Correlation time [s]; ``numpy.inf`` is not allowed here (use
        :func:`rw_coefficients`).

    Returns
    -------
    ndarray, shape (N, 5)
        Per step ``[phi, c_int, l11, l21, l22]``: ``b_next = phi b + l11 w1`` and
        ``I = c_int b + l21 w1 + l22 w2`` with ``w1, w2`` independent standard normals.
    """
    h = np.asarray(h_s, dtype=float)
    x = h / tau_s
    e = -np.expm1(-x)
    var_b = sigma**2 * e * (2.0 - e)
    cov = sigma**2 * tau_s * e * e
    var_i = 2.0 * sigma**2 * tau_s**2 * _var_integral_shape(x)
    return _pack(1.0 - e, tau_s * e, var_b, cov, var_i)


def rw_coefficients(h_s, k):
    """Transition coefficients of a random walk ``db = k dW`` (same layout as GM)."""
    h = np.asarray(h_s, dtype=float)
    return _pack(np.ones_like(h), h, k**2 * h, 0.5 * k**2 * h**2, k**2 * h**3 / 3.0)


def _pack(phi, c_int, var_b, cov, var_i):
    """Cholesky factor of the 2x2 step covariance, packed with the mean coefficients."""
    l11 = np.sqrt(var_b)
    l21 = np.divide(cov, l11, out=np.zeros_like(cov), where=l11 > 0.0)
    l22 = np.sqrt(np.maximum(var_i - l21**2, 0.0))
    return np.stack([phi, c_int, l11, l21, l22], -1)


@nb.njit(cache=True)
def _propagate(coef, b0, w):
    n, m = w.shape[0], w.shape[2]
    b = np.empty((n + 1, m))
    integral = np.empty((n, m))
    for j in range(m):  # element by element: a row assignment compiles numba's shape-error
        b[0, j] = b0[j]  # message formatting, seconds on a cold cache
    for k in range(n):
        phi, c_int, l11, l21, l22 = coef[k, 0], coef[k, 1], coef[k, 2], coef[k, 3], coef[k, 4]
        for j in range(m):
            w1, w2 = w[k, 0, j], w[k, 1, j]
            integral[k, j] = c_int * b[k, j] + l21 * w1 + l22 * w2
            b[k + 1, j] = phi * b[k, j] + l11 * w1
    return b, integral


def propagate(coef, b0, rng):
    """Sample a process and its interval integrals.

    Parameters
    ----------
    coef : ndarray, shape (N, 5)
        From :func:`gm_coefficients` or :func:`rw_coefficients`.
    b0 : ndarray, shape (m,)
        Initial values of ``m`` independent channels.
    rng : numpy.random.Generator

    Returns
    -------
    b : ndarray, shape (N+1, m)
        Values at the sample times.
    integral : ndarray, shape (N, m)
        Integrals over each step [unit * s].
    """
    b0 = np.atleast_1d(np.asarray(b0, dtype=float))
    w = rng.standard_normal((coef.shape[0], 2, b0.size))
    return _propagate(np.ascontiguousarray(coef, dtype=float), b0, w)


def gauss_markov_series(time_s, sigma, tau_s, rng, m=1):
    """Samples of ``m`` independent stationary GM channels at ``time_s`` (N,) -> (N, m)."""
    time_s = np.asarray(time_s, dtype=float)
    if sigma == 0.0 or time_s.size == 0:
        return np.zeros((time_s.size, m))
    g0, g1 = rng.spawn(2)
    b0 = sigma * g0.standard_normal(m)
    b, _ = propagate(gm_coefficients(np.diff(time_s), sigma, tau_s), b0, g1)
    return b
