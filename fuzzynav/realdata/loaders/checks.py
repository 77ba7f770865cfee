"""Plausibility checks a recording must pass before any filter sees it.

A parser refuses what it cannot read (a field that is not a number, a record that is cut);
these checks refuse what reads but cannot be a recording of a vehicle: sample clocks that
are not milliseconds, ticks that jump by days, a time tag that does not describe its CSV,
GNSS from another week, no RTK-fixed epoch, no gravity on the accelerometers.  Each raises
one :class:`~fuzzynav.errors.InputFileError` naming the file, the column (or line, record)
and what was wrong; a filter never runs on data that failed.

The thresholds are the module constants below, gathered in :class:`Limits`; pass another
``Limits`` to :func:`fuzzynav.realdata.loaders.rtklib.load_rtklib` for an unusual sensor.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fuzzynav import units
from fuzzynav.errors import InputFileError

__all__ = ["IMU_RATE_RANGE_HZ", "MAX_IMU_GAP_S", "MIN_IMU_SAMPLES", "CLOCK_RATE_TOLERANCE",
           "MAX_STRETCH_S", "GRAVITY_BAND", "GYRO_REST_MAX_RPS", "GYRO_MAX_RPS",
           "ACCEL_MAX_MPS2", "GYRO_COURSE_GAIN_RANGE", "REST_BLOCK_S", "MIN_FIXED_EPOCHS",
           "MIN_OVERLAP_FRACTION", "Limits", "DEFAULT_LIMITS", "imu_ticks", "clock_rate",
           "ImuColumns", "PhysicsScan", "imu_physics", "gyro_scale", "gnss_overlap"]

#: plausible IMU sample rates [Hz]: MEMS and FOG IMUs log at 1 Hz (slow AHRS) to 2 kHz
IMU_RATE_RANGE_HZ = (1.0, 2000.0)
#: longest gap between consecutive IMU samples that is bridged (rates interpolated) [s];
#: a longer gap is a logging fault (a tick jumping by days would need millions of samples)
MAX_IMU_GAP_S = 1.0
#: fewest IMU samples a recording must hold (a clock fit and a rest need some)
MIN_IMU_SAMPLES = 100
#: the IMU clock, measured against the logging PC (tag fit) or implied by stretching the
#: samples over the tag (fallback), must run at its ticks' rate within this fraction.
#: Crystal clocks are off by ppm (the rtklib-drive's IMU by 13 ppm); the stretch fallback
#: also absorbs the first sample's arrival latency (0.15 s: 0.03 % of the drive, 0.5 % of
#: 30 s).  Ticks in another unit than ms fail this by far.
CLOCK_RATE_TOLERANCE = 0.01
#: the stretch fallback (a tag whose byte counts do not fit the CSV) puts the first sample at
#: the tag's start and the last at its last record: the tag may outlast the samples by the
#: arrival latency (0.15 s on the drive), not more than this [s]; a longer tag means a cut
#: CSV (or a tag of another file), and stretching would misplace the samples by that much
MAX_STRETCH_S = 0.5
#: |specific force| at rest / standard gravity: Earth's gravity is 0.997-1.003 g at the
#: surface; consumer accelerometers add a few % of scale and bias (the drive reads 1.014 g)
GRAVITY_BAND = (0.9, 1.1)
#: largest |angular rate| at rest [rad/s]: earth rate plus a MEMS turn-on bias (< 1 deg/s;
#: the drive has 0.18 deg/s) is far below this 5.7 deg/s
GYRO_REST_MAX_RPS = 0.1
#: largest |angular rate| ever [rad/s]: 2000 deg/s, the full scale of common MEMS gyros
GYRO_MAX_RPS = 35.0
#: largest |specific force| ever [m/s^2]: 32 g, twice the widest common MEMS full scale
ACCEL_MAX_MPS2 = 32.0 * units.G0
#: while driving, the gyro heading must turn as the GNSS course does, by a factor within
#: this range (1 when right; gyros in rad/s read as deg/s turn 57 times too little)
GYRO_COURSE_GAIN_RANGE = (0.5, 2.0)
#: length of the blocks in which the quietest stretch (the rest) is looked for [s]
REST_BLOCK_S = 1.0
#: fewest RTK-fixed (Q = 1) epochs within the IMU's span (the reference and the fed stream)
MIN_FIXED_EPOCHS = 10
#: fraction of the IMU span the fixed epochs must cover (first to last)
MIN_OVERLAP_FRACTION = 0.5


@dataclass(frozen=True)
class Limits:
    """Thresholds of the checks (defaults: the module constants, which say why)."""

    imu_rate_range_hz: tuple = IMU_RATE_RANGE_HZ
    max_imu_gap_s: float = MAX_IMU_GAP_S
    min_imu_samples: int = MIN_IMU_SAMPLES
    clock_rate_tolerance: float = CLOCK_RATE_TOLERANCE
    max_stretch_s: float = MAX_STRETCH_S
    gravity_band: tuple = GRAVITY_BAND
    gyro_rest_max_rps: float = GYRO_REST_MAX_RPS
    gyro_max_rps: float = GYRO_MAX_RPS
    accel_max_mps2: float = ACCEL_MAX_MPS2
    gyro_course_gain_range: tuple = GYRO_COURSE_GAIN_RANGE
    min_fixed_epochs: int = MIN_FIXED_EPOCHS
    min_overlap_fraction: float = MIN_OVERLAP_FRACTION


DEFAULT_LIMITS = Limits()
_UNIT_HINTS = ((1e3, "seconds"), (1e-3, "microseconds"))


# -- the IMU sample clock ------------------------------------------------------------------
def imu_ticks(path, tick_ms, lineno, limits: Limits = DEFAULT_LIMITS) -> float:
    """Check the tick column of an IMU file; return the nominal sample rate [Hz].

    Parameters
    ----------
    path : path-like
        The IMU file (for the message).
    tick_ms : ndarray, shape (K,)
        Increasing ticks [ms].
    lineno : ndarray of int, shape (K,)
        1-based line of each sample in the file.

    Raises
    ------
    InputFileError
        Too few samples, a rate outside ``imu_rate_range_hz`` (ticks in another unit), or a
        gap longer than ``max_imu_gap_s``.
    """
    tick = np.asarray(tick_ms, dtype=float)
    if tick.size < limits.min_imu_samples:
        raise InputFileError(path, "lines", f"{tick.size} complete sample lines; a recording "
                             f"needs at least {limits.min_imu_samples} (min_imu_samples)")
    step = np.diff(tick)
    rate = 1000.0 / float(np.median(step))
    lo, hi = limits.imu_rate_range_hz
    if not lo <= rate <= hi:
        hint = ""
        for factor, unit in _UNIT_HINTS:
            if lo <= rate / factor <= hi:
                hint = f"; are the ticks in {unit}? they must be milliseconds"
        raise InputFileError(path, "column tick", f"median step {1000.0 / rate:.6g} ms implies "
                             f"a {rate:.6g}-Hz IMU, outside {lo:g}-{hi:g} Hz{hint}")
    k = int(np.argmax(step))
    if step[k] > limits.max_imu_gap_s * 1000.0:
        raise InputFileError(path, f"line {lineno[k + 1]}, column tick",
                             f"jumps by {step[k] / 1000.0:.6g} s (from {tick[k]:.0f} to "
                             f"{tick[k + 1]:.0f} ms); bridging it would need "
                             f"{step[k] / 1000.0 * rate:.3g} samples (gaps over "
                             f"{limits.max_imu_gap_s:g} s are refused: max_imu_gap_s)")
    return rate


def clock_rate(csv_path, tag_path, tag, method: str, rate: float, csv_bytes: int, n_lines: int,
               samples_s: float, limits: Limits = DEFAULT_LIMITS) -> None:
    """Check the IMU clock rate found by the time alignment (PC ms per IMU ms).

    With the stretch fallback, also how far the stretch moves the samples
    (``max_stretch_s``); the message then names the file that is short.

    Parameters
    ----------
    csv_path, tag_path : path-like
        The IMU file and its time tag (for the message).
    tag : fuzzynav.realdata.loaders.timetag.TimeTag
    method : str
        ``"tag-fit"`` or ``"endpoints"`` (the stretch fallback).
    rate : float
        The clock rate the alignment found or implied.
    csv_bytes, n_lines : int
        Size [bytes] and line count of the CSV as stored.
    samples_s : float
        Span of the samples on their own clock [s].
    """
    tol = limits.clock_rate_tolerance
    allowed = f"(allowed 1 ± {tol:g}: clock_rate_tolerance)"
    if method == "tag-fit":
        if abs(rate - 1.0) > tol:
            raise InputFileError(csv_path, "column tick", f"against the logging PC's clock (the"
                                 f" tag) the ticks run at {1.0 / rate:.6g} times real time "
                                 f"{allowed}; ticks must be milliseconds")
        return
    excess_s = tag.duration_s - samples_s
    if abs(rate - 1.0) <= tol and abs(excess_s) <= limits.max_stretch_s:
        return
    stretch = (f"stretching the samples over the tag would move them by {excess_s:.3g} s "
               f"(allowed {limits.max_stretch_s:g} s: max_stretch_s) and imply an IMU clock "
               f"{rate:.6g} times its ticks' rate {allowed}")
    logged = int(tag.fpos[-1])
    if logged > csv_bytes + n_lines:            # shorter even with every CR LF restored
        raise InputFileError(csv_path, f"line {n_lines} (end of file)",
                             f"the file holds {csv_bytes} bytes ({samples_s:.1f} s of samples) "
                             f"but its tag logged {logged} bytes over {tag.duration_s:.1f} s: "
                             f"the CSV is truncated; {stretch}")
    raise InputFileError(tag_path, f"record {tag.fpos.size}",
                         f"the last record counts {logged} bytes at {tag.duration_s:.1f} s but "
                         f"{Path(csv_path).name} holds {csv_bytes} bytes ({samples_s:.1f} s of "
                         f"samples): the tag is truncated or belongs to another file; {stretch}")


# -- physics ------------------------------------------------------------------------------------
def _block_stats(acc_g, gyro_dps, n: int) -> np.ndarray:
    """Per block of ``n`` rows: the spread of |f| and the mean specific force [g] and angular
    rate [deg/s] vectors, (k, 7); the rows must be whole blocks."""
    k = acc_g.shape[0] // n
    acc = acc_g[:k * n].reshape(k, n, 3)
    gyro = gyro_dps[:k * n].reshape(k, n, 3)
    return np.column_stack([np.linalg.norm(acc, axis=2).std(axis=1), acc.mean(axis=1),
                            gyro.mean(axis=1)])


def _rest(stats):
    """Mean specific force [g] and angular rate [deg/s] over the quietest blocks.

    The blocks whose |f| varies least (a tenth of them, at least one) are taken as rest: a
    car at a standstill, or at worst cruising smoothly, where |f| is still gravity.
    """
    quiet = np.argsort(stats[:, 0])[:max(1, stats.shape[0] // 10)]
    f = float(np.median(np.linalg.norm(stats[quiet, 1:4], axis=1)))
    w = float(np.median(np.linalg.norm(stats[quiet, 4:7], axis=1)))
    return f, w


class PhysicsScan:
    """What :func:`imu_physics` checks, gathered over consecutive blocks of rows (a file
    read a block at a time): the rest statistics of each :data:`REST_BLOCK_S` block and
    the largest magnitudes with their lines.  One block of every row is the whole check.

    Parameters
    ----------
    rate_hz : float
        Nominal sample rate (sets the rest block's length in rows).
    """

    def __init__(self, rate_hz: float):
        self.n = max(1, int(round(REST_BLOCK_S * rate_hz)))
        self.stats, self.left = [], None  # rows not yet in a whole block
        self.biggest = {}  # "gyro"/"acc" -> (magnitude, line)

    def add(self, acc_g, gyro_dps, lineno) -> None:
        """The next rows: accelerometer [g], gyro [deg/s] (K, 3), their 1-based lines."""
        # an absurd value (1e300) overflows to inf here, which the check then names: numpy's
        # warnings about it would only come before that one line
        with np.errstate(over="ignore", invalid="ignore"):
            self._add(acc_g, gyro_dps, lineno)

    def _add(self, acc_g, gyro_dps, lineno) -> None:
        for name, data, scale in (("gyro", gyro_dps, units.DPS), ("acc", acc_g, units.G0)):
            mag = np.linalg.norm(data, axis=1) * scale
            k = int(np.argmax(mag))
            if name not in self.biggest or mag[k] > self.biggest[name][0]:
                self.biggest[name] = (float(mag[k]), int(lineno[k]))
        if self.left is not None:  # the rows short of a whole block, carried
            acc_g = np.concatenate([self.left[0], acc_g])
            gyro_dps = np.concatenate([self.left[1], gyro_dps])
        whole = acc_g.shape[0] // self.n * self.n
        if whole:
            self.stats.append(_block_stats(acc_g[:whole], gyro_dps[:whole], self.n))
        self.left = (acc_g[whole:], gyro_dps[whole:])

    def rest(self):
        """:func:`_rest` of the blocks (a file shorter than a block is one block)."""
        if self.stats:
            return _rest(np.concatenate(self.stats))
        acc, gyro = self.left
        return _rest(_block_stats(acc, gyro, acc.shape[0]))

    def check(self, path, limits: Limits = DEFAULT_LIMITS, cols=None) -> None:
        """Raise the first failure (:func:`imu_physics`)."""
        cols = ImuColumns() if cols is None else cols
        f_g, w_dps = self.rest()
        _gravity(path, f_g, w_dps, limits, cols)
        if w_dps * units.DPS > limits.gyro_rest_max_rps:
            raise InputFileError(path, f"columns {cols.gyro}", f"at rest they read {w_dps:.4g}"
                                 f" deg/s, over {np.rad2deg(limits.gyro_rest_max_rps):.3g} "
                                 f"deg/s (gyro_rest_max_rps): not {cols.gyro_unit}, or not "
                                 "a gyro")
        for label, name, limit, unit, key in (
                (cols.gyro, "gyro", limits.gyro_max_rps, "rad/s", "gyro_max_rps"),
                (cols.acc, "acc", limits.accel_max_mps2, "m/s^2", "accel_max_mps2")):
            mag, line = self.biggest[name]
            if mag > limit:
                raise InputFileError(path, f"line {line}, columns {label}",
                                     f"magnitude {mag:.4g} {unit} exceeds {limit:.4g} {unit} "
                                     f"({key})")


@dataclass(frozen=True)
class ImuColumns:
    """How an IMU file names and scales its columns, for the messages of :func:`imu_physics`:
    the column labels, the file's units, the factor from the file's accelerometer unit to g
    and the unit a wrong file would most likely hold instead."""

    acc: str = "acc x,y,z"
    gyro: str = "gyro x,y,z"
    acc_unit: str = "g"
    gyro_unit: str = "deg/s"
    to_g: float = 1.0
    other_acc_unit: str = "m/s^2"
    layout: str = "acc x,y,z [g], gyro x,y,z [deg/s], tick"


def _gravity(path, f_g, w_dps, limits, cols: ImuColumns):
    lo, hi = limits.gravity_band
    if lo <= f_g <= hi:
        return
    where = f"columns {cols.acc}"
    said = (f"at rest they read |f| = {f_g * units.G0:.4g} m/s^2 ({f_g:.4g} g), expected "
            f"gravity, {lo:g}-{hi:g} g (gravity_band)")
    if f_g < 0.5 * lo and lo <= w_dps <= hi and cols.gyro_unit == "deg/s":
        raise InputFileError(path, where, f"{said}, while the gyro columns read {w_dps:.4g} as "
                             "if they held gravity in g: the accelerometer and gyro columns "
                             f"are swapped (expected {cols.layout})")
    # the file's numbers read in the other unit (m/s^2 for g, g for m/s^2) would be gravity
    other = units.G0 if cols.to_g == 1.0 else 1.0 / units.G0
    if lo <= f_g / other <= hi:
        raise InputFileError(path, where, f"{said}: the values look like {cols.other_acc_unit};"
                                          f" the file must hold {cols.acc_unit}")
    raise InputFileError(path, where, said)


def imu_physics(path, acc_g, gyro_dps, lineno, rate_hz, limits: Limits = DEFAULT_LIMITS,
                cols: ImuColumns = ImuColumns()):
    """Check that the IMU columns hold an IMU in the file's units (g, deg/s).

    Gravity at rest on the accelerometers (and not on the gyros: swapped columns), a small
    angular rate at rest, and no sample beyond the full scale of any common IMU.

    Parameters
    ----------
    path : path-like
    acc_g, gyro_dps : ndarray, shape (K, 3)
        The accelerometer [g] and gyro [deg/s] columns.
    lineno : ndarray of int, shape (K,)
        1-based line of each sample.
    rate_hz : float
        Nominal sample rate.
    cols : ImuColumns, optional
        The file's column labels and units (default: the rtklib logger's, g and deg/s), for
        the messages; the data come in g and deg/s whatever the file holds.
    """
    scan = PhysicsScan(rate_hz)
    scan.add(acc_g, gyro_dps, lineno)
    scan.check(path, limits, cols)


def gyro_scale(path, imu, fixes, limits: Limits = DEFAULT_LIMITS) -> None:
    """Check that the gyros turn as the GNSS course does while driving (their unit, scale).

    Skipped when the recording does not move and turn enough to tell
    (:func:`fuzzynav.realdata.loaders.sync.gyro_course_gain`).

    Parameters
    ----------
    path : path-like
        The IMU file.
    imu : ImuData
        The loaded increments.
    fixes : SensorData
        The RTK-fixed epochs.
    """
    from fuzzynav.realdata.loaders.sync import gyro_course_gain

    gain = gyro_course_gain(imu, fixes)
    lo, hi = limits.gyro_course_gain_range
    if gain is None or lo <= gain <= hi:
        return
    hint = ("; are the gyros in rad/s? the file must hold deg/s"
            if abs(gain * units.DPS - 1.0) < 0.5 else "")
    raise InputFileError(path, "columns gyro x,y,z", f"while driving, the GNSS course turns "
                         f"{gain:.4g} times as much as the heading the gyros integrate "
                         f"(allowed {lo:g}-{hi:g}: gyro_course_gain_range){hint}")


# -- GNSS ---------------------------------------------------------------------------------------
def _gpst(t_s: float) -> str:
    whole = int(np.floor(t_s))
    return time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime(whole)) + f".{int((t_s - whole) * 10)}"


def gnss_overlap(path, t_gpst_s, q, imu_gpst_s, limits: Limits = DEFAULT_LIMITS) -> None:
    """Check that the solution's RTK-fixed epochs cover the IMU's time span.

    Parameters
    ----------
    path : path-like
        The solution file.
    t_gpst_s : ndarray, shape (N,)
        Epochs [GPST seconds since 1970].
    q : ndarray, shape (N,)
        RTKLIB quality flags (1 = fixed).
    imu_gpst_s : (float, float)
        First and last IMU instant [GPST seconds since 1970].
    """
    lo, hi = imu_gpst_s
    inside = (t_gpst_s >= lo) & (t_gpst_s <= hi)
    imu = f"the IMU runs {_gpst(lo)} to {_gpst(hi)} GPST"
    if not inside.any():
        raise InputFileError(path, "column GPST", f"no epoch within the IMU's time span ({imu};"
                             f" the solutions {_gpst(t_gpst_s[0])} to {_gpst(t_gpst_s[-1])}): "
                             "the files are not of the same recording")
    fixed = inside & (q == 1)
    n = int(fixed.sum())
    if n < limits.min_fixed_epochs:
        found = ", ".join(f"Q={int(v)}: {int(c)}"
                          for v, c in zip(*np.unique(q[inside], return_counts=True)))
        raise InputFileError(path, "column Q", f"{n} RTK-fixed epochs (Q = 1) within the IMU's "
                             f"time span ({found}); the reference needs at least "
                             f"{limits.min_fixed_epochs} (min_fixed_epochs)")
    covered = (t_gpst_s[fixed][-1] - t_gpst_s[fixed][0]) / (hi - lo)
    if covered < limits.min_overlap_fraction:
        raise InputFileError(path, "column GPST", f"the fixed epochs cover {covered:.1%} of the "
                             f"IMU's span ({imu}; fixed from {_gpst(t_gpst_s[fixed][0])} to "
                             f"{_gpst(t_gpst_s[fixed][-1])}); at least "
                             f"{limits.min_overlap_fraction:.0%} needed (min_overlap_fraction); "
                             "keep the overlap with span_s / --span")
