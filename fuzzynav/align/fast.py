"""Paper 002's fast azimuth estimate from the rate of the level misalignment.

With ``d(phi_E)/dt = w_U phi_N - w_N phi_U - eps_E`` (:mod:`.model`), once the level
estimates track the level misalignment (the level loops settle in tens of seconds) the
azimuth follows from the *observed* east rate:
``phi_U = (w_U phi_N - d(phi_E)/dt) / w_N`` (eq. 28), biased by ``-eps_E / w_N`` as the
filter's own estimate is.

Which history.  Not the 10-state filter's own ``phi_E``: that filter predicts the east
rate from its *own* azimuth estimate, so while it is still learning the azimuth its level
estimate follows its belief, not the truth (measured on noise-free data: the slope of its
``phi_E`` gives azimuth errors of 20-30 arcmin at 50 s, or degrees with a sliding window
later on).  The history comes from a separate **level filter** (:func:`level_history`):
velocity and level misalignment only, no azimuth, the level angles a random walk fast
enough (``level_noise_factor`` times the largest east rate ``w_N sigma_phi``) to follow the
true ramp with a constant lag, so that the slope of its estimate is the true rate.

How the rate is estimated (robustly): not by differencing two samples (the estimate's
noise would be divided by one period) but as the slope of the least-squares line through
``phi_E`` over ``[settle_s, settle_s + window_s]``; ``phi_N`` is the line's value at the
window's end, likewise.  Its sigma is the slope's standard error from the fit residuals over
``w_N``, combined with ``sigma_floor_rad`` (the spread of ``eps_E / w_N`` the method cannot
see).  One estimate is made, right after the window, carried forward (the azimuth
misalignment hardly moves on a base at rest) and used while the alignment filter's own
azimuth sigma is larger than the fast estimate's; after that the filter's estimate is used.
With velocity noise the residuals make the fast sigma large and the filter is kept.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from fuzzynav.align.fine import run_fine
from fuzzynav.align.alignment_states import EAST, NORTH, UP, AlignLayout
from fuzzynav.nav import earth

__all__ = ["LAYOUT_LEVEL", "level_history", "fast_azimuth"]

#: the level filter: horizontal velocity errors and level misalignment
LAYOUT_LEVEL = AlignLayout((("vel", 2), ("att", 2)))


def level_history(epochs, noise, level_noise_factor=300.0):
    """Level misalignment estimates ``(K+1, 3)`` (azimuth column zero) of the level filter.

    Parameters
    ----------
    epochs : Epochs
    noise : AlignNoise
        The alignment filter's noise; the level angles' random walk is replaced by
        ``level_noise_factor * w_N * att_sigma_rad`` per sqrt(s).
    """
    w_n = earth.omega_ie_n(epochs.lat_rad)[NORTH]
    nz = dataclasses.replace(noise, gyro_noise_rps_psqrts=level_noise_factor * w_n
                             * noise.att_sigma_rad)
    res = run_fine(epochs, LAYOUT_LEVEL, nz)
    out = np.zeros((res.time_s.size, 3))
    out[:, EAST:UP] = res.estimate("att")
    return out


def _line(t, y):
    """Slope, value at ``t[-1]`` and the slope's standard error of the LS line."""
    tc = t - t[-1]
    A = np.column_stack([tc, np.ones_like(tc)])
    (slope, end), *_ = np.linalg.lstsq(A, y, rcond=None)
    res = y - A @ np.array([slope, end])
    dof = max(t.size - 2, 1)
    se = np.sqrt(np.sum(res**2) / dof / np.sum((tc - tc.mean()) ** 2))
    return slope, end, se


def fast_azimuth(time_s, phi_hat, level, sigma_u, lat_rad, settle_s=30.0, window_s=20.0,
                 sigma_floor_rad=0.0):
    """Azimuth misalignment [rad] and its sigma at every epoch with the fast estimate.

    Parameters
    ----------
    time_s : ndarray (K+1,)
    phi_hat : ndarray (K+1, 3)
        The alignment filter's misalignment estimates (ENU) [rad].
    level : ndarray (K+1, 3)
        Level estimates whose slope is the true rate (:func:`level_history`).
    sigma_u : ndarray (K+1,)
        The filter's azimuth sigma [rad].
    lat_rad : float
    settle_s, window_s : float
        When the level loops are taken as settled; the fit window [s].
    sigma_floor_rad : float
        Least sigma of the fast estimate (e.g. the gyro bias prior over ``w_N``).

    Returns
    -------
    phi_u, sigma : ndarray (K+1,)
        The fast estimate where it is the better one, else the filter's.
    """
    w = earth.omega_ie_n(lat_rad)
    phi_u = np.array(phi_hat[:, UP], dtype=float)
    sigma = np.array(sigma_u, dtype=float)
    sel = (time_s >= settle_s) & (time_s <= settle_s + window_s)
    if np.count_nonzero(sel) < 3:
        return phi_u, sigma
    rate, _, se = _line(time_s[sel], level[sel, EAST])
    _, phi_n, _ = _line(time_s[sel], level[sel, NORTH])
    fast = (w[UP] * phi_n - rate) / w[NORTH]
    s_fast = np.hypot(se / w[NORTH], sigma_floor_rad)
    use = (time_s >= time_s[sel][-1]) & (sigma > s_fast)
    phi_u[use] = fast
    sigma[use] = s_fast
    return phi_u, sigma
