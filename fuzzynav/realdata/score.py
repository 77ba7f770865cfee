"""Scoring a filter run against the untouched fixes: horizontal RMS and drift per outage.

Errors are formed at the reference epochs (the RTK fixes), the solution interpolated
linearly to them (:func:`fuzzynav.metrics.errors_vs_reference`) after moving it from the
IMU to the antenna by the lever arm.

**Drift at the end of an outage** ``[a, b)`` is the horizontal error at the last reference
epoch ``t_r`` inside the window that is not later than the last solution sample before
``b`` — so that both solution samples the interpolation uses precede the first fix after the
outage and no update leaks in.  An outage is *complete* when the solution runs past ``b``
and such an epoch lies within ``max_gap_s`` of ``b``; only complete outages are scored.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from fuzzynav.errors import FuzzynavError
from fuzzynav.metrics import NavErrors, errors_vs_reference, rms_metrics
from fuzzynav.nav import attitude, earth
from fuzzynav.realdata.protocol import read_later
from fuzzynav.sim.sensors.gnss import in_windows

__all__ = ["OutageDrift", "antenna_track", "check_scored", "errors_against", "horizontal",
           "outage_drifts", "score", "outage_scoring"]


@dataclass(frozen=True)
class OutageDrift:
    """Horizontal error at the end of one outage.

    Attributes
    ----------
    start_s, end_s : float
        The outage window [s].
    complete : bool
        Whether it is scored (module docstring).
    t_read_s : float
        Reference epoch at which the drift is read [s] (NaN if incomplete).
    drift_h_m : float
        Horizontal error there [m].
    max_h_m : float
        Largest horizontal error at reference epochs inside the outage [m].
    """

    start_s: float
    end_s: float
    complete: bool
    t_read_s: float
    drift_h_m: float
    max_h_m: float


def antenna_track(result, lever_arm_b) -> object:
    """The result with its positions moved from the IMU to the antenna (``p + C_bn l``)."""
    lever = np.asarray(lever_arm_b, float)
    if not np.any(lever):
        return result
    l_n = attitude.quat_to_dcm(result.q_bn) @ lever
    dlat, dlon, dh = earth.enu_to_delta_lla(l_n, result.lla[:, 0], result.lla[:, 2])
    return replace(result, lla=result.lla + np.column_stack([dlat, dlon, dh]))


def errors_against(result, reference, lever_arm_b=(0.0, 0.0, 0.0),
                   velocity_lag_s: float = 0.0) -> NavErrors:
    """Antenna errors at the reference epochs; reference velocities read ``velocity_lag_s``
    later (a receiver whose velocities lag its positions)."""
    vel = read_later(reference.z[:, 3:6], reference.time_s, velocity_lag_s)
    return errors_vs_reference(antenna_track(result, lever_arm_b), reference.time_s,
                               reference.z[:, :3], vel)


def horizontal(err: NavErrors) -> np.ndarray:
    """Horizontal error magnitude [m] per epoch."""
    return np.hypot(err.pos_m[:, 0], err.pos_m[:, 1])


def outage_drifts(err: NavErrors, result_time_s, windows, max_gap_s: float = 1.0) -> list:
    """:class:`OutageDrift` of every window (module docstring for the rule)."""
    h = horizontal(err)
    t_res = np.asarray(result_time_s, float)
    out = []
    for a, b in np.asarray(windows, float).reshape(-1, 2):
        before = t_res[t_res < b]
        sel = (err.time_s >= a) & (err.time_s < b)
        if before.size:
            sel &= err.time_s <= before[-1]
        ok = bool(sel.any() and t_res.size and t_res[-1] >= b
                  and b - err.time_s[sel][-1] <= max_gap_s)
        if ok:
            k = np.flatnonzero(sel)
            out.append(OutageDrift(float(a), float(b), True, float(err.time_s[k[-1]]),
                                   float(h[k[-1]]), float(h[k].max())))
        else:
            out.append(OutageDrift(float(a), float(b), False, np.nan, np.nan, np.nan))
    return out


def check_scored(reference, t_start_s: float, t_end_s: float, what: str) -> None:
    """Refuse a run with no reference epoch in ``[t_start_s, t_end_s]`` before it runs:
    its metrics would all be NaN, which reads as a diverged filter.

    Raises
    ------
    FuzzynavError
        Naming ``what`` (the recording or study run), the scored span and where the
        reference's epochs lie.
    """
    t = np.asarray(reference.time_s, float)
    if np.any((t >= t_start_s) & (t <= t_end_s)):
        return
    where = (f"its {t.size} epochs lie in {t[0]:.1f}-{t[-1]:.1f} s" if t.size
             else "it has no epochs")
    raise FuzzynavError(f"{what}: no reference epoch to score in {t_start_s:.1f}-"
                        f"{t_end_s:.1f} s (after the filter start and --t-start / t_start_s; "
                        f"{where}): nothing would be scored")


def score(err: NavErrors, result_time_s, windows, t_start_s: float = 0.0) -> dict:
    """Metrics of one run (SI, names carry the unit).

    Returns ``rms_pos_*``/``rms_vel_*``/``max_pos_h_m`` of :func:`fuzzynav.metrics.rms_metrics`,
    ``rms_pos_h_aided_m`` (horizontal RMS at epochs outside the outage windows),
    ``drift_h_m_<k>`` for complete outage ``k`` (1-based, in time order), ``drift_h_rms_m``,
    ``drift_h_max_m`` (over complete outages), ``outage_max_h_m`` and ``n_outages``.
    The drift figures are computed at the same instants for a run fed without outages,
    which shows what the GNSS-aided error is there.
    """
    m = rms_metrics(err, t_start_s)
    sel = (err.time_s >= t_start_s) & ~in_windows(err.time_s, windows)
    h = horizontal(err)[sel]
    m["rms_pos_h_aided_m"] = float(np.sqrt(np.mean(h**2))) if h.size else float("nan")
    drifts = [d for d in outage_drifts(err, result_time_s, windows) if d.complete]
    for k, d in enumerate(drifts, 1):
        m[f"drift_h_m_{k}"] = d.drift_h_m
    v = np.array([d.drift_h_m for d in drifts])
    m["drift_h_rms_m"] = float(np.sqrt(np.mean(v**2))) if v.size else float("nan")
    m["drift_h_max_m"] = float(v.max()) if v.size else float("nan")
    m["outage_max_h_m"] = float(max(d.max_h_m for d in drifts)) if drifts else float("nan")
    m["n_outages"] = float(len(drifts))
    return m


def outage_scoring(errors, windows, t_start_s: float = 0.0, seen: dict | None = None):
    """The :class:`~fuzzynav.realdata.reference_scoring.ReferenceScoring` of a run fed with
    outages ``windows``: ``errors(result) -> NavErrors`` (:func:`errors_against`), finished
    by :func:`score` from ``t_start_s`` on; the outage ends are the instants whose last
    solution time the drifts read.  ``seen``, if given, receives the ``errors`` and
    ``solution_time_s`` each run was scored on (for :func:`outage_drifts`)."""
    from fuzzynav.realdata.reference_scoring import ReferenceScoring

    def finish(err, t_res, _result):
        if seen is not None:
            seen.update(errors=err, solution_time_s=t_res)
        return score(err, t_res, windows, t_start_s)

    return ReferenceScoring(errors, finish,
                            tuple(np.asarray(windows, float).reshape(-1, 2)[:, 1]))
