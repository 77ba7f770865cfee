"""Non-holonomic constraints: a land vehicle (or a ship, paper 003) does not slide sideways
or lift off, so its body-frame lateral and vertical velocities are zero (plus noise).

Data row: ``[v_x, v_z, sigma_x, sigma_z]`` — the pseudo-measured body velocities (normally
0) and their 1-sigma [m/s], body RFU (x right, z up).  Residual (INS minus constraint)::

    z = (C_bn^T v_n)_{x,z} - v_{x,z},     H = [ -C_nb [v_n x]   C_nb   0 ]  (rows x and z)

from ``C_calc^T = C_true^T (I + [phi x])``.  Channel: ``constraint``.  The IMU is taken to
be at the vehicle's non-slipping point; lever arms to the rear axle are neglected.
"""
from __future__ import annotations

import math

import numpy as np

from fuzzynav.filters.layout import X_ATT, X_VEL
from fuzzynav.filters.numba_lazy import njit_signature
from fuzzynav.filters.measurements import MEAS_SIG, MeasurementModel, register
from fuzzynav.nav.state_layout import NAV_VEL

__all__ = ["nhc_kernel", "MODEL"]


@njit_signature(MEAS_SIG)
def nhc_kernel(nav, C_bn, aux, row, par, dt_back, z, H, R, chan):
    ve, vn, vu = nav[NAV_VEL], nav[NAV_VEL + 1], nav[NAV_VEL + 2]
    m = 0
    for k, axis in ((0, 0), (1, 2)):
        sig = row[2 + k]
        if not (sig > 0.0 and math.isfinite(row[k])):
            continue
        cx, cy, cz = C_bn[0, axis], C_bn[1, axis], C_bn[2, axis]  # row of C_nb
        z[m] = cx * ve + cy * vn + cz * vu - row[k]
        # c . (phi x v) = phi . (v x c)
        H[m, X_ATT] = vn * cz - vu * cy
        H[m, X_ATT + 1] = vu * cx - ve * cz
        H[m, X_ATT + 2] = ve * cy - vn * cx
        H[m, X_VEL], H[m, X_VEL + 1], H[m, X_VEL + 2] = cx, cy, cz
        R[m] = sig * sig
        chan[m] = 0
        m += 1
    return m


def _pack(data, options) -> np.ndarray:
    return np.zeros(1)


MODEL = register(MeasurementModel(kind="nhc", kernel=nhc_kernel, max_rows=2,
                                  channels=("constraint",), pack=_pack))
