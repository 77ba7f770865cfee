"""Magnetometer: heading residual (paper 001) or the 3-axis field against the INS attitude.

Data row (:mod:`fuzzynav.sim.sensors.magnetometer`): ``[heading, m_x, m_y, m_z, sigma_h,
sigma_m x 3]``.  Parameters: ``[mode, B_e, B_n, B_u, b_x, b_y, b_z]`` — the reference field
(ENU, tesla; from the sensor's ``meta["field_n_t"]`` or the option ``field_n_t``) and a known
hard-iron calibration (body, tesla; option ``hard_iron_t``) removed from the vector form.

Modes (option ``mode``)
-----------------------
``heading`` (default, the paper's local filter 3): ``z = heading_ins - heading_mag`` with
the exact row of the heading ``atan2(C_bn[0, 1], C_bn[1, 1])`` in the attitude error,
``d heading / d phi = [-C21 C01 / c^2, -C21 C11 / c^2, 1]`` (``c`` = cos pitch; for a level
vehicle ``[0, 0, 1]``, the paper's ``delta phi`` after linearising
``tan(phi + dphi) ~ tan phi + (1 + tan^2 phi) dphi``).  ``R = sigma_h^2``.

``vector``: ``z = C_nb_ins B_n - (m - b)``, three rows ``H_att = -C_nb [B_n x]`` (from
``C_bn_ins = (I - [phi x]) C_bn``); it senses tilt as well as heading and is disturbed by
anything that changes the field's magnitude.  The hard-iron offset enters as a known
calibration only: a ``mag_bias`` state needs the loop to hand measurement models the
current sensor-state estimate, which :data:`~fuzzynav.filters.measurements.MEAS_SIG` does
not carry yet.

Channels: ``heading``, ``field``.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.errors import FuzzynavError, UnknownNameError
from fuzzynav.filters.layout import X_ATT
from fuzzynav.filters.numba_lazy import njit_signature
from fuzzynav.filters.measurements import MEAS_SIG, MeasurementModel, register
from fuzzynav.filters.measurements.polarization import euler_jacobian

__all__ = ["MODES", "magnetometer_kernel", "MODEL"]

MODES = {"heading": 0, "vector": 1}
CH_HEADING, CH_FIELD = 0, 1


@nb.njit(cache=True, error_model="numpy")
def _heading_row(C, row, z, H, R, chan):
    if not (math.isfinite(row[0]) and row[4] > 0.0):
        return 0
    J = np.empty((3, 3))
    euler_jacobian(C, J)
    heading = math.atan2(C[0, 1], C[1, 1])
    z[0] = (heading - row[0] + math.pi) % (2.0 * math.pi) - math.pi
    for j in range(3):
        H[0, X_ATT + j] = J[2, j]
    R[0] = row[4] * row[4]
    chan[0] = CH_HEADING
    return 1


@nb.njit(cache=True, error_model="numpy")
def _vector_rows(C, row, par, z, H, R, chan):
    b = par[1:4]
    m = 0
    for i in range(3):
        if not (math.isfinite(row[1 + i]) and row[5 + i] > 0.0):
            continue
        pred = C[0, i] * b[0] + C[1, i] * b[1] + C[2, i] * b[2]  # (C_nb B)_i
        z[m] = pred - (row[1 + i] - par[4 + i])
        # row i of -C_nb [B x]: -(sum_k C[k, i] [B x]_{k, j})
        H[m, X_ATT + 0] = -(C[1, i] * b[2] - C[2, i] * b[1])
        H[m, X_ATT + 1] = -(C[2, i] * b[0] - C[0, i] * b[2])
        H[m, X_ATT + 2] = -(C[0, i] * b[1] - C[1, i] * b[0])
        R[m] = row[5 + i] * row[5 + i]
        chan[m] = CH_FIELD
        m += 1
    return m


@njit_signature(MEAS_SIG)
def magnetometer_kernel(nav, C_bn, aux, row, par, dt_back, z, H, R, chan):
    if int(par[0]) == 1:
        return _vector_rows(C_bn, row, par, z, H, R, chan)
    return _heading_row(C_bn, row, z, H, R, chan)


def _pack(data, options) -> np.ndarray:
    mode = options.get("mode", "heading")
    if mode not in MODES:
        raise UnknownNameError("magnetometer measurement mode", mode, MODES)
    field = np.asarray(options.get("field_n_t", data.meta.get("field_n_t", np.full(3, np.nan))),
                       float).reshape(3)
    if mode == "vector" and not np.all(np.isfinite(field)):
        raise FuzzynavError("magnetometer mode 'vector' needs the reference field: "
                            "meta['field_n_t'] of the sensor or the option field_n_t")
    hard = np.asarray(options.get("hard_iron_t", np.zeros(3)), float).reshape(3)
    return np.concatenate([[MODES[mode]], field, hard])


MODEL = register(MeasurementModel(kind="magnetometer", kernel=magnetometer_kernel,
                                  max_rows=3, channels=("heading", "field"), pack=_pack))
