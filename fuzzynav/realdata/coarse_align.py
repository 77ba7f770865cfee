"""Initial navigation state from the data itself: level at rest, heading once moving.

* **Rest.**  The opening period in which the GNSS speed stays below ``rest_speed_mps``
  (or, without GNSS velocity, the IMU's rate and specific force stay steady).
* **Level.**  Pitch and roll from the mean specific force ``f`` at rest, which points up
  (:func:`fuzzynav.nav.coarse.level`, the package's one coarse alignment).
* **Heading**, four ways (:mod:`fuzzynav.realdata.start_options` chooses, with every speed,
  window and threshold below):

  - given by the caller;
  - ``course``: when the body's forward axis is the vehicle's (a mounting is known), the
    GNSS course over ground is the heading of that axis while driving; each epoch in the
    first ``window_s`` of motion with speed above ``min_speed_mps`` gives
    ``heading_0 = course - azimuth of the forward axis`` propagated back to the end of
    rest with the gyros, and their circular mean is used;
  - ``track``: the same with the course read from chords of the GNSS track at least
    ``baseline`` metres long, for a platform too slow for its velocity to give a course;
  - ``specific-force``: when the forward axis is unknown (IMU frame = body frame), the
    specific force, levelled and carried by the gyros into the rest frame and integrated
    over short intervals between GNSS epochs, ``a_j = L sum C_b0_b dv_b``, must equal the
    velocity change the GNSS sees over the same interval with Coriolis put back,
    ``b_j = v(t_j+1) - v(t_j) + int (2 w_ie + w_en) x v dt``, up to the heading; the
    horizontal parts give it in closed form, ``heading = atan2(sum(b_e a_n - b_n a_e),
    sum(b_e a_e + b_n a_n))`` (a two-dimensional Wahba problem in velocity-increment
    form: no differentiation of the GNSS velocity, and over intervals of a second an
    accelerometer bias of some mg barely matters, while summed over a whole window it
    would turn the solution by tens of degrees).

The gyros are corrected by their mean at rest (bias and earth rate together); over a
window of a minute the earth rate left out of the propagation is below 0.25 deg.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.nav import attitude, earth
from fuzzynav.nav.coarse import body_chain, level
from fuzzynav.realdata.start_options import StartOptions
from fuzzynav.realdata import start_check

__all__ = ["StartEstimate", "opening_rest", "level", "relative_attitude",
           "heading_from_course", "heading_from_track", "heading_from_specific_force",
           "initial_state", "reads_until_s"]


@dataclass(frozen=True)
class StartEstimate:
    """Initial navigation state estimated from the data.

    Attributes
    ----------
    time_s : float
        Epoch of the state: the end of the opening rest [s].
    lla : ndarray, shape (3,)
        GNSS position at ``time_s`` (antenna; lat, lon [rad], h [m]).
    vel_n : ndarray, shape (3,)
        GNSS velocity at ``time_s`` [m/s] (ENU).
    att : ndarray, shape (3,)
        Pitch, roll, heading [rad] of the body frame.
    gyro_bias_rps : ndarray, shape (3,)
        Mean gyro rate at rest minus the earth rate seen with ``att`` [rad/s].
    f_rest_mps2 : float
        Magnitude of the mean specific force at rest [m/s^2].
    rest_s : tuple of float
        The rest period used for levelling [s].
    method : str
        ``given``, ``course``, ``track`` or ``specific-force``.
    heading_check : str
        What the independent headings said of a ``course``/``track`` heading
        (:mod:`fuzzynav.realdata.start_check`): it agrees, it was turned by 180 degrees,
        or why its direction could not be checked; empty for other methods.
    """

    time_s: float
    lla: np.ndarray
    vel_n: np.ndarray
    att: np.ndarray
    gyro_bias_rps: np.ndarray
    f_rest_mps2: float
    rest_s: tuple
    method: str
    heading_check: str = ""


def _speed(gnss) -> np.ndarray:
    return np.hypot(gnss.z[:, 3], gnss.z[:, 4])


def opening_rest(imu, gnss, rest_speed_mps=0.2, min_rest_s=2.0, block_s=0.5,
                 min_force_mps2=0.02):
    """The rest period at the start, ``(t0, t1)`` [s].

    It ends before the first GNSS epoch faster than ``rest_speed_mps`` and, earlier, at the
    first block of ``block_s`` whose mean specific force leaves that of the first half of
    the rest by more than five times its block-to-block spread (at least
    ``min_force_mps2``): a smooth start is seen by the accelerometers before the GNSS
    speed rises above its noise.
    """
    t0 = float(imu.time_s[0])
    speed = _speed(gnss)
    moving = (gnss.time_s >= t0) & np.isfinite(speed) & (speed > rest_speed_mps)
    t_move = float(gnss.time_s[moving][0]) if moving.any() else float(imu.time_s[-1])
    edges = np.arange(t0, t_move, block_s)
    if edges.size >= 5:
        k = np.searchsorted(imu.time_s, edges)
        # divide by each block's own length: float edges may give 49 or 51 samples a block
        span = np.diff(imu.time_s[k])[:, None]
        f = np.add.reduceat(imu.dv_b[: k[-1]], k[:-1], axis=0) / span
        ref = np.median(f[: max(2, f.shape[0] // 2)], axis=0)
        dev = np.linalg.norm(f - ref, axis=1)
        thr = max(5.0 * 1.4826 * np.median(dev[: max(2, f.shape[0] // 2)]), min_force_mps2)
        out = np.flatnonzero(dev > thr)
        t_move = float(edges[out[0]]) if out.size else float(edges[-1])
    if t_move - t0 < min_rest_s:
        raise InputFileError(None, "initialisation", f"no rest of {min_rest_s:g} s at the "
                             f"start (moving {t_move - t0:.1f} s after the first IMU sample; "
                             f"options min_rest, rest_speed)")
    return t0, t_move


def relative_attitude(imu, k0, k1, rate_bias_rps):
    """``C_b0_b`` at samples ``k0 .. k1`` from bias-corrected gyro increments, (K, 3, 3)."""
    dth = imu.dtheta_b[k0:k1] - rate_bias_rps * np.diff(imu.time_s[k0:k1 + 1])[:, None]
    return attitude.quat_to_dcm(body_chain(np.ascontiguousarray(dth)))


def _gnss_at(gnss, t):
    return np.array([np.interp(t, gnss.time_s, gnss.z[:, j]) for j in range(6)])


def _window(imu, gnss, t_ref, window_s, min_speed_mps):
    k0 = int(np.searchsorted(imu.time_s, t_ref))
    sel = ((gnss.time_s > imu.time_s[k0]) & (gnss.time_s <= t_ref + window_s)
           & (gnss.time_s < imu.time_s[-1]))
    if not sel.any():
        raise InputFileError(None, "initialisation", f"no GNSS fix within {window_s:g} s "
                             f"after rest (option window)")
    if min_speed_mps is not None and not np.any(sel & (_speed(gnss) >= min_speed_mps)):
        raise InputFileError(None, "initialisation", f"the vehicle does not reach "
                             f"{min_speed_mps:g} m/s within {window_s:g} s after rest "
                             f"(options min_speed, window; a slow platform: e.g. "
                             f"?min_speed=0.5 or ?heading=track, docs/data.md)")
    k1 = int(np.searchsorted(imu.time_s, gnss.time_s[sel][-1])) + 1
    return k0, k1, np.flatnonzero(sel)


def heading_from_course(imu, gnss, t_ref, c_level, rate_bias, window_s=30.0,
                        min_speed_mps=2.0, with_sigma=False):
    """Heading [rad] at ``t_ref`` of a body whose y axis is the direction of travel.

    With ``with_sigma``, also the 1-sigma [rad]: the circular spread of the epochs' own
    headings over the square root of half their number (GNSS velocities are correlated).
    """
    k0, k1, idx = _window(imu, gnss, t_ref, window_s, min_speed_mps)
    idx = idx[_speed(gnss)[idx] >= min_speed_mps]
    course = np.arctan2(gnss.z[idx, 3], gnss.z[idx, 4])
    d = course - _forward_azimuth(imu, k0, k1, c_level, rate_bias, gnss.time_s[idx])
    if with_sigma:
        return _circular_mean(d), start_check.circular_sigma(d, max(1, d.size // 2))
    return _circular_mean(d)


def _forward_azimuth(imu, k0, k1, c_level, rate_bias, t):
    """Azimuth [rad] at the instants ``t`` of the body y axis, relative to the rest frame."""
    C = relative_attitude(imu, k0, k1, rate_bias)
    t_imu = imu.time_s[k0:k1 + 1]
    k = np.clip(np.searchsorted(t_imu, t), 0, len(t_imu) - 1)
    fwd = np.einsum("ij,kjl,l->ki", c_level, C[k], np.array([0.0, 1.0, 0.0]))
    return np.arctan2(fwd[:, 0], fwd[:, 1])


def _circular_mean(d) -> float:
    return float(attitude.wrap_2pi(np.arctan2(np.sin(d).mean(), np.cos(d).mean())))


def heading_from_track(imu, gnss, t_ref, c_level, rate_bias, window_s=30.0,
                       baseline_m=10.0, with_sigma=False):
    """Heading [rad] at ``t_ref`` of a body whose y axis is the direction of travel, from the
    GNSS track: for a slow platform, whose velocity is too small for its course to be read.

    Each fix in the window is paired with the first later fix at least ``baseline_m`` away
    (horizontally); the chord's azimuth is the course at its middle instant, where the
    gyro-propagated azimuth of the forward axis is subtracted; the circular mean of the
    differences is the heading.  The position noise turns a chord by about
    ``sigma / baseline`` rad: choose the baseline well above the fixes' noise.
    With ``with_sigma``, also the 1-sigma [rad]: the chords' circular spread over the
    square root of half their number (consecutive chords share fixes).
    """
    k0, k1, idx = _window(imu, gnss, t_ref, window_s, None)  # no velocity needed
    lla = gnss.z[idx, :3]
    enu = earth.delta_lla_to_enu(lla[:, 0] - lla[0, 0], lla[:, 1] - lla[0, 1], 0.0,
                                 lla[0, 0], lla[0, 2])
    pairs = []
    for i in range(idx.size - 1):
        far = np.flatnonzero(np.hypot(*(enu[i + 1:, :2] - enu[i, :2]).T) >= baseline_m)
        if far.size:
            pairs.append((i, i + 1 + far[0]))
    if not pairs:
        raise InputFileError(None, "initialisation", f"the platform does not move "
                             f"{baseline_m:g} m within {window_s:g} s after rest (options "
                             f"baseline, window)")
    i, j = np.array(pairs).T
    chord = enu[j, :2] - enu[i, :2]
    t_mid = 0.5 * (gnss.time_s[idx[i]] + gnss.time_s[idx[j]])
    d = np.arctan2(chord[:, 0], chord[:, 1]) - _forward_azimuth(imu, k0, k1, c_level,
                                                                  rate_bias, t_mid)
    if with_sigma:
        return _circular_mean(d), start_check.circular_sigma(d, max(1, d.size // 2))
    return _circular_mean(d)


def heading_from_specific_force(imu, gnss, t_ref, c_level, rate_bias, window_s=60.0,
                                min_speed_mps=2.0, interval_s=1.0, with_sigma=False):
    """Heading [rad] at ``t_ref`` by matching levelled specific force to GNSS velocity.

    Over each interval of about ``interval_s`` between GNSS epochs in the window, the
    levelled specific force carried into the rest frame, ``a = L sum C_b0_b dv_b``, is
    paired with the velocity change ``b = dv_gnss + int (2 w_ie + w_en) x v dt``; the
    horizontal parts give the heading in closed form.  Short intervals keep an
    accelerometer bias from accumulating (it would over a whole window).
    With ``with_sigma``, also the 1-sigma [rad]: the circular spread of the intervals' own
    headings about the fit, over the half of the intervals with the larger ``|a| |b|`` (the
    ones that carry the fit), divided by the square root of their number.
    """
    k0, k1, idx = _window(imu, gnss, t_ref, window_s, min_speed_mps)
    C = relative_attitude(imu, k0, k1, rate_bias)
    dv_b0 = np.einsum("kij,kj->ki", C[:-1], imu.dv_b[k0:k1])
    a_cum = np.vstack([np.zeros(3), np.cumsum(dv_b0, 0)]) @ c_level.T
    t_imu = imu.time_s[k0:k1 + 1]
    step = max(1, int(round(interval_s / np.median(np.diff(gnss.time_s)))))
    i0, i1 = idx[:-step], idx[step:]
    a = np.column_stack([np.interp(gnss.time_s[i1], t_imu, a_cum[:, j])
                         - np.interp(gnss.time_s[i0], t_imu, a_cum[:, j]) for j in range(2)])
    v = gnss.z[:, 3:6]
    lla = gnss.z[idx[0], :3]
    w = 2.0 * earth.omega_ie_n(lla[0]) + earth.omega_en_n(lla[0], lla[2], v)
    coriolis = np.cross(w, v)
    b = (v[i1] - v[i0] + 0.5 * (coriolis[i1] + coriolis[i0])
         * (gnss.time_s[i1] - gnss.time_s[i0])[:, None])
    num = np.sum(b[:, 0] * a[:, 1] - b[:, 1] * a[:, 0])
    den = np.sum(b[:, 0] * a[:, 0] + b[:, 1] * a[:, 1])
    heading = float(attitude.wrap_2pi(np.arctan2(num, den)))
    if not with_sigma:
        return heading
    each = np.arctan2(b[:, 0] * a[:, 1] - b[:, 1] * a[:, 0], np.sum(b[:, :2] * a, 1))
    wt = np.hypot(*a.T) * np.hypot(*b[:, :2].T)
    big = wt >= np.median(wt)  # the intervals that carry the fit
    return heading, start_check.circular_sigma(each[big] - heading)


def _heading(imu, gnss, t1, c_level, w, method, options, kw) -> float:
    """Heading [rad] at ``t1`` by ``method`` (``course``, ``track``, ``specific-force``)."""
    window = {"window_s": options.window_for(method)}
    if method == "track":
        return heading_from_track(imu, gnss, t1, c_level, w, baseline_m=options.
                                  track_baseline_m, **{**window, **kw})
    fn = heading_from_course if method == "course" else heading_from_specific_force
    return fn(imu, gnss, t1, c_level, w, **{**window, "min_speed_mps": options.min_speed_mps,
                                            **kw})


def _estimate(imu, gnss, t1, c_level, w, method, options, **kw):
    """``(method, heading, sigma)`` by ``method``, or None when the data give none."""
    try:
        h, sigma = _heading(imu, gnss, t1, c_level, w, method, options,
                            {"with_sigma": True, **kw})
    except InputFileError:
        return None
    return method, h, sigma


def _cross_check(imu, gnss, t1, c_level, w, method, options, kw) -> tuple:
    """The ``course``/``track`` heading checked against the other two methods
    (:mod:`fuzzynav.realdata.start_check`): refused when course and track disagree, turned
    by 180 degrees when the specific force says the forward axis points backward.

    Returns
    -------
    heading_rad : float
    finding : str
        What the checks found (:attr:`StartEstimate.heading_check`).
    """
    chosen = _estimate(imu, gnss, t1, c_level, w, method, options, **kw)
    other = _estimate(imu, gnss, t1, c_level, w, "track" if method == "course" else
                      "course", options)
    if other is not None:
        start_check.check_headings(chosen, other)
    sf = _estimate(imu, gnss, t1, c_level, w, "specific-force", options, min_speed_mps=None)
    also = f"; agrees with {other[0]}" if other is not None else ""
    if sf is None:
        return chosen[1], f"direction not checked: no specific-force heading{also}"
    heading, finding = start_check.resolve_direction(chosen, sf)
    return heading, finding + also


def initial_state(imu, gnss, heading_rad=None, forward_known=False, options=None,
                  **kw) -> StartEstimate:
    """Initial state at the end of the opening rest.

    Parameters
    ----------
    imu : ImuData
    gnss : SensorData
        GNSS fixes with velocity (kind ``gnss``).
    heading_rad : float, optional
        A known heading [rad]; else it is estimated.
    forward_known : bool
        Whether body y is the vehicle's forward axis (a mounting is given): then the
        heading comes from the GNSS course, else from specific-force matching.
    options : StartOptions, optional
        Rest detection, heading method, speeds and windows
        (:mod:`fuzzynav.realdata.start_options`; default: the car drive's).
    **kw
        ``window_s``, ``min_speed_mps`` for the heading estimators (override ``options``).
    """
    options = StartOptions() if options is None else options
    check = ""
    t0, t1 = opening_rest(imu, gnss, options.rest_speed_mps, options.min_rest_s)
    pitch, roll, f, w = level(imu, t0, t1)
    c_level = attitude.euler_to_dcm(np.array([pitch, roll, 0.0]))
    if heading_rad is None and options.heading_deg is not None:
        heading_rad = np.radians(options.heading_deg)
    if heading_rad is not None:
        heading, method = float(attitude.wrap_2pi(heading_rad)), "given"
    else:
        method = options.method(forward_known)
        heading = _heading(imu, gnss, t1, c_level, w, method, options, kw)
        if method in ("course", "track"):
            heading, check = _cross_check(imu, gnss, t1, c_level, w, method, options, kw)
    att = np.array([pitch, roll, heading])
    g = _gnss_at(gnss, t1)
    w_ie_b = attitude.euler_to_dcm(att).T @ earth.omega_ie_n(g[0])
    return StartEstimate(time_s=t1, lla=g[:3], vel_n=g[3:], att=att, gyro_bias_rps=w - w_ie_b,
                        f_rest_mps2=float(np.linalg.norm(f)), rest_s=(t0, t1), method=method,
                        heading_check=check)


def reads_until_s(span_s, gnss, options=None) -> float:
    """The latest time [s] up to which :func:`initial_state` reads increments: the first
    GNSS epoch faster than the rest speed (the rest ends before it), the longest heading
    window after it and a second to spare (the window's last fix and the sample after
    it); the end of ``span_s`` (the IMU's first and last time) when the fixes never move.
    A recording read from its file (:mod:`fuzzynav.realdata.loaders.imu_file`) is held
    only that far for its start."""
    options = StartOptions() if options is None else options
    t0, t_end = span_s
    speed = _speed(gnss)
    moving = (gnss.time_s >= t0) & np.isfinite(speed) & (speed > options.rest_speed_mps)
    if not moving.any():
        return float(t_end)
    window = max(options.window_for(m) for m in ("course", "track", "specific-force"))
    return min(float(t_end), float(gnss.time_s[moving][0]) + window + 1.0)
