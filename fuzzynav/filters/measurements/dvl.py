"""Doppler velocity log: body-frame velocity, with scale-factor, misalignment and lever-arm
states.

Data row: ``[v_x, v_y, v_z, sigma x 3]`` in the DVL frame (body RFU up to the misalignment),
m/s; NaN entries or non-positive sigmas are skipped.  Parameters (:func:`pack`): the lever
arm ``l`` (body RFU, m) and the state starts of the blocks ``dvl_scale``,
``dvl_misalignment`` and ``lever_arm`` in the layout (-1 = the block is absent: the value is
taken as 0, or the given lever arm).

Predicted DVL velocity from the INS, with the current estimates ``k``, ``mu``, ``l``::

    u = C_nb v_n + omega_ib_b x l,     v_pred = (1 + k) (I - [mu x]) u = G u

(the earth-rate part of the lever-arm velocity is neglected: < 0.1 mm/s for metres).
Residual ``z = v_pred - v_dvl``.  With ``C_nb_calc = C_nb (I + [phi x])`` and the sensor
states defined as the loop feeds them back (``estimate += x``, so ``x = true - estimate``)::

    H_att = -G C_nb [v_n x],   H_vel = G C_nb,
    H_k = -(I - [mu x]) u,     H_mu = -(1 + k) [u x],     H_l = -G [omega x]

``tests/filters/test_dvl.py`` checks every column against finite differences of this model
through the loop's own feedback.  Channel: ``vel_b``.  For the state-transformation model the
loop maps these phi-model rows (``H A^-1``), so nothing here depends on the error model.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav import units
from fuzzynav.filters.layout import AUX_XS, N_CORE, X_ATT, X_VEL
from fuzzynav.filters.numba_lazy import njit_signature
from fuzzynav.filters.measurements import MEAS_SIG, MeasurementModel, register
from fuzzynav.nav.state_layout import NAV_VEL

__all__ = ["DVL_BLOCKS", "dvl_kernel", "pack", "MODEL"]

#: state blocks this model can use, in the order of their starts in ``par[3:6]``
DVL_BLOCKS = ("dvl_scale", "dvl_misalignment", "lever_arm")


@nb.njit(cache=True, error_model="numpy")
def _state(aux, start, i, default):
    """Component ``i`` of a sensor block's estimate (``default`` when the block is absent)."""
    if start < 0:
        return default
    return aux[AUX_XS + start - N_CORE + i]


@nb.njit(cache=True, error_model="numpy")
def _cross_matrix(a, out):
    """``out = [a x]`` (3 x 3)."""
    out[0, 0], out[0, 1], out[0, 2] = 0.0, -a[2], a[1]
    out[1, 0], out[1, 1], out[1, 2] = a[2], 0.0, -a[0]
    out[2, 0], out[2, 1], out[2, 2] = -a[1], a[0], 0.0


@nb.njit(cache=True, error_model="numpy")
def _rows_core(G, C_bn, vn, i, H, m):
    """Velocity and attitude columns of row ``m`` (axis ``i``): ``G C_nb``, ``-G C_nb [v x]``."""
    gc = np.zeros(3)
    for j in range(3):
        for a in range(3):
            gc[j] += G[i, a] * C_bn[j, a]  # (G C_nb)[i, j] with C_nb = C_bn^T
        H[m, X_VEL + j] = gc[j]
    # gc . (phi x v) = phi . (v x gc)
    H[m, X_ATT] = vn[1] * gc[2] - vn[2] * gc[1]
    H[m, X_ATT + 1] = vn[2] * gc[0] - vn[0] * gc[2]
    H[m, X_ATT + 2] = vn[0] * gc[1] - vn[1] * gc[0]


@nb.njit(cache=True, error_model="numpy")
def _rows_states(G, mu, u, w, k, i, s_k, s_mu, s_l, H, m, X):
    """Columns of the DVL's own states in row ``m`` (axis ``i``)."""
    if s_k >= 0:  # -(I - [mu x]) u
        H[m, s_k] = -G[i, 0] * u[0] / (1.0 + k) - G[i, 1] * u[1] / (1.0 + k) \
            - G[i, 2] * u[2] / (1.0 + k)
    if s_mu >= 0:  # -(1 + k) [u x]
        _cross_matrix(u, X)
        for j in range(3):
            H[m, s_mu + j] = -(1.0 + k) * X[i, j]
    if s_l >= 0:  # -G [w x]
        _cross_matrix(w, X)
        for j in range(3):
            H[m, s_l + j] = -(G[i, 0] * X[0, j] + G[i, 1] * X[1, j] + G[i, 2] * X[2, j])


@njit_signature(MEAS_SIG)
def dvl_kernel(nav, C_bn, aux, row, par, dt_back, z, H, R, chan):
    s_k, s_mu, s_l = int(par[3]), int(par[4]), int(par[5])
    k = _state(aux, s_k, 0, 0.0)
    mu, lev, w, vn, vb, u = (np.empty(3), np.empty(3), np.empty(3), np.empty(3),
                             np.empty(3), np.empty(3))
    for i in range(3):
        mu[i] = _state(aux, s_mu, i, 0.0)
        lev[i] = _state(aux, s_l, i, par[i])
        w[i] = aux[i]
        vn[i] = nav[NAV_VEL + i]
    for i in range(3):
        vb[i] = C_bn[0, i] * vn[0] + C_bn[1, i] * vn[1] + C_bn[2, i] * vn[2]
    for i in range(3):
        j, m2 = (i + 1) % 3, (i + 2) % 3
        u[i] = vb[i] + w[j] * lev[m2] - w[m2] * lev[j]
    G = np.empty((3, 3))
    _cross_matrix(mu, G)
    for i in range(3):
        for j in range(3):
            G[i, j] = (1.0 + k) * ((1.0 if i == j else 0.0) - G[i, j])
    X = np.empty((3, 3))
    m = 0
    for i in range(3):
        pred = G[i, 0] * u[0] + G[i, 1] * u[1] + G[i, 2] * u[2]
        res = pred - row[i]
        sig = row[3 + i]
        if not (math.isfinite(res) and sig > 0.0):
            continue
        z[m] = res
        R[m] = sig * sig
        chan[m] = 0
        _rows_core(G, C_bn, vn, i, H, m)
        _rows_states(G, mu, u, w, k, i, s_k, s_mu, s_l, H, m, X)
        m += 1
    return m


def pack(data, options) -> np.ndarray:
    """Constants of a run: ``[lever arm (3), start of dvl_scale, dvl_misalignment, lever_arm]``.

    ``options``: ``lever_arm_b`` (default the sensor's ``meta["lever_arm_b"]`` or zero) and
    ``state_start`` (block kind -> start in the layout, filled by
    :func:`fuzzynav.filters.sensor_states.with_sensor_states`).
    """
    lever = np.asarray(options.get("lever_arm_b", data.meta.get("lever_arm_b", np.zeros(3))),
                       dtype=float)
    starts = dict(options.get("state_start", {}))
    return np.array([*lever, *[float(starts.get(b, -1)) for b in DVL_BLOCKS]])


def _states(data, options):
    """DVL scale factor and misalignment as random constants (prior sigmas as options)."""
    blocks = [("dvl_scale", math.inf, float(options.get("dvl_scale_sigma", 0.01)), 0.0),
              ("dvl_misalignment", math.inf,
               float(options.get("dvl_misalignment_sigma_deg", 0.5)) * units.DEG, 0.0)]
    if options.get("dvl_lever_arm_sigma_m"):
        blocks.append(("lever_arm", math.inf, float(options["dvl_lever_arm_sigma_m"]), 0.0))
    return blocks


MODEL = register(MeasurementModel(kind="dvl", kernel=dvl_kernel, max_rows=3,
                                  channels=("vel_b",), pack=pack, states=_states))
