"""The epoch context an adaptation policy sees besides the innovations (numba).

The loop fills one array ``ctx`` before every policy call (:func:`fill`)::

    ctx[CTX_SPEED]   speed |v_n| of the navigation state [m/s]
    ctx[CTX_RATE]    angular-rate magnitude |omega_ib_b| of the latest IMU interval [rad/s]
    ctx[CTX_FORCE]   specific-force magnitude minus local normal gravity, |f_b| - g [m/s^2]
    ctx[CTX_M]       M, the loop's largest row count (where the data row starts)
    ctx[CTX_R:CTX_R + M]        the nominal variances ``R`` the measurement model wrote
    ctx[CTX_R + M:]             this epoch's data row (the measurement model's ``rows``)

From it come the motion-state and receiver-quality statistics of a rule file's binding
(:data:`STATISTICS`; units are those the rule file's ranges are written in):

* ``speed`` [m/s];
* ``angular_rate`` [deg/s] (rad/s inside; the earth rate, 0.004 deg/s, is included);
* ``force_deviation`` [m/s^2]: ``|f| - g``, ~0 at rest and in steady cruise, positive
  when accelerating or pulling g, negative in free fall;
* ``reported_sigma``: the sensor's own claim, ``sqrt(mean R_i)`` over the channel's rows
  before any adaptation [the channel's unit: m, m/s, ...];
* ``fix_type``, ``n_sat``: columns of the data row that the measurement model names in its
  ``quality`` (GNSS: RTKLIB's Q, 1 fixed ... 6 PPP, and the satellite count), present in
  recordings and NaN where the data has none (the policy then refuses the binding).

Rate and force are those of the IMU interval just before the epoch (not averaged), with
the bias estimates removed.
"""
from __future__ import annotations

import math

import numba as nb

from fuzzynav import units
from fuzzynav.filters.layout import AUX_FORCE, AUX_RATE
from fuzzynav.filters.adaptation import window
from fuzzynav.nav.earth import gravity_nb
from fuzzynav.nav.state_layout import NAV_H, NAV_LAT, NAV_VEL

__all__ = ["MOTION", "CLAIM", "QUALITY", "STATISTICS", "size", "fill", "statistic"]

CTX_SPEED, CTX_RATE, CTX_FORCE, CTX_M, CTX_R = 0, 1, 2, 3, 4

#: motion-state statistics -> kernel code (channel ``all``)
MOTION = {"speed": 4, "angular_rate": 5, "force_deviation": 6}
#: the sensor's claim, per channel
CLAIM = {"reported_sigma": 7}
#: receiver-quality columns of the data row (named by the measurement model's ``quality``)
QUALITY = {"fix_type": 8, "n_sat": 9}
#: every statistic a binding may name -> kernel code
STATISTICS = {**window.STATISTICS, **MOTION, **CLAIM, **QUALITY}
_RAD_TO_DEG = 1.0 / units.DPS


@nb.njit(cache=True, error_model="numpy")
def size(M, W):
    """Length of ``ctx`` for ``M`` rows at most and data rows of width ``W``."""
    return CTX_R + M + W


@nb.njit(cache=True, error_model="numpy")
def fill(ctx, nav, aux, R, m, row):
    """Write the epoch's motion state, nominal variances ``R[:m]`` and data ``row``."""
    ctx[CTX_SPEED] = math.sqrt(nav[NAV_VEL] ** 2 + nav[NAV_VEL + 1] ** 2
                               + nav[NAV_VEL + 2] ** 2)
    ctx[CTX_RATE] = math.sqrt(aux[AUX_RATE] ** 2 + aux[AUX_RATE + 1] ** 2
                              + aux[AUX_RATE + 2] ** 2)
    f = math.sqrt(aux[AUX_FORCE] ** 2 + aux[AUX_FORCE + 1] ** 2 + aux[AUX_FORCE + 2] ** 2)
    ctx[CTX_FORCE] = f - gravity_nb(nav[NAV_LAT], nav[NAV_H])
    M = int(ctx[CTX_M])
    for i in range(m):
        ctx[CTX_R + i] = R[i]
    for j in range(row.size):
        ctx[CTX_R + M + j] = row[j]


@nb.njit(cache=True, error_model="numpy")
def statistic(kind, ctx, chan, m, c):
    """Context statistic ``kind`` (codes 4-9 of :data:`STATISTICS`); ``c`` is the channel
    (``reported_sigma``, -1 all rows) or the data-row column (``fix_type``, ``n_sat``)."""
    if kind == 4:
        return ctx[CTX_SPEED]
    if kind == 5:
        return ctx[CTX_RATE] * _RAD_TO_DEG
    if kind == 6:
        return ctx[CTX_FORCE]
    if kind == 7:
        s, k = 0.0, 0
        for i in range(m):
            if c < 0 or chan[i] == c:
                s += ctx[CTX_R + i]
                k += 1
        return math.sqrt(s / k) if k > 0 else math.nan
    return ctx[CTX_R + int(ctx[CTX_M]) + c]
