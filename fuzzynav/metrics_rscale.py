"""How much an adaptive filter still uses a magnetometer: its R-scale on calm and disturbed epochs.

A fuzzy R-scaling controller (:mod:`fuzzynav.filters.adaptation.r_scaling`) that learns to
hold the magnetometer's running factor ``s = R / R_nominal`` far above 1 has switched the
sensor off: on the disturbance it wins, but it is no controller to ship.  These statistics
split the magnetometer epochs of a simulated run by the simulator's truth
(``meta["deflection_rad"]``, the disturbance zones' share of the heading error): *calm*
epochs (no deflection) and *zone* epochs (inside a disturbance zone, ramps included).

Metrics (prefix :data:`PREFIX`, not required finite: a run without a zone has no zone
figures):

* ``r_use_dev_calm``: ``exp(mean |ln s|)`` over calm epochs, the geometric-mean factor by
  which R departs from its nominal value in either direction (1 = nominal throughout; a
  constant-noise filter scores 1) -- the penalty a study may weight (objective group
  ``r_use``);
* ``r_use_median_calm`` / ``r_use_median_zone``: the median factor;
* ``r_use_off_calm`` / ``r_use_off_zone``: the fraction of epochs with ``s >`` :data:`OFF_SCALE`
  (the magnetometer weighed at less than a tenth of its nominal information).
"""
from __future__ import annotations

import numpy as np

__all__ = ["PREFIX", "OFF_SCALE", "CALM_RAD", "r_scale_trace", "usage_stats", "usage_metrics"]

#: the metrics' name prefix
PREFIX = "r_use_"
#: a running R factor above this weighs the sensor at less than 1/10 of its information
OFF_SCALE = 10.0
#: a deflection below this is no disturbance (the zones' raised-cosine ramps start at 0) [rad]
CALM_RAD = 1e-9
#: the sensor kind these statistics concern
KIND = "magnetometer"


#: diagnostics that carry R over its nominal value: the fuzzy R-scaling's running factor and a
#: constant scale (``r_scale``), Sage-Husa's and VB's first row (``r_scale_row0``: the heading
#: row of the magnetometer's heading measurement)
SCALE_DIAGS = ("r_scale", "r_scale_row0")


def r_scale_trace(events, n: int) -> np.ndarray:
    """The R factor per epoch of one sensor's event log (:data:`SCALE_DIAGS`); ones (nominal
    R) when the filter logs none for that sensor (a constant-noise EKF, Huber)."""
    names = getattr(events, "diag_names", ())
    for d in SCALE_DIAGS:
        if d in names:
            return np.asarray(events.diagnostic(d), float)
    return np.ones(n)


def usage_stats(scale, calm) -> dict:
    """The usage statistics of an R-factor trace split by a calm mask.

    Parameters
    ----------
    scale : (E,) array_like
        Running R factor per epoch (non-finite or non-positive entries are dropped).
    calm : (E,) array_like of bool
        True on epochs without a disturbance.

    Returns
    -------
    dict
        ``dev_calm``, ``median_calm``, ``off_calm``, ``median_zone``, ``off_zone`` (see the
        module docstring); NaN where the split holds no epoch.
    """
    s = np.asarray(scale, float)
    calm = np.asarray(calm, bool)
    if s.shape != calm.shape:
        raise ValueError(f"scale {s.shape} and calm mask {calm.shape} differ in shape")
    ok = np.isfinite(s) & (s > 0.0)
    out = {}
    for name, mask in (("calm", ok & calm), ("zone", ok & ~calm)):
        x = s[mask]
        out[f"median_{name}"] = float(np.median(x)) if x.size else float("nan")
        out[f"off_{name}"] = float(np.mean(x > OFF_SCALE)) if x.size else float("nan")
        if name == "calm":
            out["dev_calm"] = float(np.exp(np.mean(np.abs(np.log(x))))) if x.size else float("nan")
    return out


def usage_metrics(result, sensors) -> dict:
    """:func:`usage_stats` of the first magnetometer of a simulated run, as metrics.

    Parameters
    ----------
    result : FilterResult
        Its ``events`` name the streams as ``sensors`` does.
    sensors : dict
        Sensor name -> :class:`~fuzzynav.sim.sensors.SensorData` of the log.

    Returns
    -------
    dict
        ``r_use_*`` metrics; empty without a magnetometer carrying the simulator's
        ``deflection_rad`` (a recording, another scenario family).
    """
    for name, data in sensors.items():
        defl = getattr(data, "meta", {}).get("deflection_rad") if data.kind == KIND else None
        if defl is None:
            continue
        events = getattr(result, "events", {}).get(name)
        n = len(data.time_s) if events is None else len(events.time_s)
        calm = np.abs(np.asarray(defl, float)[:n]) < CALM_RAD
        scale = r_scale_trace(events, n)
        if calm.shape != scale.shape:  # a run that stopped early logs fewer epochs
            calm = calm[:scale.size]
        return {PREFIX + k: v for k, v in usage_stats(scale, calm).items()}
    return {}
