"""Check (and measure) the time alignment of IMU and GNSS on a recording of a car.

A car does not slip sideways much, so while it drives its heading changes as its course
over ground does.  The course is taken from the *positions*: the chord between two
consecutive fixes points along the path at the interval's midpoint (exactly so on an arc
of constant curvature).  The change of that course from one midpoint to the next is
compared with the heading change the gyros integrate between the same instants, the IMU
times shifted by a trial lag; the lag with the smallest squared difference (refined by a
parabola) is how much the IMU times must be moved to agree with GNSS time.  Comparing
changes over the same intervals avoids differentiating either signal.

Positions, not the reported velocities, are used because a receiver's velocity may be a
filtered estimate that lags its positions (RTKLIB's does, by about 0.14 s on the
rtklib-drive: :func:`velocity_lag`).
"""
from __future__ import annotations

import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.nav import earth

__all__ = ["gyro_course_gain", "course_rate_lag", "velocity_lag"]


def _chord_courses(gnss, max_gap_factor=1.5):
    """Midpoint times, courses [rad] and speeds [m/s] of chords between consecutive fixes."""
    z = gnss.z
    enu = earth.lla_to_enu(z[:, 0], z[:, 1], z[:, 2], z[0, 0], z[0, 1], z[0, 2])
    t = gnss.time_s
    dt = np.diff(t)
    d = np.diff(enu, axis=0)
    regular = dt <= max_gap_factor * np.median(dt)
    return 0.5 * (t[1:] + t[:-1]), np.unwrap(np.arctan2(d[:, 0], d[:, 1])), \
        np.hypot(d[:, 0], d[:, 1]) / dt, regular


def _best_lag(cost_of, lags):
    cost = np.array([cost_of(lag) for lag in lags])
    j = int(np.clip(np.argmin(cost), 1, lags.size - 2))
    c0, c1, c2 = cost[j - 1], cost[j], cost[j + 1]
    curv = c0 - 2.0 * c1 + c2
    shift = 0.5 * (c0 - c2) / curv if curv > 0 else 0.0
    return float(lags[j] + shift * (lags[1] - lags[0]))


def _course_changes(imu, gnss, up_b, min_speed_mps, margin_s, t_range=None):
    """Chord midpoints, usable pairs, course changes over them [rad] and the gyro heading
    integral at the IMU instants [rad] (up: ``up_b`` or the mean specific force)."""
    if up_b is None:
        up_b = imu.dv_b.sum(0)
    up_b = np.asarray(up_b, dtype=float) / np.linalg.norm(up_b)
    psi = np.concatenate([[0.0], np.cumsum(-(imu.dtheta_b @ up_b))])
    mid, course, speed, regular = _chord_courses(gnss)
    ok = (regular[:-1] & regular[1:] & (speed[:-1] >= min_speed_mps)
          & (speed[1:] >= min_speed_mps) & (mid[:-1] - margin_s > imu.time_s[0])
          & (mid[1:] + margin_s < imu.time_s[-1]))
    if t_range is not None:
        ok &= (mid[:-1] >= t_range[0]) & (mid[1:] <= t_range[1])
    return mid, ok, np.diff(course)[ok], psi


def gyro_course_gain(imu, gnss, min_speed_mps=3.0, min_turn_rad=np.pi / 2):
    """How many times the gyro heading turns as much as the GNSS course (1 if all is right).

    The least-squares factor ``k`` in ``course change = k x gyro heading change`` over the
    intervals between consecutive chords while moving (regressing the course on the gyro
    leaves the course's position noise unbiased).  ``None`` when the car did not move or
    turn enough (fewer than 20 intervals, or less than ``min_turn_rad`` of turning).

    ``imu`` is an :class:`~fuzzynav.sim.imu.ImuData` or a recording read from its file
    (:class:`~fuzzynav.realdata.loaders.imu_file.ImuFile`): the increments are taken a
    piece at a time (``imu.pieces()``), the angle integral carried across pieces.
    """
    mid, course, speed, regular = _chord_courses(gnss)
    t0, t1 = imu.span_s
    ok = (regular[:-1] & regular[1:] & (speed[:-1] >= min_speed_mps)
          & (speed[1:] >= min_speed_mps) & (mid[:-1] > t0) & (mid[1:] < t1))
    d_course = np.diff(course)[ok]
    if ok.sum() < 20 or np.sum(np.abs(d_course)) < min_turn_rad:
        return None
    theta, up = np.zeros((mid.size, 3)), np.zeros(3)  # the angle integral at the midpoints
    carry = np.zeros(3)
    for p in (imu.pieces() if hasattr(imu, "pieces") else [imu]):
        cum = carry + np.concatenate([np.zeros((1, 3)), np.cumsum(p.dtheta_b, axis=0)])
        sel = (mid >= p.time_s[0]) & (mid <= p.time_s[-1])
        theta[sel] = np.column_stack([np.interp(mid[sel], p.time_s, cum[:, j])
                                      for j in range(3)])
        up += p.dv_b.sum(0)  # up: the mean specific force
        carry = cum[-1]
    d_psi = np.diff(-(theta @ (up / np.linalg.norm(up))))[ok]
    den = float(np.sum(d_psi * d_psi))
    return float(np.sum(d_psi * d_course) / den) if den > 0.0 else float("inf")


def course_rate_lag(imu, gnss, up_b=None, t_range=None, min_speed_mps=3.0, max_lag_s=0.5,
                    step_s=0.0025, source=None):
    """The shift [s] to add to IMU times for the gyro heading to follow the GNSS course.

    Parameters
    ----------
    imu : ImuData
    gnss : SensorData
        Position fixes (best: the RTK-fixed reference).
    up_b : array_like, optional
        The up direction in the body frame; default: the mean specific force direction.
    t_range : (float, float), optional
        Use only chords inside this time range [s].
    min_speed_mps : float
        Both chords of a pair must be at least this fast (a course is defined).
    max_lag_s, step_s : float
        Search range and grid [s].
    source : path-like, optional
        The recording the data came from, named in errors; default ``imu.meta["source"]``
        (set by the RTKLIB loader to the IMU file).

    Returns
    -------
    float

    Raises
    ------
    InputFileError
        Too few moving GNSS intervals in ``t_range`` to measure a lag (naming ``source``).
    """
    mid, ok, d_course, psi = _course_changes(imu, gnss, up_b, min_speed_mps, max_lag_s, t_range)
    if ok.sum() < 20:
        source = imu.meta.get("source") if source is None else source
        raise InputFileError(source, "time alignment", "too few moving GNSS intervals to "
                                                     "measure the IMU lag")

    def cost(lag):
        return np.sum((np.diff(np.interp(mid - lag, imu.time_s, psi))[ok] - d_course) ** 2)

    return _best_lag(cost, np.arange(-max_lag_s, max_lag_s + step_s / 2, step_s))


def velocity_lag(gnss, max_lag_s=0.5, step_s=0.0025):
    """How late [s] the reported velocities are relative to the positions' derivative.

    The chord velocity ``(p_k+1 - p_k) / dt`` belongs to the interval's midpoint; the
    returned ``d`` makes ``v(t + d)`` match it best (positive: the velocity lags).
    """
    z = gnss.z
    enu = earth.lla_to_enu(z[:, 0], z[:, 1], z[:, 2], z[0, 0], z[0, 1], z[0, 2])
    t = gnss.time_s
    dt = np.diff(t)
    ok = (dt <= 1.5 * np.median(dt)) & np.all(np.isfinite(z[1:, 3:]), axis=1)
    v_chord = np.diff(enu, axis=0) / dt[:, None]
    mid = 0.5 * (t[1:] + t[:-1])

    def cost(d):
        v = np.column_stack([np.interp(mid + d, t, z[:, 3 + j]) for j in range(3)])
        return np.sum((v - v_chord)[ok] ** 2)

    return _best_lag(cost, np.arange(-max_lag_s, max_lag_s + step_s / 2, step_s))
