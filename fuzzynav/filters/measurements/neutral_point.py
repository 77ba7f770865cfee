"""Neutral-point polarization heading (paper 003): the angle of the line through two
neutral points in a body-fixed fisheye image.

Data row (:mod:`fuzzynav.sim.sensors.neutral_point`): ``[beta, sun_e, sun_n, sun_u, pair,
sigma, 0, 0, 0, 0]``.  Parameters: ``[delta_rad]``.  The model predicts the line angle from
the INS attitude, the sun and the sky model of :mod:`fuzzynav.nav.neutral_points`, so the
ship's roll and pitch enter exactly (paper 003 reads the heading as ``beta`` plus the sun
azimuth, which holds for a level camera only)::

    z = wrap(beta_hat(C_bn) - beta),   H_att = d beta_hat((I - [phi x]) C_bn) / d phi

(central differences of the closed-form projection, step 1e-6 rad; ``beta`` turns with the
heading one for one, so ``H`` is about ``[tilt terms, tilt terms, +-1]``).  ``R = sigma^2``.
Channel: ``heading``.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.filters.layout import X_ATT
from fuzzynav.filters.numba_lazy import njit_signature
from fuzzynav.filters.measurements import MEAS_SIG, MeasurementModel, register
from fuzzynav.nav.neutral_points import pair_beta

__all__ = ["neutral_point_kernel", "MODEL"]

_STEP = 1e-6


@nb.njit(cache=True, error_model="numpy")
def _wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@nb.njit(cache=True, error_model="numpy")
def _tilted(C_bn, axis, eps, out):
    """``(I - [phi x]) C_bn`` for ``phi = eps e_axis`` into ``out``."""
    phi = np.zeros(3)
    phi[axis] = eps
    for j in range(3):
        c0, c1, c2 = C_bn[0, j], C_bn[1, j], C_bn[2, j]
        out[0, j] = c0 + phi[2] * c1 - phi[1] * c2
        out[1, j] = c1 - phi[2] * c0 + phi[0] * c2
        out[2, j] = c2 + phi[1] * c0 - phi[0] * c1


@njit_signature(MEAS_SIG)
def neutral_point_kernel(nav, C_bn, aux, row, par, dt_back, z, H, R, chan):
    sig = row[5]
    if not (sig > 0.0 and math.isfinite(row[0])):
        return 0
    sun = row[1:4].copy()
    pair = int(row[4])
    pts = np.zeros((4, 3))
    z[0] = _wrap(pair_beta(C_bn, sun, par[0], pair, pts) - row[0])
    Cp = np.zeros((3, 3))
    for i in range(3):
        _tilted(C_bn, i, _STEP, Cp)
        bp = pair_beta(Cp, sun, par[0], pair, pts)
        _tilted(C_bn, i, -_STEP, Cp)
        bm = pair_beta(Cp, sun, par[0], pair, pts)
        H[0, X_ATT + i] = _wrap(bp - bm) / (2.0 * _STEP)
    R[0] = sig * sig
    chan[0] = 0
    return 1


def _pack(data, options) -> np.ndarray:
    return np.array([float(data.meta.get("delta_rad", np.deg2rad(20.0)))])


MODEL = register(MeasurementModel(kind="neutral_point", kernel=neutral_point_kernel,
                                  max_rows=1, channels=("heading",), pack=_pack))
