"""Layout of the navigation-state vector ``nav`` and of the strapdown work array ``prev``.

The one place these offsets are defined: numba kernels import the integer constants (frozen
into the compiled code), Python code the slices.

``nav`` (float64[:data:`NAV_SIZE`])::

    NAV_Q    4  attitude quaternion of C_bn (w, x, y, z)
    NAV_VEL  3  ENU velocity [m/s]
    NAV_LLA  3  latitude [rad], longitude [rad], height [m]  (NAV_LAT, NAV_LON, NAV_H)

``prev`` (float64[:data:`PREV_SIZE`]), the previous strapdown step::

    PREV_DTH 3  angle increment [rad]       PREV_DV  3  velocity increment [m/s]
    PREV_VEL 3  velocity [m/s]              PREV_LLA 3  latitude, longitude, height
    PREV_FLAG   0 before the first step, 1 after
    PREV_TRIG 4 midpoint latitude of the last step [rad], its sine and cosine, and the
                steps since they were last evaluated exactly (strapdown.sin_cos_lat)
"""
from __future__ import annotations

__all__ = ["NAV_Q", "NAV_VEL", "NAV_LAT", "NAV_LON", "NAV_H", "NAV_SIZE", "Q_SLICE",
           "VEL_SLICE", "LLA_SLICE", "PREV_DTH", "PREV_DV", "PREV_VEL", "PREV_LLA",
           "PREV_FLAG", "PREV_TRIG", "PREV_SIZE"]

NAV_Q = 0
NAV_VEL = NAV_Q + 4
NAV_LAT = NAV_VEL + 3
NAV_LON = NAV_LAT + 1
NAV_H = NAV_LAT + 2
NAV_SIZE = NAV_LAT + 3

#: slices of ``nav`` (and of the columns of a recorded ``(K, NAV_SIZE)`` solution)
Q_SLICE = slice(NAV_Q, NAV_Q + 4)
VEL_SLICE = slice(NAV_VEL, NAV_VEL + 3)
LLA_SLICE = slice(NAV_LAT, NAV_LAT + 3)

PREV_DTH = 0
PREV_DV = 3
PREV_VEL = 6
PREV_LLA = 9
PREV_FLAG = 12
PREV_TRIG = 13
PREV_SIZE = 17
