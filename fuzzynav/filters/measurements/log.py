"""Electromagnetic log: forward speed through the water (paper 003).

Data row: ``[v_log, sigma]`` [m/s].  The model predicts the reading from the INS with the
filter's own log-error states (each optional, present when the layout has the block)::

    v_hat = (1 + k) c . (v_n - w_n) + b,     c = C_bn[:, 1] (the keel in ENU)

``k`` the scale factor (block ``log_scale``), ``b`` the constant error (``log_bias``) and
``w_n`` the horizontal water current (``water_current``, east and north).  Residual
``z = v_hat - v_log``; with ``C_calc^T = C_true^T (I + [phi x])`` its Jacobian is::

    H_att = (1 + k) (v - w) x c,   H_vel = (1 + k) c,   H_k = -c . (v - w),   H_b = -1,
    H_w = (1 + k) c_{e,n}

The navigation errors are *computed minus true* (subtracted on feedback), but a sensor state
is corrected by *adding* the update (``xs += x``, as the IMU bias blocks), so its error is
*true minus estimate* and its columns carry the opposite sign of d(z)/d(estimate)
(checked against finite differences in ``tests/filters/test_log_model.py``).  Without a
current state the current is an error of the reading, and it is unobservable without a
position fix anyway: a ``water_current`` block only bounds it by its prior.  Channel:
``log``.  The estimates come from ``aux[AUX_XS:]`` (the sensor states); the block starts from
``options["state_start"]``, filled by :func:`fuzzynav.filters.sensor_states.with_sensor_states`.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.filters.layout import AUX_XS, COUPLE_NONE, N_CORE, X_ATT, X_VEL, register_block
from fuzzynav.filters.numba_lazy import njit_signature
from fuzzynav.filters.measurements import MEAS_SIG, MeasurementModel, register
from fuzzynav.nav.state_layout import NAV_VEL

__all__ = ["LOG_STATES", "log_kernel", "MODEL"]

register_block("log_bias", 1, COUPLE_NONE)
register_block("water_current", 2, COUPLE_NONE, axes="en")

#: the log's state blocks and their defaults: (block, tau [s], initial sigma, steady sigma);
#: tau = inf is a random constant (its noise density is then 0)
LOG_STATES = (("log_scale", math.inf, 0.02, 0.0), ("log_bias", math.inf, 1.0, 0.0),
              ("water_current", 1800.0, 0.5, 0.5))


@nb.njit(cache=True, error_model="numpy")
def _state(aux, par, j):
    """Estimate of the log state whose start is ``par[j]`` (0 when the block is absent)."""
    return aux[AUX_XS + int(par[j]) - N_CORE] if par[j] >= 0.0 else 0.0


@njit_signature(MEAS_SIG)
def log_kernel(nav, C_bn, aux, row, par, dt_back, z, H, R, chan):
    sig = row[1]
    if not (sig > 0.0 and math.isfinite(row[0])):
        return 0
    k, b = _state(aux, par, 0), _state(aux, par, 1)
    we, wn = _state(aux, par, 2), 0.0
    if par[2] >= 0.0:
        wn = aux[AUX_XS + int(par[2]) + 1 - N_CORE]
    ve, vn, vu = nav[NAV_VEL] - we, nav[NAV_VEL + 1] - wn, nav[NAV_VEL + 2]
    cx, cy, cz = C_bn[0, 1], C_bn[1, 1], C_bn[2, 1]
    s = cx * ve + cy * vn + cz * vu
    g = 1.0 + k
    z[0] = g * s + b - row[0]
    H[0, X_ATT] = g * (vn * cz - vu * cy)
    H[0, X_ATT + 1] = g * (vu * cx - ve * cz)
    H[0, X_ATT + 2] = g * (ve * cy - vn * cx)
    H[0, X_VEL], H[0, X_VEL + 1], H[0, X_VEL + 2] = g * cx, g * cy, g * cz
    if par[0] >= 0.0:
        H[0, int(par[0])] = -s
    if par[1] >= 0.0:
        H[0, int(par[1])] = -1.0
    if par[2] >= 0.0:
        H[0, int(par[2])], H[0, int(par[2]) + 1] = g * cx, g * cy
    R[0] = sig * sig
    chan[0] = 0
    return 1


def _pack(data, options) -> np.ndarray:
    """``[start of log_scale, of log_bias, of water_current]`` (-1: not in the layout)."""
    starts = options.get("state_start", {})
    return np.array([float(starts.get(nm, -1)) for nm, *_ in LOG_STATES])


def _states(data, options) -> tuple:
    """The state blocks the log asks for: those named by ``options["log_states"]``.

    None by default, as paper 003's 18-state filter: without a position fix each of them
    trades against the forward velocity error (with a 3-mg accelerometer Markov bias the
    INS cannot tell them apart), and on paper003 every one of them drifted to several m/s
    (or a scale of 0.8) and made the run worse, not better.
    """
    wanted = options.get("log_states", ())
    return tuple(s for s in LOG_STATES if s[0] in wanted)


MODEL = register(MeasurementModel(kind="log", kernel=log_kernel, max_rows=1,
                                  channels=("log",), pack=_pack, states=_states))
