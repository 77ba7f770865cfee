"""Loader of the A-KIT AUV recordings (Snapir AUV, Phins INS 100 Hz, RDI DVL 1 Hz, Delph
post-processed reference; ``../shared/datasets/akit``, trajectories 1-8).

Conventions, established from the data (``docs/data.md``; the numbers come from
``tools/akit_conventions.py``):

* the IMU (``IMU_trajectoryN.csv``, top level only) gives specific force [m/s^2] and rates
  [rad/s] in a forward-right-down body frame: the accelerometer z axis reads -9.79 m/s^2;
* the reference and the DVL are read from ``corrected/``: there the columns headed
  Longitude / Latitude really hold longitude / latitude (in the top-level GT files they are
  swapped), and the pitch has the sign the IMU sees (10-s means of the forward specific
  force follow +g sin(pitch) with correlation 0.80-0.96 on all eight trajectories; -0.80 to
  -0.96 with the top-level pitch).  Attitude is ZYX Euler (roll, pitch, yaw) of
  body FRD to NED; velocity NED; altitude is minus the depth;
* the reference and DVL stamps are not on the IMU's clock: they run 0.25 % slow against it
  (each stream's samples were spread over 0-400 s) and start offset by a fraction of a
  second; :func:`~fuzzynav.realdata.loaders.akit_timing.estimate_clock` measures the map from
  the gyros (negative offsets allowed) and the reference and the DVL are moved onto the IMU
  clock by it (module :mod:`~fuzzynav.realdata.loaders.akit_timing`);
* the DVL velocity is that of the IMU point (the filter's residuals show no lever-arm
  effect), while the reference is given at a point about 1.8 m forward of it: the lateral
  difference between the DVL and the reference velocity rotated into the body is the yaw
  rate times that offset (:func:`reference_offset`, fitted per trajectory).

Everything is returned in fuzzynav's frames: ENU navigation, body RFU
(``x_rfu = y_frd, y_rfu = x_frd, z_rfu = -z_frd``).
"""
from __future__ import annotations

import io
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fuzzynav.errors import DataMissingError, InputFileError, brief
from fuzzynav.nav import attitude
from fuzzynav.realdata.loaders import akit_checks as checks, chunked
from fuzzynav.realdata.loaders.chunked import DEFAULT_CHUNK_ROWS
from fuzzynav.realdata.loaders.akit_timing import BLOCK_ELEMENTS, ClockMap, ClockSearch, \
    dvl_offset, estimate_clock
from fuzzynav.sim.imu import ImuData
from fuzzynav.sim.sensors import SensorData

__all__ = ["SWAP", "IMU_FILE_TO_FRD", "COLUMNS", "DVL_SIGMA_MPS", "Reference", "AkitRecording",
           "MAX_TRAJECTORY", "parse_trajectories", "read_table", "imu_increments",
           "reference_attitude", "reference_at", "forward_velocity", "reference_clock",
           "body_velocity", "yaw_rate_at", "reference_offset", "reference_on_imu_clock",
           "load_trajectory", "load_akit"]

#: FRD <-> RFU and NED <-> ENU: the same axis swap (a proper rotation, its own inverse)
SWAP = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
#: sign of the IMU file's x, y, z columns in body FRD: the y axis is reversed (left).  Found
#: from the data: with it reversed the gyro y rate anticorrelates with the reference's pitch
#: rate (-0.54 to -0.96) while x and z follow roll and yaw rates (+0.7, +0.99), and the
#: lateral specific force is minus (forward speed x yaw rate - g sin roll); the z column
#: reads -9.79 m/s^2 (down).  A left-handed file frame, fixed by one sign.
IMU_FILE_TO_FRD = np.array([1.0, -1.0, 1.0])
#: columns of each file kind, as headed in the recordings
COLUMNS = {"IMU": 7, "DVL": 4, "GT": 10}
#: the DVL's 1-sigma per axis according to the source [m/s]
DVL_SIGMA_MPS = 0.02


@dataclass(frozen=True)
class Reference:
    """The post-processed reference in fuzzynav's frames (on the IMU clock)."""

    time_s: np.ndarray
    lla: np.ndarray      # (K, 3) lat, lon [rad], h [m]
    vel_n: np.ndarray    # (K, 3) ENU [m/s]
    q_bn: np.ndarray     # (K, 4) body RFU -> ENU


@dataclass(frozen=True)
class AkitRecording:
    """One A-KIT trajectory, ready for the filter."""

    trajectory: int
    directory: Path
    imu: ImuData
    dvl: SensorData
    reference: Reference
    clock: ClockMap
    reference_offset_b: np.ndarray  # reference point in body RFU from the IMU [m]
    files: dict = field(default_factory=dict)
    kind = "akit"


#: highest trajectory number accepted (A-KIT has 1-8; a range to 10^12 would fill memory
#: before the first missing file is noticed)
MAX_TRAJECTORY = 9999


def parse_trajectories(text) -> list[int]:
    """``"3"``, ``"1,4,6"`` or ``"1-8"`` (and mixtures) -> sorted trajectory numbers."""
    out = set()
    for part in str(text if text is not None else "1-8").split(","):
        m = re.fullmatch(r"\s*(\d{1,12})\s*(?:-\s*(\d{1,12})\s*)?", part)
        if not m or (m.group(2) and int(m.group(2)) < int(m.group(1))):
            raise InputFileError(None, "--data trajectory",
                                 f"expected N, N-M or a comma list, got {brief(text)}")
        lo, hi = int(m.group(1)), int(m.group(2) or m.group(1))
        if not 1 <= lo <= hi <= MAX_TRAJECTORY:
            raise InputFileError(None, "--data trajectory",
                                 f"trajectory numbers run from 1 to {MAX_TRAJECTORY}, got "
                                 f"{brief(part.strip())}")
        out.update(range(lo, hi + 1))
    return sorted(out)


#: what a whole read refuses first (after a file that cannot be read, one without two data
#: rows): a row that does not parse, then a time that does not increase
_ERROR_ORDER = ("row", "time")


def _column(names, j: int) -> str:
    """``column NAME`` of the header's ``j``-th field (its number when the header has none)."""
    name = names[j].strip() if j < len(names) else ""
    return f"column {name or j + 1}"


def _parse_rows(path, lines, first_lineno: int, ncol: int, names=()):
    """The numbers of text rows (``lines``, the first being line ``first_lineno`` of the
    file, 1-based); raises the error of the first row that is cut, not a number or not
    finite, naming its column from the header's ``names``."""
    plain = _parsed_at_once(lines, ncol)
    if plain is not None:
        return plain
    rows = []
    for i, line in enumerate(lines, start=first_lineno):
        parts = line.split(",")
        if len(parts) != ncol:
            raise InputFileError(path, f"line {i}", f"has {len(parts)} columns, expected "
                                                    f"{ncol} (a cut or damaged row)")
        vals = []
        for j, part in enumerate(parts):
            try:
                vals.append(float(part))
            except ValueError:
                raise InputFileError(path, f"line {i}, {_column(names, j)}",
                                     f"not a number: {part.strip()[:40]!r}") from None
            if not np.isfinite(vals[-1]):
                raise InputFileError(path, f"line {i}, {_column(names, j)}",
                                     f"not finite: {part.strip()[:40]!r}")
        rows.append(vals)
    return np.array(rows, dtype=float).reshape(len(rows), ncol)


def _parsed_at_once(lines, ncol: int):
    """The rows parsed by numpy's reader at once (the speed of a long file), or ``None``
    when one is not plain numbers (a cut row, a blank line, an odd spelling): the row by
    row parse then says which, or reads what Python's ``float`` takes and numpy's does
    not.  Both parse a number with CPython's own ``PyOS_string_to_double``, so a row gives
    the same floats either way."""
    try:
        a = np.loadtxt(io.StringIO("\n".join(lines)), delimiter=",", ndmin=2, comments=None)
    except ValueError:
        return None
    if a.shape != (len(lines), ncol) or not np.all(np.isfinite(a)):
        return None
    return a


def _time_error(path, t, first_lineno: int):
    """The error of the first time that does not increase in ``t`` (rows from line
    ``first_lineno`` of the file on), or ``None``."""
    bad = np.flatnonzero(np.diff(t) <= 0)
    if not bad.size:
        return None
    return InputFileError(path, f"line {first_lineno + bad[0] + 1}, column Time [s]",
                          "time does not increase")


def _split_lines(block) -> list:
    """The lines of a block of text lines as ``str.splitlines`` splits the whole text."""
    return [part for line in block for part in line.splitlines()]


def read_table(path: Path, kind: str, chunk_rows=DEFAULT_CHUNK_ROWS) -> np.ndarray:
    """A numeric CSV with one header line; every row complete and finite, time increasing.

    Read ``chunk_rows`` lines at a time (:mod:`.chunked`; ``None``: at once): each block's
    rows are parsed and checked, the time order across block boundaries too, then the
    time column as a whole (:func:`~.akit_checks.timing_of`); every block size gives the
    same table and the same error.
    """
    if path.is_dir():
        raise InputFileError(path, "", "is a directory, not an A-KIT file")
    if not path.is_file():
        raise DataMissingError(f"{path}: A-KIT file not found")
    chunk_rows = chunked.check_chunk_rows(chunk_rows)
    ncol = COLUMNS[kind]
    errors = chunked.FirstErrors(_ERROR_ORDER)
    n_lines, last, names = 0, None, ()  # last: the previous block's last (time, line)
    try:
        held = chunked.counted_lines(path, checks.held_bytes_per_row(ncol), universal=True)
        rows = chunked.Rows(path, held, ncol)
        with open(path) as f:
            for _, block in chunked.line_blocks(f, chunk_rows):
                lines = _split_lines(block)
                if not n_lines and lines:
                    names = lines[0].split(",")  # the header: the columns' names
                # the header is line 1; rows are numbered from 2
                first = max(n_lines, 1) - n_lines
                lineno = n_lines + first + 1
                n_lines += len(lines)
                if "row" in errors or not lines[first:]:  # past a bad row only lines count
                    continue
                try:
                    a = _parse_rows(path, lines[first:], lineno, ncol, names)
                except InputFileError as exc:
                    errors.note("row", exc)
                    continue
                t = a[:, 0] if last is None else np.concatenate([[last[0]], a[:, 0]])
                bad = _time_error(path, t, lineno if last is None else last[1])
                if bad is not None:
                    errors.note("time", bad)
                last = (a[-1, 0], lineno + a.shape[0] - 1)
                rows.add(a)
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(path, "", f"cannot be read ({exc.__class__.__name__})") from None
    if n_lines < 3:
        raise InputFileError(path, "line 2", "no data rows (a header and at least 2 rows)")
    errors.raise_first()
    a = rows.array()
    checks.timing_of(path, a[:, 0], kind)
    return a


def imu_increments(t, acc_file, gyro_file) -> ImuData:
    """Trapezoidal increments of the sampled rates, in body RFU.

    The files' y columns (accelerometer and gyro) have the opposite sign of a
    forward-right-down frame (:data:`IMU_FILE_TO_FRD`); they are turned round first.  Made
    a block of samples at a time (:data:`~.akit_timing.BLOCK_ELEMENTS`: each increment is
    its two samples' alone), so a long file's temporaries are the block's.
    """
    K = max(t.size - 1, 0)
    dth, dv = np.empty((K, 3)), np.empty((K, 3))
    for a in range(0, K, BLOCK_ELEMENTS):
        b = min(a + BLOCK_ELEMENTS, K)
        acc_frd = acc_file[a:b + 1] * IMU_FILE_TO_FRD
        gyro_frd = gyro_file[a:b + 1] * IMU_FILE_TO_FRD
        dt = np.diff(t[a:b + 1])[:, None]
        dth[a:b] = (0.5 * (gyro_frd[1:] + gyro_frd[:-1]) * dt) @ SWAP.T
        dv[a:b] = (0.5 * (acc_frd[1:] + acc_frd[:-1]) * dt) @ SWAP.T
    return ImuData(time_s=t.copy(), dtheta_b=dth, dv_b=dv, meta={"frame": "RFU from FRD"})


def reference_attitude(rpy) -> np.ndarray:
    """Quaternions (body RFU -> ENU) of ZYX Euler angles (roll, pitch, yaw) FRD -> NED."""
    r, p, y = rpy[:, 0], rpy[:, 1], rpy[:, 2]
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    C = np.array([[cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy],
                  [cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy],
                  [-sp, sr * cp, cr * cp]])
    return attitude.dcm_to_quat(SWAP @ np.moveaxis(C, -1, 0) @ SWAP).reshape(len(rpy), 4)


def reference_at(gt, t_new) -> Reference:
    """The reference (columns of a GT file) interpolated at ``t_new`` [s], in our frames."""
    t = gt[:, 0]
    cols = gt[:, 1:10].copy()
    cols[:, 8] = np.unwrap(cols[:, 8])  # yaw: interpolate without the wrap
    g = np.column_stack([np.interp(t_new, t, cols[:, i]) for i in range(9)])
    return Reference(time_s=np.asarray(t_new, float),
                     lla=np.column_stack([g[:, 1], g[:, 0], g[:, 2]]),
                     vel_n=g[:, 3:6] @ SWAP.T, q_bn=reference_attitude(g[:, 6:9]))


def forward_velocity(gt) -> np.ndarray:
    """The reference velocity rotated into the body: its forward component [m/s]."""
    C = attitude.quat_to_dcm(reference_attitude(gt[:, 7:10]))
    return np.einsum("ki,ki->k", C[:, :, 1], gt[:, 4:7] @ SWAP.T)


def reference_clock(inc: ImuData, gt, dvl) -> tuple[ClockMap, ClockSearch]:
    """The reference's and the DVL's clock map onto the IMU (:mod:`.akit_timing`) from the
    IMU's increments ``inc`` (:func:`imu_increments` of its table), and where the
    reference's was searched for."""
    clock, search = estimate_clock(inc.time_s, inc.dtheta_b, gt[:, 0],
                                   reference_attitude(gt[:, 7:10]), float(np.median(gt[:, 2])))
    dt = float(np.median(np.diff(inc.time_s)))
    delta = dvl_offset(dvl[:, 0], dvl[:, 1], gt[:, 0], forward_velocity(gt), dt)
    return ClockMap(clock.offset_s, clock.rate, delta), search


def body_velocity(ref: Reference) -> np.ndarray:
    """The reference velocity rotated into the body (RFU) at each of its epochs [m/s]."""
    return np.einsum("kji,kj->ki", attitude.quat_to_dcm(ref.q_bn), ref.vel_n)


def yaw_rate_at(imu: ImuData, t) -> np.ndarray:
    """The body z (up) rate of the IMU increments at times ``t`` [rad/s]."""
    ti = imu.time_s
    return np.interp(t, 0.5 * (ti[1:] + ti[:-1]), imu.dtheta_b[:, 2] / np.diff(ti))


def reference_offset(imu: ImuData, dvl: SensorData, ref_at_dvl: Reference) -> np.ndarray:
    """Position of the reference point in body RFU relative to the IMU [m].

    The DVL agrees with the IMU-point velocity (no lever-arm effect in the filter's
    residuals) but not with the reference velocity rotated into the body: their lateral
    difference is the yaw rate times a forward offset ``r_y``,
    ``(v_dvl - C_nb v_ref)_x = omega_z r_y``; fitted by least squares (only ``r_y``: the
    roll and pitch rates are too small to fix the other components).  ``ref_at_dvl`` is
    the reference at the DVL's times (:func:`reference_on_imu_clock`): a reference epoch
    up to a second away would add the change of the body velocity over that second.
    """
    lateral = dvl.z[:, 0] - body_velocity(ref_at_dvl)[:, 0]
    wz = yaw_rate_at(imu, dvl.time_s)
    r_y = float(np.dot(wz, lateral) / max(np.dot(wz, wz), 1e-30))
    return np.array([0.0, r_y, 0.0])


def reference_on_imu_clock(gt, clock: ClockMap, t_imu) -> Reference:
    """The reference (columns of a GT file) interpolated at IMU times ``t_imu`` [s] through
    the clock map, stamped with those IMU times."""
    ref = reference_at(gt, clock.to_label(t_imu))
    return Reference(np.asarray(t_imu, float), ref.lla, ref.vel_n, ref.q_bn)


def _reference_on_imu_clock(gt, t_imu, clock: ClockMap):
    """The reference resampled at its own rate on the IMU clock from the first IMU sample it
    covers, and that sample's index in ``t_imu`` (the samples before it are dropped: the
    filter starts from the reference)."""
    s = int(np.searchsorted(t_imu, max(t_imu[0], float(clock.to_imu(gt[0, 0]))) - 1e-9))
    period = float(np.median(np.diff(gt[:, 0]))) / clock.rate
    t_ref = np.arange(t_imu[s], min(float(clock.to_imu(gt[-1, 0])), t_imu[-1]) + 1e-9, period)
    return reference_on_imu_clock(gt, clock, t_ref), s


def load_trajectory(directory, n: int, chunk_rows=DEFAULT_CHUNK_ROWS) -> AkitRecording:
    """Read trajectory ``n`` of an A-KIT directory (see the module notes for frames), its
    files ``chunk_rows`` lines at a time (:func:`read_table`; the same recording whatever
    it is)."""
    d = Path(directory)
    files = {"imu": d / f"IMU_trajectory{n}.csv", "dvl": d / "corrected" / f"DVL_trajectory{n}.csv",
             "reference": d / "corrected" / f"GT_trajectory{n}.csv"}
    # a damaged file's arithmetic (a mean of nothing, an overflow) is reported by the checks
    # in one line, not as numpy's warnings first
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return _load(d, n, files, chunk_rows)


def _load(d: Path, n: int, files: dict, chunk_rows) -> AkitRecording:
    imu = read_table(files["imu"], "IMU", chunk_rows)
    dvl = read_table(files["dvl"], "DVL", chunk_rows)
    gt = read_table(files["reference"], "GT", chunk_rows)
    checks.imu_of(files["imu"], imu)
    checks.dvl_of(files["dvl"], dvl)
    checks.reference_of(files["reference"], gt)
    checks.pitch_sign(files["reference"], imu, gt)
    checks.spans(files, imu[:, 0], dvl[:, 0], gt[:, 0])
    full = imu_increments(imu[:, 0], imu[:, 1:4], imu[:, 4:7])
    del imu  # from here on its increments and their times: the table is not held twice
    t = full.time_s
    clock, search = reference_clock(full, gt, dvl)
    checks.belong_together(
        files, checks.rotation_misfit_deg(full, gt, reference_attitude(gt[:, 7:10]), clock),
        checks.dvl_forward_rms(dvl, gt, clock, reference_on_imu_clock, body_velocity),
        search.inside(clock, gt[:, 0]))
    checks.clock_map(files, clock, search, gt[:, 0])
    ref, s = _reference_on_imu_clock(gt, t, clock)
    t_dvl = clock.to_imu(dvl[:, 0], clock.dvl_offset_s)
    inside = (t_dvl > t[s]) & (t_dvl <= t[-1])
    z = dvl[inside, 1:4] @ SWAP.T
    sensor = SensorData("dvl", t_dvl[inside], z, np.full(z.shape, DVL_SIGMA_MPS),
                        {"rate_hz": 1.0 / float(np.median(np.diff(dvl[:, 0])))})
    # the increments from the first sample kept on: the whole table's from there (each
    # increment is its two samples' alone), not made again
    inc = full if s == 0 else ImuData(t[s:], full.dtheta_b[s:], full.dv_b[s:], meta=full.meta)
    r_b = reference_offset(inc, sensor, reference_on_imu_clock(gt, clock, sensor.time_s))
    return AkitRecording(n, d, inc, sensor, ref, clock, r_b, {k: str(v) for k, v in files.items()})


def load_akit(directory, trajectories="1-8", chunk_rows=DEFAULT_CHUNK_ROWS
              ) -> list[AkitRecording]:
    """Load several trajectories (``"1-8"``, ``"2"``, ``"1,3"``; ``chunk_rows``: as
    :func:`load_trajectory`)."""
    return [load_trajectory(directory, n, chunk_rows) for n in parse_trajectories(trajectories)]
