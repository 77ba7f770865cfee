"""The ``als`` baseline's noise: autocovariance least squares on the training runs.

The INS error filter is time-varying and 15-dimensional; ALS needs a fixed-gain linear
filter.  So, per training run, the free-running INS (the EKF configuration with no aiding)
is compared with each GNSS receiver: ``y_k = INS - GNSS`` per ENU axis at the fix epochs is
the slowly drifting INS error plus the receiver's white error.  Each axis is modelled as a
constant-velocity error (``A = [[1, T], [0, 1]]``, ``G = [T^2/2, T]``, ``C = [1, 0]``), filtered
with a fixed stabilising gain, and ALS (:func:`fuzzynav.filters.als.als_estimate`) splits
the innovations' autocovariances into the drift's process noise and the receiver's ``R``.
The ratio of the estimated ``R`` to the variance the receiver claims, averaged over the
axes of a channel (``pos``, ``vel``) and geometrically over the runs, becomes the ``als``
filter's ``r_<channel>``.  The INS process noise stays nominal (the local model's ``Q``
describes the drift of the free INS, not the IMU noise), and channels of other sensors
(the polarization compass) are not estimated.  Epochs with a missing fix are dropped (an
outage makes the sampling irregular and is assumed rare).
"""
from __future__ import annotations

import numpy as np

from fuzzynav.errors import FuzzynavError
from fuzzynav.experiment import SimulatedSource, setup_for
from fuzzynav.filters.als import als_estimate, innovations, steady_gain
from fuzzynav.filters.named import FilterSetup
from fuzzynav.runpath import run
from fuzzynav.nav import earth
from fuzzynav.sim.sensor_log import SensorLog

__all__ = ["INS_RATE_HZ", "ins_minus_gnss", "axis_r", "run_scales", "als_params"]

#: autocovariance lags and the filter transient dropped [epochs]
LAGS, SKIP = 15, 20
#: output rate of the free INS [Hz] (interpolated to the fix epochs)
INS_RATE_HZ = 50.0


def ins_minus_gnss(log, data) -> tuple:
    """``(y (K, 6), claimed variance (K, 6), T)``: free INS minus a receiver, ENU m and m/s."""
    free = FilterSetup(config=setup_for(log, "ekf").config.with_(out_rate_hz=INS_RATE_HZ))
    res = run(SimulatedSource(log, aided=False), "ekf (free inertial)", setup=free).result
    t = np.asarray(data.time_s, float)
    ins = np.column_stack([np.interp(t, res.time_s, res.lla[:, i]) for i in range(3)] +
                          [np.interp(t, res.time_s, res.vel_n[:, i]) for i in range(3)])
    z = np.asarray(data.z, float)[:, :6]
    rm, rn = earth.radii(ins[:, 0])
    y = np.column_stack([(ins[:, 1] - z[:, 1]) * (rn + ins[:, 2]) * np.cos(ins[:, 0]),
                         (ins[:, 0] - z[:, 0]) * (rm + ins[:, 2]), ins[:, 2] - z[:, 2],
                         ins[:, 3:6] - z[:, 3:6]])
    var = np.asarray(data.sigma, float)[:, :6] ** 2
    ok = np.all(np.isfinite(y), axis=1) & np.all(np.isfinite(var), axis=1)
    return y[ok], var[ok], float(np.median(np.diff(t))) if t.size > 1 else 1.0


def axis_r(y, var, T: float) -> float:
    """ALS estimate of one axis's white measurement variance (local constant-velocity model)."""
    A = np.array([[1.0, T], [0.0, 1.0]])
    G = np.array([[0.5 * T * T], [T]])
    C = np.array([[1.0, 0.0]])
    r0 = float(np.mean(var))
    L = steady_gain(A, G, C, 0.01 * r0, r0)  # any stabilising gain will do; this is smooth
    e = innovations(A, C, L, y.reshape(-1, 1))
    return float(als_estimate(A, G, C, L, e, lags=LAGS, skip=SKIP).R[0, 0])


def run_scales(log) -> dict:
    """``{"pos": ratio, "vel": ratio}``: estimated over claimed R on one run's receivers."""
    ratios = {"pos": [], "vel": []}
    for data in log.sensors.values():
        if data.kind != "gnss":
            continue
        y, var, T = ins_minus_gnss(log, data)
        for i in range(6):
            ratios["pos" if i < 3 else "vel"].append(axis_r(y[:, i], var[:, i], T)
                                                     / float(np.mean(var[:, i])))
    return {c: float(np.mean(v)) for c, v in ratios.items() if v}


def als_params(evaluator, runs) -> dict:
    """The ``als`` filter's ``r_<channel>``: geometric mean over the runs of :func:`run_scales`."""
    logs = [evaluator.log(sc, sd) for sc, sd in runs]
    for (sc, sd), log in zip(runs, logs):
        if not isinstance(log, SensorLog):  # a long run of a [streaming] study
            raise FuzzynavError(f"als: fits its noise on each training run's whole log; run "
                                f"({sc}, seed {sd}) is streamed chunk by chunk by the "
                                "study's [streaming] table (raise its hold_log_mb to hold it)")
    per_run = [run_scales(log) for log in logs]
    chans = sorted({c for p in per_run for c in p})
    return {f"r_{c}": float(np.exp(np.mean([np.log(max(p[c], 1e-6)) for p in per_run if c in p])))
            for c in chans}
