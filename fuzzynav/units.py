"""Unit conversions between datasheet units and SI, done in one place.

Multiply a datasheet value by the constant to get SI; divide an SI value to get the
datasheet unit.  Example: ``gyro_bias_rps = gyro_bias_dph * DPH``.
"""
from __future__ import annotations

import math

__all__ = ["G0", "DEG", "ARCMIN", "DPH", "DPS", "DPSH", "DPH_PSQRTHZ", "DPS_PSQRTHZ", "MG",
           "UG", "UG_PSQRTHZ", "MPS_PSH", "DPH_PSH", "PPM", "NT"]

#: standard gravity used for accelerometer units [m/s^2]
G0 = 9.80665
#: degree [rad]
DEG = math.pi / 180.0
#: arc minute [rad]
ARCMIN = DEG / 60.0
#: degree per hour [rad/s]
DPH = DEG / 3600.0
#: degree per second [rad/s]
DPS = DEG
#: degree per root-hour (angle random walk) [rad/sqrt(s)]
DPSH = DEG / 60.0
#: degree per hour per root-hertz (gyro noise density) [rad/s/sqrt(Hz)]
DPH_PSQRTHZ = DPH
#: degree per second per root-hertz [rad/s/sqrt(Hz)]
DPS_PSQRTHZ = DEG
#: milli-g [m/s^2]
MG = 1e-3 * G0
#: micro-g [m/s^2]
UG = 1e-6 * G0
#: micro-g per root-hertz (velocity random walk density) [m/s^2/sqrt(Hz)]
UG_PSQRTHZ = UG
#: metre per second per root-hour (velocity random walk) [m/s/sqrt(s)]
MPS_PSH = 1.0 / 60.0
#: degree per hour per root-hour (rate random walk) [rad/s/sqrt(s)]
DPH_PSH = DPH / 60.0
#: parts per million (scale factor) [-]
PPM = 1e-6
#: nanotesla (magnetic flux density) [T]
NT = 1e-9
