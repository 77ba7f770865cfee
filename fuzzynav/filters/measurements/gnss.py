"""GNSS position and velocity, loosely coupled, with a lever arm.

Data row: ``[lat_rad, lon_rad, h_m, vel_e, vel_n, vel_u, sigma x 6, Q, ns]`` (NaN entries
are skipped, so position-only receivers work; ``Q`` the RTKLIB solution quality, 1 fixed ...
6 PPP, and ``ns`` the satellite count come from ``meta["q"]`` / ``meta["ns"]`` of a
recording, NaN for simulated fixes; they feed only adaptation policies).  Parameters: ``lever_arm_b`` [m, body RFU] of the
antenna from the IMU, and switches ``use_position`` / ``use_velocity``.

Residuals (INS minus GNSS, ENU metres and m/s) at the measurement time::

    z_pos = (p_ins - p_gnss) + C_bn l - v dt_back,   H = [ [C_bn l x]  0  I  0 ]
    z_vel = v_ins + C_bn (omega_ib_b x l) - v_gnss,   H = [ 0  I  0  0 ]

(the lever-arm velocity neglects the small earth-rate and attitude-error couplings).
"""
from __future__ import annotations

import math

import numpy as np

from fuzzynav.filters.layout import X_ATT, X_POS, X_VEL
from fuzzynav.filters.numba_lazy import njit_signature
from fuzzynav.filters.measurements import MEAS_SIG, MeasurementModel, default_rows, register
from fuzzynav.nav.earth import radii_nb
from fuzzynav.nav.state_layout import NAV_H, NAV_LAT, NAV_LON, NAV_VEL

__all__ = ["gnss_kernel", "QUALITY", "MODEL"]


@njit_signature(MEAS_SIG)
def gnss_kernel(nav, C_bn, aux, row, par, dt_back, z, H, R, chan):
    lx, ly, lz = par[0], par[1], par[2]
    # antenna offset in ENU and its velocity from the body rotation
    le = C_bn[0, 0] * lx + C_bn[0, 1] * ly + C_bn[0, 2] * lz
    ln = C_bn[1, 0] * lx + C_bn[1, 1] * ly + C_bn[1, 2] * lz
    lu = C_bn[2, 0] * lx + C_bn[2, 1] * ly + C_bn[2, 2] * lz
    wx, wy, wz = aux[0], aux[1], aux[2]
    cx, cy, cz = wy * lz - wz * ly, wz * lx - wx * lz, wx * ly - wy * lx
    lat, h = nav[NAV_LAT], nav[NAV_H]
    rm, rn = radii_nb(lat)
    m = 0
    if par[3] != 0.0:
        de = (nav[NAV_LON] - row[1]) * (rn + h) * math.cos(lat) + le - nav[NAV_VEL] * dt_back
        dn = (lat - row[0]) * (rm + h) + ln - nav[NAV_VEL + 1] * dt_back
        du = (h - row[2]) + lu - nav[NAV_VEL + 2] * dt_back
        res = (de, dn, du)
        for i in range(3):
            if math.isfinite(res[i]) and row[6 + i] > 0.0:
                z[m] = res[i]
                # d(C l) = (C l) x phi  ->  [C l x]
                if i == 0:
                    H[m, X_ATT + 1], H[m, X_ATT + 2] = -lu, ln
                elif i == 1:
                    H[m, X_ATT], H[m, X_ATT + 2] = lu, -le
                else:
                    H[m, X_ATT], H[m, X_ATT + 1] = -ln, le
                H[m, X_POS + i] = 1.0
                R[m] = row[6 + i] * row[6 + i]
                chan[m] = 0
                m += 1
    if par[4] != 0.0:
        for i in range(3):
            lever_v = C_bn[i, 0] * cx + C_bn[i, 1] * cy + C_bn[i, 2] * cz
            res = nav[NAV_VEL + i] + lever_v - row[3 + i]
            if math.isfinite(res) and row[9 + i] > 0.0:
                z[m] = res
                H[m, X_VEL + i] = 1.0
                R[m] = row[9 + i] * row[9 + i]
                chan[m] = 1
                m += 1
    return m


def _pack(data, options) -> np.ndarray:
    lever = np.asarray(options.get("lever_arm_b", data.meta.get("lever_arm_b", np.zeros(3))),
                       dtype=float)
    return np.array([*lever, float(options.get("use_position", True)),
                     float(options.get("use_velocity", True))])


#: receiver-quality columns of a data row, after ``[z x 6, sigma x 6]``
QUALITY = (("fix_type", 12), ("n_sat", 13))


def _rows(data) -> np.ndarray:
    """Default rows plus the receiver's per-epoch quality (NaN where the data have none)."""
    n = data.time_s.size
    extra = [np.broadcast_to(np.asarray(data.meta.get(k, np.nan), float), (n,))
             for k in ("q", "ns")]
    return np.column_stack([default_rows(data), *extra])


MODEL = register(MeasurementModel(kind="gnss", kernel=gnss_kernel, max_rows=6,
                                  channels=("pos", "vel"), pack=_pack, rows=_rows,
                                  quality=QUALITY))
