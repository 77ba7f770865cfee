"""Loader for RTKLIB-logged car recordings: ``imu_*.csv`` + ``.tag`` and ``gnss_*.pos``.

The directory holds (the ``rtklib-drive`` recording of rtklibexplorer/GNSS_IMU is one):

* ``imu_<id>.csv`` — no header; ``acc x, y, z [g], gyro x, y, z [deg/s], tick [ms since IMU
  power-up]``; the first and the last line may be cut (logging started or stopped inside
  them): the first line is always dropped, the last unless the file ends with a newline;
* ``imu_<id>.csv.tag`` — RTKLIB time tags of the CSV (:mod:`.timetag`);
* ``gnss_<id>*.pos`` — the RTKLIB solution (:mod:`.rtkpos`), GPST;
* optionally ``mounting.toml`` (:mod:`.mounting`).

Time alignment (IMU tick -> GPST):

1. the IMU's own ticks are regularised into its sample clock (:mod:`.increments`);
2. each CSV line is matched to the tag record by which the logger had written it (the tag
   counts bytes as logged; CR LF line ends turned into LF by a copy are detected), giving
   its arrival time on the logging PC's clock;
3. a straight line through arrival versus sample clock gives the clock rate and the mean
   arrival latency: ``t = start + (a + b x) / 1000 - imu_delay_s``, ``x`` the sample clock
   [ms] since the first kept line, ``start`` the GPST of the tag file;
4. ``imu_delay_s`` is what remains between a sample and the fitted arrival (buffering,
   the PC clock's offset from GPST).  Its default, :data:`DEFAULT_IMU_DELAY_S`, was
   measured on the rtklib-drive by matching the gyro yaw rate to the GNSS course rate
   (:func:`fuzzynav.realdata.loaders.sync.course_rate_lag`; ``docs/data.md``).

If the tag's byte counts do not fit the CSV (another copy of the file), the source's
method is used instead: the sample clock is stretched onto ``[start, start + last tick]``.

Times in the returned :class:`Recording` are seconds since ``epoch_gpst_s`` (a whole GPST
second just before the first IMU sample, counted from 1970 in the GPS time scale).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from fuzzynav.errors import DataMissingError, FuzzynavError, InputFileError
from fuzzynav.sim.imu import ImuData
from fuzzynav.realdata.loaders import checks, increments, timetag
from fuzzynav.realdata.loaders.chunked import DEFAULT_CHUNK_ROWS
from fuzzynav.realdata.loaders.imu_csv import parsed_blocks, read_imu_csv
from fuzzynav.realdata.loaders.imu_file import SCAN_BYTES_PER_LINE, ImuFile, RowTimes, \
    body_rates
from fuzzynav.realdata.loaders.mounting import Mounting
from fuzzynav.realdata.loaders.recording_files import find_files
from fuzzynav.realdata.loaders.rtkpos import read_pos
from fuzzynav.sim.sensors import SensorData
from fuzzynav.realdata.start_options import StartOptions

__all__ = ["STREAMED_HINT", "DEFAULT_IMU_DELAY_S", "MAX_IMU_DELAY_S", "TimeAlignment",
           "Recording", "read_imu_csv", "align_time", "load_rtklib"]

#: how a recording too long to hold is read instead (the end of the held load's refusal)
STREAMED_HINT = ("load it streamed, its IMU read from the file chunk by chunk "
                 "(load_rtklib(streamed=True); fuzzynav run --data ... --output-rate HZ or "
                 "--chunk S)")
#: sample-to-fitted-arrival delay of the rtklib-drive IMU [s] (see the module docstring)
DEFAULT_IMU_DELAY_S = 0.21
#: largest IMU delay accepted either way [s]: a logger's buffering is milliseconds to a
#: fraction of a second; seconds would be a clock error, which the tag fit measures
MAX_IMU_DELAY_S = 10.0


@dataclass(frozen=True)
class TimeAlignment:
    """How IMU ticks were put on GPST.

    Attributes
    ----------
    method : str
        ``"tag-fit"`` (line arrival times fitted) or ``"endpoints"`` (the stretch fallback).
    clock_rate : float
        Logging-PC milliseconds per IMU-clock millisecond.
    latency_ms : float
        Fitted arrival of the first kept sample after the tag start [ms].
    resid_sd_ms : float
        Robust spread of the arrivals about the fitted line [ms].
    imu_delay_s : float
        Delay subtracted from the fitted arrival [s].
    crlf_restored : bool
        Whether the CSV copy had lost the CR of CR LF line ends.
    clock : increments.SampleClock
        The regularised IMU sample clock.
    """

    method: str
    clock_rate: float
    latency_ms: float
    resid_sd_ms: float
    imu_delay_s: float
    crlf_restored: bool
    clock: increments.SampleClock


@dataclass(frozen=True)
class Recording:
    """A loaded car recording.

    Attributes
    ----------
    directory : Path
    files : dict
        ``imu``, ``tag``, ``pos`` (and ``mounting`` if read) -> Path.
    epoch_gpst_s : int
        GPST (seconds since 1970, GPS scale) of ``t = 0``.
    imu : ImuData or ImuFile
        Increments in the body frame (the IMU frame without a mounting); an
        :class:`~.imu_file.ImuFile` (read from the file when asked) if loaded ``streamed``.
    gnss : SensorData
        All fixes in the IMU's time span, kind ``gnss``, RTKLIB sigmas; ``meta``: ``q``,
        ``ns``, ``ratio``, ``age_s``, ``lever_arm_b``.
    reference : SensorData
        The untouched RTK-fixed (Q = 1) epochs, for scoring.
    mounting : Mounting or None
    timing : TimeAlignment
    start_options : StartOptions
        How the initial state is found (rest, heading method, speeds, windows; the lever
        arm, if given, is already in ``gnss.meta``).
    """

    directory: Path
    files: dict
    epoch_gpst_s: int
    imu: ImuData
    gnss: SensorData
    reference: SensorData
    mounting: Mounting | None
    timing: TimeAlignment
    start_options: StartOptions = StartOptions()

    def initial_state(self, heading_rad=None, **kw):
        """Initial state from the data (:func:`fuzzynav.realdata.coarse_align.initial_state`).

        The heading comes from the GNSS course when a mounting says where forward is, else
        from matching the specific force to the GNSS velocity changes.
        """
        from fuzzynav.realdata.coarse_align import initial_state

        return initial_state(self.imu, self.gnss, heading_rad=heading_rad,
                             forward_known=self.mounting is not None,
                             options=self.start_options, **kw)


# -- time alignment -----------------------------------------------------------------------------
def align_time(tag, clock, matched, imu_delay_s):
    """GPST offset [s] from tag start of every kept sample, and the :class:`TimeAlignment`.

    ``matched`` is :func:`~.timetag.kept_arrivals`' result (``None``: the tag does not fit
    the file, the samples are stretched over it).  The fit is a load's peak of memory (a
    recording of a day has millions of points): no copy is made that it does not need.
    """
    x_ms = clock.time_ms - clock.time_ms[0]
    if matched is not None:
        arrival, crlf = matched
        ok = arrival >= 0
        # all arrived (the usual case): the arrays whole, the same numbers as selected
        x, y = (x_ms, arrival) if ok.all() else (x_ms[ok], arrival[ok])
        del ok
        a, b, sd, _ = timetag.fit_clock(x, y)
        del x, y
        method = "tag-fit"
    else:
        a, b, sd, crlf, method = 0.0, float(tag.tick_ms[-1]) / x_ms[-1], float("nan"), \
            False, "endpoints"
    offset_s = (a + b * x_ms) / 1000.0 - imu_delay_s
    return offset_s, TimeAlignment(method=method, clock_rate=float(b), latency_ms=float(a),
                                   resid_sd_ms=float(sd), imu_delay_s=float(imu_delay_s),
                                   crlf_restored=bool(crlf), clock=clock)


# -- assembly -----------------------------------------------------------------------------------
def _resolve_mounting(mounting, directory: Path, files: dict):
    if isinstance(mounting, str) and mounting == "auto":
        path = directory / "mounting.toml"
        if not path.is_file():
            return None
        files["mounting"] = path
        return Mounting.from_toml(path)
    if mounting is None or isinstance(mounting, Mounting):
        return mounting
    files["mounting"] = Path(mounting)
    if not files["mounting"].is_file():
        raise DataMissingError(f"{mounting}: mounting file not found")
    return Mounting.from_toml(mounting)


def _rates_of(data, mounting):
    """``rates(a, b)``: gyro [rad/s] and accelerometer [m/s^2] rates of rows ``a .. b-1``,
    in the body frame."""
    c = None if mounting is None else mounting.matrix
    return lambda a, b: body_rates(data[a:b], c)


def _bounds_of(t_s, resample_hz, span):
    """The increments' boundaries inside the span: the samples, or a grid of ``resample_hz``."""
    lo, hi = max(t_s[0], span[0]), min(t_s[-1], span[1])
    if resample_hz is None:
        bounds = t_s[(t_s >= lo) & (t_s <= hi)]
    else:
        bounds = increments.grid_bounds(lo, hi, resample_hz)
    if bounds.size < 2:
        raise InputFileError(None, "span_s", f"leaves no IMU data (IMU covers {t_s[0]:.3f} "
                                             f"to {t_s[-1]:.3f} s)")
    return bounds


def _imu_data(data, t_s, mounting, resample_hz, span, block_rows=None):
    """Increments in the body frame between the chosen boundaries (the rates made and
    integrated ``block_rows`` samples at a time: :func:`~.increments.integrate_rates`)."""
    bounds = _bounds_of(t_s, resample_hz, span)
    inc = increments.integrate_rates(t_s, _rates_of(data, mounting), bounds, block_rows)
    return ImuData(time_s=bounds, dtheta_b=inc[:, :3], dv_b=inc[:, 3:])


def _imu_file(path, identity, t_s, clock, timing, base_s, mounting, resample_hz, span,
              chunk_rows):
    """The increments as an :class:`~.imu_file.ImuFile` (read from the file when asked)."""
    bounds = _bounds_of(t_s, resample_hz, span)
    times = RowTimes(p0_ms=clock.p0_ms, c0_ms=clock.c0_ms, period_ms=clock.period_ms,
                     regular=clock.regular, time0_ms=float(clock.time_ms[0]),
                     a_ms=timing.latency_ms, b=timing.clock_rate, delay_s=timing.imu_delay_s,
                     base_s=base_s)
    dt = float(np.median(np.diff(bounds)))
    return ImuFile(path=path, identity=identity, times=times,
                   matrix=None if mounting is None else mounting.matrix,
                   grid_hz=resample_hz, span_s=(float(bounds[0]), float(bounds[-1])),
                   n_samples=int(bounds.size - 1), dt_nom_s=dt, chunk_rows=chunk_rows)


def _physics(path, data, kept, rate_hz, limits, chunk_rows):
    """:func:`~.checks.imu_physics` on the held rows, or on the file read again in blocks
    (``data`` None: only the ticks were kept)."""
    if data is not None:
        checks.imu_physics(path, data[:, 0:3], data[:, 3:6], kept + 1, rate_hz, limits)
        return
    scan = checks.PhysicsScan(rate_hz)
    for _, first, rows, block in parsed_blocks(path, chunk_rows):
        if block is not None and rows.size:
            scan.add(block[:, 0:3], block[:, 3:6], rows + first + 1)
    scan.check(path, limits)


def _fixes(pos, epoch: int, t_lo: float, t_hi: float, lever_arm_b, fixed_only: bool,
           velocity_lag_s: float = 0.0):
    c = pos.columns
    t = (pos.time_int_s - epoch) + pos.time_frac_s
    sel = (t >= t_lo) & (t <= t_hi) & ((c["q"] == 1) if fixed_only else True)
    vel = np.column_stack([c["vel_e"], c["vel_n"], c["vel_u"]])
    if velocity_lag_s:  # a velocity reported late belongs to an earlier instant
        vel = np.column_stack([np.interp(t + velocity_lag_s, t, vel[:, j]) for j in range(3)])
    z = np.column_stack([np.deg2rad(c["lat_deg"]), np.deg2rad(c["lon_deg"]), c["h_m"],
                         vel])[sel]
    sigma = np.column_stack([c["sd_e"], c["sd_n"], c["sd_u"],
                             c["sd_ve"], c["sd_vn"], c["sd_vu"]])[sel]
    meta = {k: c[k][sel] for k in ("q", "ns", "ratio", "age_s")}
    meta["lever_arm_b"] = np.asarray(lever_arm_b, dtype=float)
    return SensorData(kind="gnss", time_s=t[sel], z=z, sigma=sigma, meta=meta)


def load_rtklib(directory, mounting="auto", imu_delay_s=DEFAULT_IMU_DELAY_S,
                resample_hz="nominal", span_s=None, session=None,
                gnss_velocity_lag_s=0.0, limits=None, start=None,
                chunk_rows=DEFAULT_CHUNK_ROWS, streamed=False) -> Recording:
    """Load an RTKLIB-logged IMU + GNSS recording.

    Parameters
    ----------
    directory : path-like
        The recording directory.
    mounting : "auto", Mounting, path-like or None
        ``"auto"`` reads ``mounting.toml`` from the directory if present; ``None`` uses
        the IMU frame as the body frame.
    imu_delay_s : float
        Delay from an IMU sample to its fitted arrival at the logger [s].
    resample_hz : "nominal", float or None
        Increment grid: whole multiples of ``1/resample_hz`` GPST seconds (``"nominal"``:
        the IMU's rate rounded to a whole Hz); ``None`` keeps the sample instants.
    span_s : (float, float), optional
        Keep only this time window, seconds after the first IMU sample.
    session : str, optional
        The ``<id>`` of ``imu_<id>.csv`` when the directory holds several.
    gnss_velocity_lag_s : float
        How late the receiver reports its velocities [s]; when non-zero the velocities of
        ``gnss`` (not of ``reference``) are moved back by this much (by interpolation).
        RTKLIB's on the rtklib-drive lag the positions by about 0.14 s
        (:func:`fuzzynav.realdata.loaders.sync.velocity_lag`).
    limits : checks.Limits, optional
        Thresholds of the plausibility checks (:mod:`.checks`; default: its constants).
    start : StartOptions, optional
        How the initial state is found (:mod:`fuzzynav.realdata.start_options`; default: the
        car drive's); its ``lever_arm_b_m``, if set, replaces the mounting's.
    chunk_rows : int or None
        Lines of the IMU CSV parsed at a time (:func:`read_imu_csv`; ``None``: the whole
        file at once); the recording is the same whatever it is.
    streamed : bool
        Keep no IMU rows: the CSV is read once for the timing (its ticks and line
        lengths), and its increments are read again from the file, a block of lines at a
        time, whenever they are wanted (``imu`` is then an
        :class:`~.imu_file.ImuFile`, :mod:`.imu_file`): memory bounded by the block, not
        the recording, at the cost of a read of the file per use.  The increments, and
        every check, are those of the held load.

    Returns
    -------
    Recording

    Raises
    ------
    DataMissingError
        A directory or file is missing.
    InputFileError
        A file is malformed or the recording fails a check of :mod:`.checks`.
    """
    if not (isinstance(imu_delay_s, (int, float)) and abs(imu_delay_s) <= MAX_IMU_DELAY_S):
        raise FuzzynavError(f"imu_delay_s (--imu-delay) must be a number of seconds within "
                            f"+-{MAX_IMU_DELAY_S:g}, got {imu_delay_s!r}")
    directory = Path(directory)
    files = find_files(directory, session)
    mount = _resolve_mounting(mounting, directory, files)
    tag = timetag.read_timetag(files["tag"])
    path = files["imu"]
    identity = ImuFile.identity_of(path)
    if streamed:  # the ticks alone: the rows are read again when wanted
        ticks, kept, lengths, size = read_imu_csv(path, chunk_rows, 6, SCAN_BYTES_PER_LINE)
        data = None
    else:
        data, kept, lengths, size = read_imu_csv(path, chunk_rows, hint=STREAMED_HINT)
        ticks = data[:, 6]
    limits = checks.DEFAULT_LIMITS if limits is None else limits
    rate_hz = checks.imu_ticks(path, ticks, kept + 1, limits)
    _physics(path, data, kept, rate_hz, limits, chunk_rows)
    clock = increments.regular_sample_times(ticks)
    del ticks
    n_lines, span_ms = lengths.size, float(np.ptp(clock.time_ms))
    matched = timetag.kept_arrivals(tag, kept, lengths, size)
    del kept, lengths  # the fit below is the load's peak: hold only what it needs
    offset_s, timing = align_time(tag, clock, matched, imu_delay_s)
    del matched
    checks.clock_rate(path, files["tag"], tag, timing.method, timing.clock_rate, size,
                      n_lines, span_ms / 1000.0, limits)
    frac0 = tag.start_frac_s + offset_s[0]
    epoch = tag.start_int_s + int(np.floor(frac0))
    base_s = tag.start_frac_s - (epoch - tag.start_int_s)
    t_s = base_s + offset_s
    del offset_s
    span = (-np.inf, np.inf) if span_s is None else (t_s[0] + span_s[0], t_s[0] + span_s[1])
    rate = round(1000.0 / clock.period_ms) if resample_hz == "nominal" else resample_hz
    try:
        imu = _imu_data(data, t_s, mount, rate, span, chunk_rows) if not streamed else \
            _imu_file(path, identity, t_s, clock, timing, base_s, mount, rate, span,
                      chunk_rows)
    except InputFileError as exc:  # a span outside the data
        raise InputFileError(directory, exc.where, exc.what) from None
    del t_s, data
    if streamed:  # the sample clock's times are not held either
        timing = replace(timing, clock=replace(clock, time_ms=clock.time_ms[:1]))
    imu.meta.update(n_missing_samples=clock.n_missing, max_gap_s=clock.max_gap_ms / 1000.0,
                    tick_jitter_ms=clock.jitter_ms, source=str(path))
    pos = read_pos(files["pos"])
    t_lo, t_hi = imu.span_s
    checks.gnss_overlap(files["pos"], pos.time_int_s + pos.time_frac_s, pos.columns["q"],
                        (epoch + t_lo, epoch + t_hi), limits)
    start = StartOptions() if start is None else start
    lever = np.zeros(3) if mount is None else mount.gnss_lever_arm_b_m
    lever = lever if start.lever_arm_b_m is None else np.asarray(start.lever_arm_b_m, float)
    reference = _fixes(pos, epoch, t_lo, t_hi, lever, True)
    checks.gyro_scale(path, imu, reference, limits)
    return Recording(directory=directory, files=files, epoch_gpst_s=int(epoch), imu=imu,
                     gnss=_fixes(pos, epoch, t_lo, t_hi, lever, False, gnss_velocity_lag_s),
                     reference=reference, mounting=mount, timing=timing,
                     start_options=start)
