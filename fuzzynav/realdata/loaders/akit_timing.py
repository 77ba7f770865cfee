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
  the start is refined over all epochs along that line;
* when that map leaves the offsets searched (a clock drifting further over the file than
  +-:data:`MAX_OFFSET_S`), the search is made again in blocks of :data:`FOLLOW_BLOCK_S`,
  each about the offset the blocks before it predict (:func:`followed_clock`);
  :class:`ClockSearch` says where it looked, so that a map at its edge is refused.

A time offset is observable only where the turn rate changes (for a steady rate the shifted
increments are the same), which the misfit curvature reflects: segments are weighted by it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.nav import attitude, attitude_chain

__all__ = ["EARTH_RATE", "MAX_OFFSET_S", "SEGMENTS", "BLOCK_ELEMENTS", "ClockMap",
           "ClockSearch", "FOLLOW_BLOCK_S", "SEARCH_EDGE_S", "followed_clock",
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


#: reference seconds per block of the search that follows a drifting clock: at the largest
#: plausible rate error (1 %) the offset moves 1 s over a block, well inside the offsets
#: searched about where the blocks before it predict
FOLLOW_BLOCK_S = 100.0
#: how near [s] the map's offset may come to the edge of the offsets searched
SEARCH_EDGE_S = 0.05


@dataclass(frozen=True)
class ClockSearch:
    """Where the clock search looked: from reference stamp ``starts_s[i]`` on, the offsets
    ``centres_s[i] +- MAX_OFFSET_S`` (one search centred on 0 unless the clock drifted out
    of it and the search followed, :func:`followed_clock`)."""

    starts_s: np.ndarray
    centres_s: np.ndarray

    def from_centre(self, clock: ClockMap, labels) -> tuple[np.ndarray, np.ndarray]:
        """``clock``'s offsets ``label - t_imu`` at reference stamps ``labels`` and the
        centres of the offsets searched there."""
        labels = np.asarray(labels, float)
        k = np.clip(np.searchsorted(self.starts_s, labels, side="right") - 1, 0, None)
        return labels - clock.to_imu(labels), self.centres_s[k]

    def inside(self, clock: ClockMap, labels) -> bool:
        """``clock``'s offset stays :data:`SEARCH_EDGE_S` inside the offsets searched at
        every stamp of ``labels``: the map is a measurement, not the search's edge."""
        gap, centre = self.from_centre(clock, labels)
        return bool(np.all(np.abs(gap - centre) < MAX_OFFSET_S - SEARCH_EDGE_S))


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
    """The track's next quaternions after ``q_last``, one per increment of ``dtheta_b``:
    the increments' quaternions a block at a time, chained by the compiled loop
    (:func:`fuzzynav.nav.attitude_chain.chain_into`)."""
    q = np.empty((dtheta_b.shape[0], 4))
    last = np.asarray(q_last, dtype=float)
    for s0 in range(0, dtheta_b.shape[0], BLOCK_ELEMENTS):
        dq = attitude.rotvec_to_quat(dtheta_b[s0:s0 + BLOCK_ELEMENTS])
        attitude_chain.chain_into(last, dq, q[s0:s0 + dq.shape[0]])
        last = q[s0 + dq.shape[0] - 1]
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
    keep : samples held before the last window's first, so that the next window may start
        up to that many earlier.
    """

    def __init__(self, t_imu, dtheta_b, t_ref, q_ref, lat_rad, keep: int = 0):
        self.t_imu, self.dtheta_b, self.earth = t_imu, dtheta_b, (t_ref, q_ref, lat_rad)
        self.keep = keep
        self.start = 0  # the sample of q[0], the increment of gyro[0]
        self.q = np.array([[1.0, 0.0, 0.0, 0.0]])
        self.gyro = np.empty((0, 3))

    def window(self, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray]:
        """``(q, gyro)``: the track at samples ``lo..hi`` and the increments ``lo..hi`` (up
        to the last); ``lo`` must not be before an earlier window's less ``keep``."""
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
        first = lo - self.start
        return self.q[first:hi - self.start + 1], self.gyro[first:hi - self.start + 1]

    def _make_gyro(self, upto: int) -> None:
        """The increments up to ``upto``, less the earth rate."""
        end = self.start + self.gyro.shape[0]
        if upto >= end:
            new = without_earth_rate(self.t_imu[end:upto + 2], self.dtheta_b[end:upto + 1],
                                     *self.earth)
            self.gyro = np.concatenate([self.gyro, new])

    def _drop(self, lo: int) -> None:
        """Let go of the samples before ``lo`` less ``keep``."""
        cut = lo - self.keep - self.start
        if cut > 0:
            self.q, self.gyro, self.start = self.q[cut:], self.gyro[cut:], self.start + cut


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
    if not j.size:
        return misfit, j
    # a block's pairs, and the track's samples its epochs span (one shift would otherwise
    # ask for hours of track at once)
    per_epoch = (t_imu.size - 1) / (t_imu[-1] - t_imu[0]) * float(np.median(np.diff(t_ref)))
    step = max(1, int(min(BLOCK_ELEMENTS // shifts.size, BLOCK_ELEMENTS / max(per_epoch, 1.0))))
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


def _along(misfit, origin, starts, slope: float, t_epoch) -> np.ndarray:
    """Mean misfit over epochs along each line of shifts ``starts[i] + slope t_epoch``, the
    misfit interpolated between its sampled shifts (``origin``, per epoch or one for all,
    then IMU-sample steps); a block of lines at a time (each line's mean is over all
    epochs, so the blocks do not change it)."""
    step = starts[1] - starts[0]
    cols = np.arange(misfit.shape[1])
    out = np.empty(starts.size)
    rows = max(1, BLOCK_ELEMENTS // max(cols.size, 1))
    for r in range(0, starts.size, rows):
        lines = starts[r:r + rows, None] + slope * t_epoch[None, :]
        pos = np.clip((lines - origin) / step, 0.0, misfit.shape[0] - 1.000001)
        i = pos.astype(int)
        f = pos - i
        out[r:r + rows] = np.mean((1 - f) * misfit[i, cols] + f * misfit[i + 1, cols], axis=-1)
    return out


def _best(cost, origin: float, step: float) -> tuple[float, float]:
    """The best shift of mean misfits ``cost`` sampled from ``origin`` in ``step``s and its
    weight (the misfit's curvature there; zero at the search's edge)."""
    p = parabola_min(cost)
    i = int(round(p))
    inside = 0 < i < cost.size - 1
    return (origin + p * step,
            max(cost[i - 1] - 2 * cost[i] + cost[i + 1], 0.0) if inside else 0.0)


def segment_offsets(misfit, shifts, t_epoch) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Best offset of each of :data:`SEGMENTS` segments: (mid times, offsets, weights =
    misfit curvature at the best offset, zero where the best is at the search's edge)."""
    mids, best, weight = [], [], []
    for cols in np.array_split(np.arange(misfit.shape[1]), SEGMENTS):
        b, w = _best(misfit[:, cols].mean(axis=1), shifts[0], shifts[1] - shifts[0])
        mids.append(t_epoch[cols].mean())
        best.append(b)
        weight.append(w)
    return np.array(mids), np.array(best), np.array(weight)


def _line(mids, best, w, least: int) -> tuple[float, float]:
    """``(a, b)`` of the straight line ``offset(t) = a + b t`` through offsets ``best`` at
    ``mids`` weighted by ``w``; with fewer than ``least`` informative ones (weight over
    1e-3 of the largest) ``b = 0`` and ``a`` their weighted mean (0 without any)."""
    mids, best, w = (np.asarray(x, float) for x in (mids, best, w))
    keep = w > 1e-3 * w.max(initial=0.0)
    if np.count_nonzero(keep) >= least:
        A = np.column_stack([np.ones_like(mids), mids]) * np.sqrt(w)[:, None]
        a, b = np.linalg.lstsq(A, best * np.sqrt(w), rcond=None)[0]
        return float(a), float(b)
    return (float(np.sum(w[keep] * best[keep]) / np.sum(w[keep])) if keep.any() else 0.0), 0.0


def _refined(misfit, origin, starts, slope: float, t_epoch, dt: float) -> ClockMap:
    """The map whose offset at the start is refined along ``slope`` over every epoch, from
    the lines starting at ``starts`` (:func:`_along`)."""
    a = starts[0] + parabola_min(_along(misfit, origin, starts, slope, t_epoch)) * dt
    # label = t_ref; the event happened at t_imu = label - (a + b * label)
    rate = 1.0 / (1.0 - slope)
    return ClockMap(offset_s=float(a * rate), rate=float(rate))


def _informed_time(misfit, t_epoch) -> float:
    """The time a block's best offset describes: its epochs' mean time weighted by how much
    each epoch's misfit changes over the offsets (a steady turn rate says nothing of the
    offset; the block's mean misfit is dominated by the epochs where it changes)."""
    w = misfit.max(axis=0) - misfit.min(axis=0)
    return float(np.sum(w * t_epoch) / np.sum(w)) if np.sum(w) > 0.0 else float(t_epoch.mean())


def estimate_clock(t_imu, dtheta_b, t_ref, q_ref, lat_rad) -> tuple[ClockMap, ClockSearch]:
    """The reference's clock map (:class:`ClockMap`, DVL offset 0) from the gyro track, and
    where it was searched for (:class:`ClockSearch`).

    The offsets +-:data:`MAX_OFFSET_S` are searched over the whole reference; when the map
    found leaves them (a clock drifting further over the file), the search is made again
    following the drift (:func:`followed_clock`).

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
    misfit, j = epoch_misfits(GyroTrack(t_imu, dtheta_b, t_ref, q_ref, lat_rad), t_ref,
                              q_ref, shifts)
    # the slope of the line through the segment offsets (zero with fewer than three
    # informative segments: the clocks' rates equal), then the offset along it
    slope = _line(*segment_offsets(misfit, shifts, t_ref[j]), least=3)[1]
    clock = _refined(misfit, shifts[0], shifts, slope, t_ref[j], dt)
    search = ClockSearch(t_ref[:1].copy(), np.zeros(1))
    if search.inside(clock, t_ref):
        return clock, search
    del misfit  # held no longer than the search made again
    return followed_clock(t_imu, dtheta_b, t_ref, q_ref, lat_rad, shifts)


def followed_clock(t_imu, dtheta_b, t_ref, q_ref, lat_rad, shifts
                   ) -> tuple[ClockMap, ClockSearch]:
    """The clock search following a drifting clock: the reference in blocks of
    :data:`FOLLOW_BLOCK_S`, each searched over ``shifts`` about the offset the line through
    the blocks before it predicts there (moved by at most :data:`MAX_OFFSET_S` a block),
    then the line through every block's best offset and the offset along it refined as
    :func:`estimate_clock` does over the one search."""
    dt = shifts[1] - shifts[0]
    track = GyroTrack(t_imu, dtheta_b, t_ref, q_ref, lat_rad,
                      keep=2 * shifts.size)  # a centre moved back needs samples let go
    edges = np.append(np.searchsorted(t_ref, np.arange(t_ref[0], t_ref[-1], FOLLOW_BLOCK_S)),
                      t_ref.size - 1)
    misfit, origin, t_epoch = (np.empty((shifts.size, t_ref.size - 1)),
                               np.empty(t_ref.size - 1), np.empty(t_ref.size - 1))
    fits, centres, used = ([], [], []), [0.0], 0
    for e0, e1 in zip(edges[:-1].tolist(), edges[1:].tolist()):
        a, b = _line(*fits, least=2)
        want = a + b * 0.5 * (t_ref[e0] + t_ref[e1])
        centre = centres[-1] + dt * round(np.clip(want - centres[-1], -MAX_OFFSET_S,
                                                  MAX_OFFSET_S) / dt)
        centres.append(centre)
        m, jj = epoch_misfits(track, t_ref[e0:e1 + 1], q_ref[e0:e1 + 1], centre + shifts)
        if jj.size:
            cols = slice(used, used + jj.size)
            misfit[:, cols], origin[cols], t_epoch[cols] = m, centre + shifts[0], t_ref[e0 + jj]
            for seq, x in zip(fits, (_informed_time(m, t_epoch[cols]), *_best(m.mean(axis=1),
                                                                  centre + shifts[0], dt))):
                seq.append(x)
            used += jj.size
    a, slope = _line(*fits, least=3)
    clock = _refined(misfit[:, :used], origin[:used], dt * round(a / dt) + shifts, slope,
                     t_epoch[:used], dt)
    return clock, ClockSearch(t_ref[edges[:-1]], np.array(centres[1:]))


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
