"""Plausibility checks of an A-KIT trajectory before any filter sees it.

The parser (:func:`fuzzynav.realdata.loaders.akit_recording.read_table`) refuses what it cannot read; these
checks refuse what reads but is not one trajectory of an AUV: a file too large to be one, a
time column in another unit, origin or clock, an IMU with a gap or ending early, physics no
vehicle has (the IMU checks are :mod:`~fuzzynav.realdata.loaders.checks`', shared with the car's
loader), and -- once the clock map is measured -- files that do not belong together: the
gyros must turn as the reference's attitude does, and the DVL's forward speed must be the
reference's.  Each check blames the file at fault by name, with the column and the named
threshold; the thresholds were set from the eight real trajectories (their values in the
comments) against mismatched pairs of them.
"""
from __future__ import annotations

import numpy as np

from fuzzynav import units
from fuzzynav.errors import InputFileError
from fuzzynav.nav import earth
from fuzzynav.realdata.loaders import akit_timing as timing
from fuzzynav.realdata.loaders.checks import DEFAULT_LIMITS, MAX_IMU_GAP_S, ImuColumns, \
    PhysicsScan

__all__ = ["HELD_COPIES", "NOMINAL_RATE_HZ", "RATE_TOLERANCE", "MAX_START_S",
           "MAX_SPAN_SHORTFALL_S", "MAX_ROTATION_MISFIT_DEG", "MAX_DVL_FORWARD_RMS_MPS",
           "GRAVITY_TOLERANCE", "MAX_RATE_DEVIATION", "PITCH_WINDOW_S",
           "MIN_PITCH_CORRELATION", "MAX_SPEED_MPS", "ALTITUDE_RANGE_M",
           "MAX_TRACK_VELOCITY_RMS_MPS", "AKIT_IMU", "held_bytes_per_row", "timing_of", "imu_of",
           "reference_of", "pitch_correlation", "pitch_sign", "dvl_of", "spans",
           "rotation_misfit_deg", "belong_together", "dvl_forward_rms", "clock_map"]

#: peak memory of loading a file, in copies of its parsed table (float64 rows): the table
#: and what the loader derives from it (the IMU's increments, the clock estimate's attitude
#: track, gyro and misfit table; their temporaries are a block's, ``akit_timing``);
#: measured 2.0 (the peak traced over ``load_trajectory`` grows by 106 B per IMU line from
#: a synthetic 0.5-h file to a 24-h one at 100 Hz with a 1-Hz reference, 113 B a line at
#: 24 h: ``benchmarks/bench_akit_long.py``), 19 before the array steps were made in blocks
HELD_COPIES = 5
#: nominal rates [Hz] of the files (Phins IMU 100 Hz; DVL and reference 1 Hz) and how far
#: the time column may imply another (the 1-Hz streams run 0.25 % slow; a time column in ms,
#: or an IMU clock 5 % off, is far outside)
NOMINAL_RATE_HZ = {"IMU": 100.0, "DVL": 1.0, "GT": 1.0}
RATE_TOLERANCE = 0.01
#: every file's time column starts within this of 0 [s] (each stream was spread over 0-400 s)
MAX_START_S = 5.0
#: the DVL and the reference cover the IMU's span, and the IMU theirs, within this [s]
MAX_SPAN_SHORTFALL_S = 2.0
#: largest RMS misfit between the reference's body rotation over one epoch and the gyros'
#: at the fitted clock map [deg]; the real trajectories give 0.006-0.07, the IMU of another
#: trajectory 6.2-6.5
MAX_ROTATION_MISFIT_DEG = 0.5
#: largest RMS difference of the DVL's forward velocity from the reference's (rotated into
#: the body) [m/s]; the real trajectories give 0.009-0.017, another trajectory's DVL 0.44-0.59
MAX_DVL_FORWARD_RMS_MPS = 0.1
#: accelerometer z mean must be within this of -g (FRD, at sea level) [m/s^2]
GRAVITY_TOLERANCE = 0.5
#: largest plausible |rate - 1| of the reference clock against the IMU (measured: 0.25 %)
MAX_RATE_DEVIATION = 0.01
#: the forward specific force follows +g sin(pitch) over windows of this length [s] (10-s
#: means: a clock offset of up to 2 s hardly matters); the real trajectories correlate
#: 0.90-0.998, their pitch with the sign reversed -0.90 to -0.998
PITCH_WINDOW_S = 10.0
#: a correlation below minus this is a reversed pitch column
MIN_PITCH_CORRELATION = 0.3
#: fastest plausible AUV [m/s]
MAX_SPEED_MPS = 20.0
#: altitude of the reference (minus the depth) [m]: the deepest ocean to a high lake
ALTITUDE_RANGE_M = (-11_000.0, 5_000.0)
#: the reference's positions, differenced over an epoch, must give its velocity within this
#: RMS [m/s]: the real trajectories give 0.026-0.073, their latitude and longitude swapped
#: 2.4-4.1
MAX_TRACK_VELOCITY_RMS_MPS = 0.5

#: the A-KIT IMU's columns, for the shared IMU checks' messages
AKIT_IMU = ImuColumns(acc="ACC X,Y,Z [m/s^2]", gyro="GYRO X,Y,Z [rad/s]", acc_unit="m/s^2",
                      gyro_unit="rad/s", to_g=1.0 / units.G0, other_acc_unit="g",
                      layout="Time [s], ACC X,Y,Z [m/s^2], GYRO X,Y,Z [rad/s]")


def held_bytes_per_row(ncol: int) -> int:
    """Peak memory of loading one row of ``ncol`` columns [bytes] (:data:`HELD_COPIES`): what a
    file's size is judged by (:func:`fuzzynav.realdata.loaders.chunked.counted_lines`)."""
    return 8 * ncol * HELD_COPIES


def timing_of(path, t, kind: str) -> None:
    """The time column: starting near 0, at the file kind's nominal rate, without gaps."""
    if abs(t[0]) > MAX_START_S:
        raise InputFileError(path, "column Time [s]", f"starts at {t[0]:.6g} s; A-KIT files "
                             f"start within {MAX_START_S:g} s of 0 (MAX_START_S): shifted "
                             "to another origin (epoch time?)")
    rate = (t.size - 1) / (t[-1] - t[0])
    nominal = NOMINAL_RATE_HZ[kind]
    off = abs(rate / nominal - 1.0) > RATE_TOLERANCE
    unit = next((u for f, u in ((1e-3, "milliseconds"), (1e3, "microseconds"))
                 if abs(rate / (nominal * f) - 1.0) < RATE_TOLERANCE), None)
    said = (f"implies {rate:.6g} samples/s, the {kind} file's rate is {nominal:g} Hz within "
            f"{RATE_TOLERANCE:.0%} (RATE_TOLERANCE)")
    if off and unit:  # another unit first: its steps would also read as gaps
        raise InputFileError(path, "column Time [s]", f"{said}: {unit}?")
    if kind == "IMU":  # then a gap: it also lowers the mean rate
        gaps = np.diff(t)
        k = int(np.argmax(gaps))
        if gaps[k] > MAX_IMU_GAP_S:
            raise InputFileError(path, f"line {k + 3}, column Time [s]", f"a gap of "
                                 f"{gaps[k]:.3g} s after {t[k]:.6g} s; at most {MAX_IMU_GAP_S:g} s"
                                 " is bridged (max_imu_gap_s)")
    if off:
        raise InputFileError(path, "column Time [s]", f"{said}: seconds on another clock")


def imu_of(path, imu) -> None:
    """Gravity, rates at rest and full scale (the shared checks), then the file's frame:
    forward-right-down, the accelerometer z column reading about -g."""
    scan = PhysicsScan(NOMINAL_RATE_HZ["IMU"])
    step = timing.BLOCK_ELEMENTS  # the columns in g and deg/s a block at a time, not whole
    for a in range(0, imu.shape[0], step):
        rows = imu[a:a + step]
        scan.add(rows[:, 1:4] / units.G0, rows[:, 4:7] / units.DPS,
                 np.arange(a + 2, a + 2 + rows.shape[0]))
    scan.check(path, DEFAULT_LIMITS, AKIT_IMU)
    fz = imu[:, 3].mean()
    if abs(fz + 9.8) > GRAVITY_TOLERANCE:
        raise InputFileError(path, "column ACC Z [m/s^2]",
                             f"mean {fz:.3f} m/s^2: not gravity on a forward-right-down IMU "
                             "(expected about -9.8)")


def reference_of(path, gt) -> None:
    """Positions in radians and metres, attitude in radians, and positions that move as
    the velocity columns say."""
    lon, lat, alt = gt[:, 1], gt[:, 2], gt[:, 3]
    for col, v, lim in (("Latitude [rad]", lat, np.pi / 2), ("Longitude [rad]", lon, np.pi),
                        ("Roll [rad]", gt[:, 7], np.pi), ("Pitch [rad]", gt[:, 8], np.pi / 2),
                        ("Yaw [rad]", gt[:, 9], 2 * np.pi)):
        k = int(np.argmax(np.abs(v)))
        if abs(v[k]) > lim + 1e-9:
            raise InputFileError(path, f"line {k + 2}, column {col}", f"{v[k]:.6g} is beyond "
                                 f"+-{lim:.4g} rad: not radians (degrees?)")
    lo, hi = ALTITUDE_RANGE_M
    k = int(np.argmax(np.abs(alt - 0.5 * (lo + hi))))
    if not lo <= alt[k] <= hi:
        raise InputFileError(path, f"line {k + 2}, column Altitude [m]", f"{alt[k]:.6g} m is "
                             f"outside {lo:g}..{hi:g} m (ALTITUDE_RANGE_M)")
    speed = np.linalg.norm(gt[:, 4:7], axis=1)
    if speed.max() > MAX_SPEED_MPS:
        k = int(np.argmax(speed))
        raise InputFileError(path, f"line {k + 2}, columns V North,East,Down [m/s]",
                             f"speed {speed[k]:.4g} m/s over {MAX_SPEED_MPS:g} (MAX_SPEED_MPS)")
    dt = np.diff(gt[:, 0])
    r_n, r_e = earth.radii(lat[1:])
    north = np.diff(lat) * (r_n + alt[1:]) / dt
    east = np.diff(lon) * (r_e + alt[1:]) * np.cos(lat[1:]) / dt
    v_mid = 0.5 * (gt[1:, 4:6] + gt[:-1, 4:6])
    rms = float(np.sqrt(np.mean((north - v_mid[:, 0]) ** 2 + (east - v_mid[:, 1]) ** 2)))
    if not rms <= MAX_TRACK_VELOCITY_RMS_MPS:
        raise InputFileError(path, "columns Longitude, Latitude [rad]", f"the positions move "
                             f"{rms:.3g} m/s (RMS) away from the V North, V East columns "
                             f"(at most {MAX_TRACK_VELOCITY_RMS_MPS:g}: "
                             "MAX_TRACK_VELOCITY_RMS_MPS): longitude and latitude swapped "
                             "(the top-level files' order?) or in other units")


def pitch_correlation(imu, gt) -> float:
    """Correlation of :data:`PITCH_WINDOW_S` means of the forward specific force (the IMU
    file's ACC X) with g sin(pitch) of the reference (NaN when the pitch hardly varies)."""
    lo, hi = max(imu[0, 0], gt[0, 0]), min(imu[-1, 0], gt[-1, 0])
    edges = np.arange(lo, hi + 1e-9, PITCH_WINDOW_S)
    if edges.size < 6:
        return float("nan")
    f = _window_means(imu[:, 0], imu[:, 1], edges)
    p = _window_means(gt[:, 0], units.G0 * np.sin(gt[:, 8]), edges)
    ok = np.isfinite(f) & np.isfinite(p)
    if ok.sum() < 5 or np.std(p[ok]) < 1e-3 * units.G0:
        return float("nan")
    return float(np.corrcoef(f[ok], p[ok])[0, 1])


def _window_means(t, v, edges) -> np.ndarray:
    """Means of ``v`` over the samples with ``edges[i] <= t < edges[i + 1]`` (NaN where
    none): ``t`` increases, so each window is a slice, found by bisection (a mask per
    window would cost windows x samples, hours on a day's IMU)."""
    i = np.searchsorted(t, edges, side="left")
    return np.array([v[a:b].mean() if b > a else np.nan
                     for a, b in zip(i[:-1].tolist(), i[1:].tolist())])


def pitch_sign(path, imu, gt) -> None:
    """Refuse a reference whose pitch has the other sign than the IMU sees (the top-level
    GT files' convention copied into ``corrected/``)."""
    c = pitch_correlation(imu, gt)
    if c < -MIN_PITCH_CORRELATION:
        raise InputFileError(path, "column Pitch [rad]", f"the forward specific force follows "
                             f"-g sin(pitch) (correlation {c:.2f} of {PITCH_WINDOW_S:g}-s "
                             "means): the pitch has the reversed sign of the top-level GT "
                             "files; corrected/ files give the sign the IMU sees")


def dvl_of(path, dvl) -> None:
    """A DVL that measured something, at a speed an AUV can have."""
    speed = np.linalg.norm(dvl[:, 1:4], axis=1)
    if not np.any(speed > 0.0):
        raise InputFileError(path, "columns DVL X,Y,Z [m/s]", "every velocity is zero: no "
                             "bottom lock was recorded")
    k = int(np.argmax(speed))
    if speed[k] > MAX_SPEED_MPS:
        raise InputFileError(path, f"line {k + 2}, columns DVL X,Y,Z [m/s]", f"speed "
                             f"{speed[k]:.4g} m/s over {MAX_SPEED_MPS:g} (MAX_SPEED_MPS)")


def spans(files, imu_t, dvl_t, gt_t) -> None:
    """The DVL and the reference cover the IMU, and the IMU covers the reference."""
    slack = MAX_SPAN_SHORTFALL_S
    if imu_t[-1] < gt_t[-1] - slack:
        raise InputFileError(files["imu"], "column Time [s]", (
            f"ends at {imu_t[-1]:.1f} s, the reference at {gt_t[-1]:.1f} s and the DVL at "
            f"{dvl_t[-1]:.1f} s: the IMU file is cut short"))
    for name, t in (("dvl", dvl_t), ("reference", gt_t)):
        if t[0] > imu_t[0] + slack or t[-1] < imu_t[-1] - slack:
            raise InputFileError(files[name], "column Time [s]", (
                f"covers {t[0]:.1f}-{t[-1]:.1f} s, the IMU {imu_t[0]:.1f}-{imu_t[-1]:.1f} s "
                "(a truncated file?)"))


def rotation_misfit_deg(inc, gt, q_ref, clock) -> float:
    """RMS misfit [deg] between the reference's body rotation over each epoch and the
    gyros' over the same interval on the IMU clock."""
    t_ref = clock.to_imu(gt[:, 0])
    track = timing.GyroTrack(inc.time_s, inc.dtheta_b, t_ref, q_ref, float(np.median(gt[:, 2])))
    misfit, _ = timing.epoch_misfits(track, t_ref, q_ref, np.zeros(1))
    return float(np.rad2deg(np.sqrt(np.mean(misfit[0]))))


def belong_together(files, rotation_deg: float, dvl_forward_rms: float,
                    clock_measured: bool = True) -> None:
    """Stop when the three files are not one trajectory, blaming the odd one out: the IMU
    when only the gyros disagree with the reference, the DVL when only it does, the
    reference when both do.  ``clock_measured``: whether the clock map was found inside
    its search (:meth:`~.akit_timing.ClockSearch.inside`); when not, the gyros' misfit may
    be the stamps' offset instead, and the message says so."""
    gyros_ok = rotation_deg <= MAX_ROTATION_MISFIT_DEG
    dvl_ok = dvl_forward_rms <= MAX_DVL_FORWARD_RMS_MPS
    if gyros_ok and dvl_ok:
        return
    gyro_said = (f"the gyros turn {rotation_deg:.3g} deg (RMS per epoch) away from the "
                 f"reference's attitude (at most {MAX_ROTATION_MISFIT_DEG:g}: "
                 "MAX_ROTATION_MISFIT_DEG)")
    if not clock_measured:
        gyro_said += (" along a clock map found at the edge of its search (offsets "
                      f"+-{timing.MAX_OFFSET_S:g} s about zero at the start: MAX_OFFSET_S; "
                      "are the reference's stamps further off the IMU's?)")
    dvl_said = (f"the DVL's forward velocity is {dvl_forward_rms:.3g} m/s (RMS) away from the "
                f"reference's (at most {MAX_DVL_FORWARD_RMS_MPS:g}: MAX_DVL_FORWARD_RMS_MPS)")
    if not gyros_ok and not dvl_ok:
        raise InputFileError(files["reference"], "", f"does not belong with the IMU and DVL "
                             f"files: {gyro_said}, and {dvl_said} (another trajectory's "
                             "reference?)")
    if not gyros_ok:
        raise InputFileError(files["imu"], "columns GYRO X,Y,Z [rad/s]", f"{gyro_said}, while "
                             "the DVL agrees with the reference: another trajectory's IMU, "
                             "or swapped or mis-scaled axes")
    raise InputFileError(files["dvl"], "columns DVL X,Y,Z [m/s]", f"{dvl_said}, while the "
                         "gyros agree with it: another trajectory's DVL, or swapped axes")


def dvl_forward_rms(dvl, gt, clock, reference_on_imu_clock, body_velocity) -> float:
    """RMS [m/s] of the DVL's forward velocity minus the reference's in the body, at the DVL's
    times on the IMU clock."""
    ref = reference_on_imu_clock(gt, clock, clock.to_imu(dvl[:, 0], clock.dvl_offset_s))
    fwd = dvl[:, 1] - body_velocity(ref)[:, 1]
    return float(np.sqrt(np.mean(fwd ** 2)))



def clock_map(files, clock, search, labels) -> None:
    """Stop when the clock map is not a measurement: an offset at the edge of the offsets
    searched (``search``, :class:`~.akit_timing.ClockSearch`: the gyros and the reference
    never line up within them) at any of the reference's stamps ``labels``, or an
    implausible rate."""
    edge = timing.MAX_OFFSET_S - timing.SEARCH_EDGE_S
    if not (search.inside(clock, labels) and abs(clock.rate - 1.0) < MAX_RATE_DEVIATION):
        gap, centre = search.from_centre(clock, labels)
        k = int(np.argmax(np.abs(gap - centre)))
        raise InputFileError(files["reference"], "column Time [s]", (
            f"does not line up with the IMU's gyros (offset {gap[k]:+.2f} s at stamp "
            f"{labels[k]:.1f} s, rate {clock.rate:.4f}; plausible: within {edge:.2f} s of "
            f"the offset searched about there ({centre[k]:+.2f} s), rate within "
            f"{MAX_RATE_DEVIATION:.0%} of 1): wrong trajectory pair or damaged time stamps"))
    if not abs(clock.dvl_offset_s) < edge:
        raise InputFileError(files["dvl"], "column Time [s]", (
            f"its velocity does not line up with the reference's (offset "
            f"{clock.dvl_offset_s:+.2f} s at the edge of the +-{timing.MAX_OFFSET_S:.0f} s "
            "search)"))
