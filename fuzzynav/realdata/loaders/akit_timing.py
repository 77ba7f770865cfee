"""The clock map of the A-KIT reference and DVL onto the IMU's clock.

The reference and DVL rows of the A-KIT files are stamped ``k * 400 / 399`` s and the IMU
rows ``m * 400 / 39999`` s: each stream's samples were spread over 0-400 s whatever their
number, so the 1-Hz streams run 0.25 % slow against the IMU and drift by about 1 s over a
trajectory, on top of a constant offset.  Matching the gyros to the reference shows it
(``docs/data.md``), and this module measures the map from the data instead of assuming it:

* the gyro increments (earth rate removed with the reference attitude) are chained into one
  body attitude track; between two consecutive reference epochs the reference's body
  rotation is compared with the track's over the same interval shifted by each candidate
  offset (IMU-sample steps, negative and positive), giving a misfit per epoch and offset;
* per segment of the trajectory the best offset (parabola through the three smallest
  misfits) is found, a straight line through them gives the clock rate, and the offset at
  the start is refined over all epochs along that line.

A time offset is observable only where the turn rate changes (for a steady rate the shifted
increments are the same), which the misfit curvature reflects: segments are weighted by it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.nav import attitude

__all__ = ["EARTH_RATE", "MAX_OFFSET_S", "SEGMENTS", "BLOCK_ELEMENTS", "ClockMap",
           "parabola_min", "GyroTrack", "track_at", "without_earth_rate",
           "epoch_misfits", "segment_offsets", "estimate_clock", "MIN_OFFSET_CONTRAST",
           "dvl_offset"]

#: earth rotation rate [rad/s] (WGS-84)
EARTH_RATE = 7.292115e-5
#: largest offset searched either side of zero [s]
MAX_OFFSET_S = 2.0
#: segments of the trajectory whose best offsets give the clock rate
SEGMENTS = 10
#: IMU samples, or (offset, epoch) pairs of the misfit search, handled at a time: the
#: array steps work through a recording in blocks of this many, so their temporaries are
#: bounded by the block (a day of 100-Hz IMU and 1-Hz reference has 35 M pairs of four
#: quaternions each) while every number is the whole arrays' (each is computed from its
#: own sample or pair alone)
BLOCK_ELEMENTS = 1 << 15


@dataclass(frozen=True)
class ClockMap:
    """``label = rate * t_imu + offset_s``: the 1-Hz file stamp of an event at IMU time
    ``t_imu``.  ``offset_s > 0``: the stream's stamps trail the IMU.  ``dvl_offset_s``: what
    the DVL's stamps trail the reference's by (the DVL label of an event is
    ``rate * t_imu + offset_s + dvl_offset_s``)."""

    offset_s: float
    rate: float
    dvl_offset_s: float = 0.0

    def to_imu(self, label, extra_s: float = 0.0) -> np.ndarray:
        """IMU times of file stamps ``label`` (minus ``extra_s`` more offset)."""
        return (np.asarray(label, float) - self.offset_s - extra_s) / self.rate

    def to_label(self, t_imu) -> np.ndarray:
        """Reference file stamps of IMU times ``t_imu``."""
        return self.rate * np.asarray(t_imu, float) + self.offset_s


def parabola_min(cost) -> float:
    """Position of the minimum of sampled costs, refined by a parabola through three."""
    i = int(np.argmin(cost))
    if 0 < i < len(cost) - 1:
        c0, c1, c2 = cost[i - 1], cost[i], cost[i + 1]
        den = c0 - 2.0 * c1 + c2
        if den > 0.0:
            return i + 0.5 * (c0 - c2) / den
    return float(i)


def _chain(q_last, dtheta_b) -> np.ndarray:
    """The track's next quaternions after ``q_last``, one per increment of ``dtheta_b``."""
    q = np.empty((dtheta_b.shape[0], 4))
    w, x, y, z = q_last.tolist()
    k = 0
    # a scalar loop: a cumulative quaternion product has no numpy form; the increments'
    # quaternions a block at a time (as Python floats they would be ~200 B a sample)
    for s0 in range(0, dtheta_b.shape[0], BLOCK_ELEMENTS):
        for a, b, c, d in attitude.rotvec_to_quat(dtheta_b[s0:s0 + BLOCK_ELEMENTS]).tolist():
            w, x, y, z = (w * a - x * b - y * c - z * d, w * b + x * a + y * d - z * c,
                          w * c - x * d + y * a + z * b, w * d + x * c - y * b + z * a)
            q[k] = w, x, y, z
            k += 1
    return q


class GyroTrack:
    """The gyro track of an IMU made as far as it is asked for, forward only: the
    increments less the earth rate (:func:`without_earth_rate`) chained into the body's
    attitude relative to the first sample (``q[k] = q[k-1] * exp(dtheta[k-1])``), held from
    the last window's first sample on.

    The misfit search asks for the samples around each block of reference epochs in turn,
    so a recording's track is never held whole; its numbers are the whole track's (each
    increment is its own sample's, the chain the same scalar loop carried on).

    Parameters
    ----------
    t_imu, dtheta_b : IMU times (K+1,) and rotation increments (K, 3).
    t_ref, q_ref, lat_rad : the earth rate's reference, as :func:`without_earth_rate`.
    """

    def __init__(self, t_imu, dtheta_b, t_ref, q_ref, lat_rad):
        self.t_imu, self.dtheta_b, self.earth = t_imu, dtheta_b, (t_ref, q_ref, lat_rad)
        self.start = 0  # the sample of q[0], the increment of gyro[0]
        self.q = np.array([[1.0, 0.0, 0.0, 0.0]])
        self.gyro = np.empty((0, 3))

    def window(self, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray]:
        """``(q, gyro)``: the track at samples ``lo..hi`` and the increments ``lo..hi`` (up
        to the last); ``lo`` must not be before an earlier window's."""
        if lo < self.start:
            raise ValueError(f"GyroTrack goes forward only: sample {lo} is before {self.start}")
        while self.start + self.q.shape[0] <= hi:  # chain on, a block at a time
            last = self.start + self.q.shape[0] - 1
            target = min(hi, last + BLOCK_ELEMENTS)
            self._make_gyro(target - 1)
            g = self.gyro[last - self.start:target - self.start]
            self.q = np.concatenate([self.q, _chain(self.q[-1], g)])
            self._drop(min(lo, target))
        self._make_gyro(min(hi, self.dtheta_b.shape[0] - 1))
        self._drop(lo)
        return self.q[:hi - lo + 1], self.gyro[:hi - lo + 1]

    def _make_gyro(self, upto: int) -> None:
        """The increments up to ``upto``, less the earth rate."""
        end = self.start + self.gyro.shape[0]
        if upto >= end:
            new = without_earth_rate(self.t_imu[end:upto + 2], self.dtheta_b[end:upto + 1],
                                     *self.earth)
            self.gyro = np.concatenate([self.gyro, new])

    def _drop(self, lo: int) -> None:
        """Let go of the samples before ``lo``."""
        cut = lo - self.start
        if cut > 0:
            self.q, self.gyro, self.start = self.q[cut:], self.gyro[cut:], lo


def track_at(t_imu, q, dtheta_b, t, first: int = 0) -> np.ndarray:
    """The track ``q`` at times ``t`` (any shape) between samples: the increment of the
    sample interval taken in proportion (constant rate within a sample).  ``q`` and
    ``dtheta_b`` may start at sample ``first`` (a :meth:`GyroTrack.window`)."""
    k = np.clip(np.searchsorted(t_imu, t, side="right") - 1, 0, t_imu.size - 2)
    frac = (t - t_imu[k]) / (t_imu[k + 1] - t_imu[k])
    return attitude.quat_multiply(q[k - first], attitude.rotvec_to_quat(
        frac[..., None] * dtheta_b[k - first]))


def without_earth_rate(t_imu, dtheta_b, t_ref, q_ref, lat_rad) -> np.ndarray:
    """Gyro increments less the earth rate seen in the body (the reference attitude of the
    nearest epoch is close enough: 0.004 deg/s either way)."""
    w_ie = EARTH_RATE * np.array([0.0, np.cos(lat_rad), np.sin(lat_rad)])  # ENU
    out = np.empty_like(dtheta_b)
    for a in range(0, dtheta_b.shape[0], BLOCK_ELEMENTS):  # a (3, 3) matrix per sample
        b = min(a + BLOCK_ELEMENTS, dtheta_b.shape[0])
        k = np.clip(np.searchsorted(t_ref, t_imu[a + 1:b + 1]), 0, t_ref.size - 1)
        C_bn = np.swapaxes(attitude.quat_to_dcm(q_ref[k]), -1, -2)
        out[a:b] = dtheta_b[a:b] - (C_bn @ w_ie) * np.diff(t_imu[a:b + 1])[:, None]
    return out


def epoch_misfits(track: GyroTrack, t_ref, q_ref, shifts) -> tuple[np.ndarray, np.ndarray]:
    """Squared rotation misfit [rad^2], shape (len(shifts), J), between the reference's body
    rotation from epoch j to j+1 and the gyro track's (a :class:`GyroTrack`) from
    ``t_ref - shift``; with the epochs j used (both ends inside the IMU span for every
    shift).  Made for :data:`BLOCK_ELEMENTS` pairs of shift and epoch at a time, the
    track's samples around them asked for in turn."""
    t_imu = track.t_imu
    j = np.flatnonzero((t_ref[:-1] - shifts.max() >= t_imu[0])
                       & (t_ref[1:] - shifts.min() <= t_imu[-1]))
    misfit = np.empty((shifts.size, j.size))
    step = max(1, BLOCK_ELEMENTS // shifts.size)
    for a in range(0, j.size, step):
        jb = j[a:a + step]
        t0 = t_ref[jb][None, :] - shifts[:, None]
        t1 = t_ref[jb + 1][None, :] - shifts[:, None]
        lo, hi = np.clip(np.searchsorted(t_imu, [t0.min(), t1.max()], side="right") - 1, 0,
                         t_imu.size - 2)
        q, gyro = track.window(int(lo), int(hi))
        d_ref = attitude.quat_multiply(attitude.quat_conj(q_ref[jb]), q_ref[jb + 1])
        q0 = track_at(t_imu, q, gyro, t0, int(lo))
        q1 = track_at(t_imu, q, gyro, t1, int(lo))
        d_gyro = attitude.quat_multiply(attitude.quat_conj(q0), q1)
        err = attitude.quat_to_rotvec(attitude.quat_multiply(attitude.quat_conj(d_ref)[None],
                                                             d_gyro))
        misfit[:, a:a + jb.size] = np.sum(err * err, -1)
    return misfit, j


def _along(misfit, shifts, slope: float, t_epoch) -> np.ndarray:
    """Mean misfit over epochs along each line of shifts ``shifts[i] + slope t_epoch``, the
    misfit interpolated between the sampled shifts; a block of lines at a time (each
    line's mean is over all epochs, so the blocks do not change it)."""
    step = shifts[1] - shifts[0]
    cols = np.arange(misfit.shape[1])
    out = np.empty(shifts.size)
    rows = max(1, BLOCK_ELEMENTS // max(cols.size, 1))
    for r in range(0, shifts.size, rows):
        lines = shifts[r:r + rows, None] + slope * t_epoch[None, :]
        pos = np.clip((lines - shifts[0]) / step, 0.0, shifts.size - 1.000001)
        i = pos.astype(int)
        f = pos - i
        out[r:r + rows] = np.mean((1 - f) * misfit[i, cols] + f * misfit[i + 1, cols], axis=-1)
    return out


def segment_offsets(misfit, shifts, t_epoch) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Best offset of each of :data:`SEGMENTS` segments: (mid times, offsets, weights =
    misfit curvature at the best offset, zero where the best is at the search's edge)."""
    mids, best, weight = [], [], []
    step = shifts[1] - shifts[0]
    for cols in np.array_split(np.arange(misfit.shape[1]), SEGMENTS):
        c = misfit[:, cols].mean(axis=1)
        p = parabola_min(c)
        i = int(round(p))
        inside = 0 < i < c.size - 1
        mids.append(t_epoch[cols].mean())
        best.append(shifts[0] + p * step)
        weight.append(max(c[i - 1] - 2 * c[i] + c[i + 1], 0.0) if inside else 0.0)
    return np.array(mids), np.array(best), np.array(weight)


def estimate_clock(t_imu, dtheta_b, t_ref, q_ref, lat_rad) -> ClockMap:
    """The reference's clock map (:class:`ClockMap`, DVL offset 0) from the gyro track.

    Parameters
    ----------
    t_imu, dtheta_b : IMU times (K,) and rotation increments (K-1, 3) in the body frame
        the reference attitude is given for.
    t_ref, q_ref : reference file stamps (J,) and attitude quaternions (J, 4) body to ENU.
    lat_rad : latitude for the earth rate.
    """
    dt = float(np.median(np.diff(t_imu)))
    n = int(round(MAX_OFFSET_S / dt))
    shifts = np.arange(-n, n + 1) * dt
    track = GyroTrack(t_imu, dtheta_b, t_ref, q_ref, lat_rad)
    misfit, j = epoch_misfits(track, t_ref, q_ref, shifts)
    mids, best, w = segment_offsets(misfit, shifts, t_ref[j])
    # weighted straight line offset(t) = a + b t through the segment offsets; with fewer
    # than three informative segments the slope is left at zero (the clocks' rates equal)
    b = 0.0
    if np.count_nonzero(w > 1e-3 * w.max(initial=0.0)) >= 3:
        A = np.column_stack([np.ones_like(mids), mids]) * np.sqrt(w)[:, None]
        b = float(np.linalg.lstsq(A, best * np.sqrt(w), rcond=None)[0][1])
    # the offset at the start, refined along the fitted slope over every epoch
    c = _along(misfit, shifts, b, t_ref[j])
    a = shifts[0] + parabola_min(c) * dt
    # label = t_ref; the event happened at t_imu = label - (a + b * label)
    rate = 1.0 / (1.0 - b)
    return ClockMap(offset_s=float(a * rate), rate=float(rate))


#: the DVL offset is determined when the best shift's misfit is this many times below the
#: spread of the misfit over the search (the A-KIT trajectories give 30-250; a constant
#: speed, where every shift fits alike, gives the noise's ~0.1)
MIN_OFFSET_CONTRAST = 1.0


def dvl_offset(t_dvl, fwd_dvl, t_ref, fwd_ref, dt: float) -> float:
    """Seconds by which the DVL's stamps trail the reference's (both 1 Hz): the shift that
    best matches its forward velocity to the reference's (rotated into the body),
    searched in steps ``dt`` over +-:data:`MAX_OFFSET_S`, parabola-refined.

    When the forward speed hardly changes, every shift fits alike and the minimum is noise
    (it could land anywhere in the search, even at its edge); the offset then does not
    matter either, and 0 is returned (:data:`MIN_OFFSET_CONTRAST`).
    """
    n = int(round(MAX_OFFSET_S / dt))
    shifts = np.arange(-n, n + 1) * dt
    ok = (t_dvl - MAX_OFFSET_S >= t_ref[0]) & (t_dvl + MAX_OFFSET_S <= t_ref[-1])
    cost = np.array([np.mean((fwd_dvl[ok] - np.interp(t_dvl[ok] - s, t_ref, fwd_ref)) ** 2)
                     for s in shifts])
    lo = float(np.min(cost))
    if not float(np.max(cost)) - lo > MIN_OFFSET_CONTRAST * lo:
        return 0.0
    return float(shifts[0] + parabola_min(cost) * dt)
