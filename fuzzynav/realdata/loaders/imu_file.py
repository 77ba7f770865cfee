"""A recording's IMU increments read from its CSV chunk by chunk, never held whole.

:func:`fuzzynav.realdata.loaders.rtklib.load_rtklib` with ``streamed=True`` reads the CSV
once for its timing (the ticks, the line lengths matched against the time tag: the clock
fits need every tick) and keeps only the numbers that put a row on GPST
(:class:`RowTimes`).  :class:`ImuFile` then reads the file again whenever increments are
wanted — for the load's checks, the coarse alignment's opening minutes, each filter run
— parsing a block of lines at a time, making each row's time and body-frame rates from
that row alone, and integrating them with the running integral carried across blocks
(:class:`~.increments.RateIntegrator`).  Each row's time is the same elementwise
arithmetic as the whole load's and the integral is summed in the same order, so the
increments are the whole load's to the last bit; what is held is one block.

The file must not change between the reads: its size and modification time are checked
before each (:meth:`ImuFile.identity`).
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fuzzynav import units
from fuzzynav.errors import InputFileError
from fuzzynav.realdata.loaders.imu_csv import parsed_blocks
from fuzzynav.realdata.loaders.increments import RateIntegrator
from fuzzynav.sim.imu import ImuData

__all__ = ["SCAN_BYTES_PER_LINE", "body_rates", "RowTimes", "ImuFile", "ImuCut",
           "without_gyro_bias"]

#: peak memory per line of the CSV of a streamed load beyond its parse block [bytes]: the
#: ticks (8), the lines' lengths and indices (4 + 4) held for the clock fits, and the fits'
#: working arrays; measured 83 at the fits' peak (tracemalloc, synthetic drives of 86 801 and
#: 266 801 lines in blocks of 4 096; tests/realdata/test_imu_file.py), rounded up.
#: Released once the load returns
SCAN_BYTES_PER_LINE = 128


def body_rates(rows, matrix=None) -> np.ndarray:
    """Gyro [rad/s] and accelerometer [m/s^2] rates of CSV rows (g, deg/s), in the body
    frame (``matrix``: the mounting's IMU-to-body rotation, ``None``: the IMU frame)."""
    out = np.column_stack([rows[:, 3:6] * units.DPS, rows[:, 0:3] * units.G0])
    if matrix is not None:
        out = np.column_stack([out[:, :3] @ matrix.T, out[:, 3:] @ matrix.T])
    return out


@dataclass(frozen=True)
class RowTimes:
    """How a CSV row's tick becomes its time [s since the recording's epoch].

    The regularised sample clock counts whole periods between ticks
    (:func:`~.increments.regular_sample_times`); the fitted arrival line and the IMU delay
    put it on GPST (:func:`~.rtklib.align_time`).  :meth:`of` repeats that arithmetic on
    any consecutive rows, the period count carried from the rows before.

    Attributes
    ----------
    p0_ms : float
        Median tick step [ms] (what a step is counted in periods of).
    c0_ms, period_ms : float
        The fitted clock ``c0 + period n``.
    regular : bool
        Whether the fitted clock is used (else the raw ticks).
    time0_ms : float
        The first row's clock time [ms].
    a_ms, b, delay_s, base_s : float
        ``t = base + ((a + b (clock - time0)) / 1000 - delay)``.
    """

    p0_ms: float
    c0_ms: float
    period_ms: float
    regular: bool
    time0_ms: float
    a_ms: float
    b: float
    delay_s: float
    base_s: float

    def of(self, tick, carry):
        """Times [s] of consecutive rows' ticks; ``carry``: ``(tick, n)`` of the row before
        (``None`` for the file's first row).  Returns ``(times, carry)``."""
        if carry is None:
            counts = np.maximum(np.rint(np.diff(tick) / self.p0_ms), 1.0)
            n = np.concatenate([[0.0], np.cumsum(counts)])
        else:
            counts = np.maximum(np.rint(np.diff(np.concatenate([[carry[0]], tick]))
                                        / self.p0_ms), 1.0)
            n = np.cumsum(np.concatenate([[carry[1]], counts]))[1:]
        clock = self.c0_ms + self.period_ms * n if self.regular else tick
        offset = (self.a_ms + self.b * (clock - self.time0_ms)) / 1000.0 - self.delay_s
        return self.base_s + offset, (tick[-1], n[-1])


@dataclass(frozen=True)
class ImuFile:
    """The increments of an RTKLIB IMU CSV, read from the file when asked for.

    Attributes
    ----------
    path : Path
    identity : tuple
        ``(size, mtime_ns)`` of the file when it was loaded.
    times : RowTimes
    matrix : ndarray or None
        The mounting's IMU-to-body rotation.
    grid_hz : float or None
        Increments between whole multiples of ``1/grid_hz`` s, or between the samples.
    span_s : (float, float)
        The first and last boundary [s].
    n_samples : int
        Number of increments.
    dt_nom_s : float
        Nominal increment interval [s].
    chunk_rows : int or None
        Lines parsed at a time.
    meta : dict
        As :class:`~fuzzynav.sim.imu.ImuData`'s (gaps, jitter, source).
    """

    path: Path
    identity: tuple
    times: RowTimes
    matrix: np.ndarray | None
    grid_hz: float | None
    span_s: tuple
    n_samples: int
    dt_nom_s: float
    chunk_rows: int | None
    meta: dict = field(default_factory=dict)

    @property
    def rate_hz(self) -> float:
        """The increments' nominal rate [Hz]."""
        return 1.0 / self.dt_nom_s

    @staticmethod
    def identity_of(path) -> tuple:
        """``(size, mtime_ns)`` of ``path``: what must not change between reads."""
        st = os.stat(path)
        return st.st_size, st.st_mtime_ns

    def samples(self):
        """Yield ``(t, w)`` per block of rows: their times [s] and body rates (gyro, accel),
        each block led by the previous block's last sample."""
        if self.identity_of(self.path) != self.identity:
            raise InputFileError(self.path, "", "changed since the recording was loaded "
                                                "(its size or modification time); load it "
                                                "again")
        carry, prev = None, None
        for _, _, rows, data in parsed_blocks(self.path, self.chunk_rows):
            if data is None or not rows.size:
                continue
            t, carry = self.times.of(data[:, 6], carry)
            w = body_rates(data, self.matrix)
            if prev is not None:
                t, w = np.concatenate([prev[0][-1:], t]), np.concatenate([prev[1][-1:], w])
            prev = (t, w)
            if t.size >= 2:
                yield t, w

    def _bounds(self, t, final: bool, done: int):
        """The boundaries of one block of samples ``t`` from the ``done``-th on."""
        lo, hi = self.span_s
        if self.grid_hz is None:
            cand = t if final else t[:-1]
            return cand[(cand >= lo) & (cand <= hi)]
        k0 = int(np.ceil(lo * self.grid_hz - 1e-9)) + done
        k1 = int(np.floor(hi * self.grid_hz + 1e-9))
        if not final:  # those below the block's last sample (a later one opens the next)
            k1 = min(k1, int(np.ceil(t[-1] * self.grid_hz)) + 1)
        b = np.arange(k0, k1 + 1) / float(self.grid_hz)
        return b if final else b[b < t[-1]]

    def pieces(self):
        """Yield :class:`~fuzzynav.sim.imu.ImuData` of consecutive increments, as the file's
        blocks give them (each piece starts at the previous piece's last time)."""
        acc, done, last_t = RateIntegrator(), 0, None
        for (t, w), final in _lookahead(self.samples()):
            b = self._bounds(t, final, done)
            done += b.size
            k = np.clip(np.searchsorted(t, b, side="right") - 1, 0, t.size - 2)
            inc = acc.add(t, w, b, k)
            times = b if last_t is None else np.concatenate([[last_t], b])
            if b.size:
                last_t = b[-1]
            if inc.shape[0]:
                yield ImuData(time_s=times, dtheta_b=inc[:, :3], dv_b=inc[:, 3:])

    def chunks(self, samples: int, start: int = 0):
        """Yield ImuData of ``samples`` increments each (the last may be shorter) from
        increment ``start`` on."""
        yield from _rechunk(self.pieces(), int(samples), int(start))

    def window(self, t0_s: float, t1_s: float) -> ImuData:
        """The increments whose intervals start in ``[t0_s, t1_s]``, held."""
        parts = []
        for p in self.pieces():
            if p.time_s[0] > t1_s:
                break
            sel = np.flatnonzero((p.time_s[:-1] >= t0_s) & (p.time_s[:-1] <= t1_s))
            if sel.size:
                parts.append(ImuData(p.time_s[sel[0]:sel[-1] + 2], p.dtheta_b[sel],
                                     p.dv_b[sel]))
        return _joined(parts, self.meta)


def _lookahead(it):
    """``(item, final)`` for each item, ``final`` true on the last."""
    prev = None
    for item in it:
        if prev is not None:
            yield prev, False
        prev = item
    if prev is not None:
        yield prev, True


def _rechunk(pieces, samples: int, start: int):
    """Consecutive pieces of increments cut into chunks of ``samples`` from ``start``."""
    if samples < 1:
        raise ValueError(f"samples must be >= 1, got {samples}")
    held, n_held, skip = [], 0, start
    for p in pieces:
        if skip >= p.n_samples:
            skip -= p.n_samples
            continue
        if skip:
            p = ImuData(p.time_s[skip:], p.dtheta_b[skip:], p.dv_b[skip:])
            skip = 0
        held.append(p)
        n_held += p.n_samples
        while n_held >= samples:
            whole = _joined(held, {})
            yield ImuData(whole.time_s[:samples + 1], whole.dtheta_b[:samples],
                          whole.dv_b[:samples])
            rest = ImuData(whole.time_s[samples:], whole.dtheta_b[samples:],
                           whole.dv_b[samples:])
            held, n_held = ([rest] if rest.n_samples else []), rest.n_samples
    if n_held:
        yield _joined(held, {})


def _joined(parts, meta) -> ImuData:
    """Consecutive pieces as one ImuData (each piece's first time is the last's last)."""
    if len(parts) == 1:
        p = parts[0]
        return ImuData(p.time_s, p.dtheta_b, p.dv_b, meta=dict(meta))
    if not parts:
        return ImuData(np.zeros(1), np.zeros((0, 3)), np.zeros((0, 3)), meta=dict(meta))
    return ImuData(np.concatenate([parts[0].time_s[:1]] + [p.time_s[1:] for p in parts]),
                   np.concatenate([p.dtheta_b for p in parts]),
                   np.concatenate([p.dv_b for p in parts]), meta=dict(meta))


@dataclass(frozen=True)
class ImuCut:
    """An :class:`ImuFile` from increment ``start`` on, a constant gyro bias removed: the
    filter's input after a start found on the data (:mod:`fuzzynav.realdata.session`).

    The bias is removed per increment as ``dtheta - bias * dt`` (the held start's
    arithmetic), so its chunks are the held start's to the last bit.

    Attributes
    ----------
    source : ImuFile
    start : int
        Index of the first increment used.
    gyro_bias_rps : ndarray, shape (3,)
        The gyro bias removed [rad/s].
    t0_s : float
        Time of increment ``start`` [s].
    """

    source: ImuFile
    start: int
    gyro_bias_rps: np.ndarray
    t0_s: float

    @property
    def span_s(self) -> tuple:
        """The first and last increment boundary [s]."""
        return self.t0_s, self.source.span_s[1]

    @property
    def n_samples(self) -> int:
        """Number of increments from the start on."""
        return self.source.n_samples - self.start

    @property
    def dt_nom_s(self) -> float:
        """Nominal increment interval [s] (the file's)."""
        return self.source.dt_nom_s

    @property
    def rate_hz(self) -> float:
        """Nominal increment rate [Hz] (the file's)."""
        return self.source.rate_hz

    @property
    def meta(self) -> dict:
        """The file's :attr:`ImuFile.meta`."""
        return self.source.meta

    def chunks(self, samples: int):
        """Yield ImuData chunks of ``samples`` increments, the bias removed."""
        for c in self.source.chunks(samples, self.start):
            yield without_gyro_bias(c, self.gyro_bias_rps)


def without_gyro_bias(imu: ImuData, gyro_bias_rps) -> ImuData:
    """``imu`` with a constant gyro bias [rad/s] removed from its angle increments
    (``dtheta - bias * dt``: per increment, so a chunk's is the whole run's slice)."""
    dth = imu.dtheta_b - gyro_bias_rps * np.diff(imu.time_s)[:, None]
    return ImuData(time_s=imu.time_s, dtheta_b=dth, dv_b=imu.dv_b, meta=dict(imu.meta))
