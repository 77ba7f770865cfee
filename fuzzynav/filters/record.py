"""What the filter loop records at each output: time, navigation state, sensor states and
sigma (a bank of several locals also each local's error state, sigma and share)."""
from __future__ import annotations

import math

import numba as nb

from fuzzynav.filters import error_hook
from fuzzynav.nav.state_layout import NAV_SIZE

__all__ = ["sigma_into", "record_output"]


@nb.njit(cache=True, error_model="numpy")
def sigma_into(row, P, nav, em):
    """``row = sqrt(diag P)`` (the velocity entries of the ST model: those of the velocity
    error itself); ``em`` is the error-model argument of :mod:`fuzzynav.filters.error_hook`."""
    for i in range(P.shape[0]):
        row[i] = math.sqrt(max(P[i, i], 0.0))
    error_hook.sigma_velocity(em, row, P, nav)  # the velocity error's, whatever the state's


@nb.njit(cache=True, error_model="numpy")
def record_output(j, t, nav, xs, st, P_master, beta, out, em):
    """Record output ``j`` into ``out`` (:class:`~fuzzynav.filters.loop.Outputs`);
    ``P_master`` is the master's covariance (see
    :func:`~fuzzynav.filters.bank_fusion.master_covariance`).  A bank of one records only
    the master, its local's outputs are formed from it (the runner's ``_locals``)."""
    out_t, out_nav, out_xs, out_sig, out_xl, out_sigl, out_beta = out
    out_t[j] = t
    for i in range(NAV_SIZE):
        out_nav[j, i] = nav[i]
    for i in range(xs.size):
        out_xs[j, i] = xs[i]
    P3, X = st.P, st.x
    sigma_into(out_sig[j], P_master, nav, em)
    if X.shape[0] == 1:
        return
    for k in range(X.shape[0]):
        out_beta[j, k] = beta[k]
        sigma_into(out_sigl[j, k], P3[k], nav, em)
        for i in range(X.shape[1]):
            out_xl[j, k, i] = X[k, i]
