"""From rate samples (gyro deg/s, accelerometer g) to IMU increments on a chosen grid.

Real IMUs log *rate* samples — angular rate and specific force at sample instants — while
the strapdown integrator and the filters take *increments* over intervals.  Here:

* **Sample times.**  A MEMS IMU samples on its own regular clock; the logged millisecond
  ticks carry quantisation and read-out jitter.  :func:`regular_sample_times` counts the
  nominal periods between ticks (so dropped samples leave a gap of whole periods) and fits
  one straight line ``tick = c0 + P n`` through all of them, which removes the jitter and
  keeps the clock's true rate.  When the ticks are not regular (residuals over half a
  period) the raw ticks are kept.
* **Integration.**  Between samples the rate is taken as linear (the trapezoid rule), so
  the running integral is piecewise quadratic and can be evaluated at any instant:
  :func:`integrate_rates` returns the increments between arbitrary boundaries (a uniform
  grid aligned to GPST, or the sample instants themselves).  Across a gap from dropped
  samples the rate is interpolated linearly as well; the gaps are reported.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SampleClock", "regular_sample_times", "integrate_rates", "interval_of",
           "RateIntegrator", "grid_bounds"]


@dataclass(frozen=True)
class SampleClock:
    """Regularised sample times of a rate-sampled IMU.

    Attributes
    ----------
    time_ms : ndarray, shape (K,)
        Sample times on the IMU's clock [ms] (dejittered, or the raw ticks).
    period_ms : float
        Fitted sample period [ms].
    n_missing : int
        Samples missing between the first and the last (dropouts).
    max_gap_ms : float
        Longest interval between consecutive samples [ms].
    jitter_ms : float
        Largest |tick - fitted time| [ms].
    regular : bool
        Whether the fit was used (``False``: raw ticks kept).
    p0_ms : float
        Median tick step [ms], the unit the steps are counted in.
    c0_ms : float
        The fitted clock at the first sample [ms] (``time_ms = c0 + period n``).
    """

    time_ms: np.ndarray
    period_ms: float
    n_missing: int
    max_gap_ms: float
    jitter_ms: float
    regular: bool
    p0_ms: float = float("nan")
    c0_ms: float = float("nan")


def regular_sample_times(tick_ms) -> SampleClock:
    """Fit a regular sample clock through jittered, increasing ticks [ms]."""
    tick = np.asarray(tick_ms, dtype=float)
    step = np.diff(tick)
    p0 = float(np.median(step))
    counts = np.maximum(np.rint(step / p0), 1.0)
    n = np.concatenate([[0.0], np.cumsum(counts)])
    del step, counts  # a recording of a day has millions of ticks: hold no more than needed
    period, c0 = np.polyfit(n, tick, 1)
    resid = tick - (c0 + period * n)
    jitter = float(np.max(np.abs(resid)))
    del resid
    regular = jitter < 0.5 * period
    times = c0 + period * n if regular else tick
    return SampleClock(time_ms=times, period_ms=float(period),
                       n_missing=int(n[-1] - (tick.size - 1)),
                       max_gap_ms=float(np.max(np.diff(times))), jitter_ms=jitter,
                       regular=bool(regular), p0_ms=p0, c0_ms=float(c0))


def integrate_rates(t_s, rate, bounds_s, block_samples=None) -> np.ndarray:
    """Integrals of a piecewise-linear rate between consecutive boundaries.

    Parameters
    ----------
    t_s : ndarray, shape (K,)
        Increasing sample times [s].
    rate : ndarray, shape (K, m), or callable
        Rate samples [unit/s], or ``rate(a, b) -> ndarray (b - a, m)``: the samples
        ``a .. b-1``, asked for in consecutive blocks (made when needed, e.g. from rows
        read and rotated block by block).
    bounds_s : ndarray, shape (M+1,)
        Increasing boundaries inside ``[t_s[0], t_s[-1]]``.
    block_samples : int, optional
        Work through the samples this many at a time (default: all at once); the result
        is the same to the last bit (:class:`RateIntegrator` carries the running integral
        across blocks and sums in the same order).

    Returns
    -------
    ndarray, shape (M, m)
        ``int_{bounds[j]}^{bounds[j+1]} rate dt`` [unit].
    """
    t = np.asarray(t_s, dtype=float)
    b = np.asarray(bounds_s, dtype=float)
    rate_of = rate if callable(rate) else (lambda lo, hi, w=np.asarray(rate, float): w[lo:hi])
    i = interval_of(t, b)
    step = t.size - 1 if block_samples is None else max(int(block_samples), 1)
    acc, out, done = RateIntegrator(), None, 0
    for s0 in range(0, t.size - 1, step):
        s1 = min(s0 + step, t.size - 1)  # intervals s0 .. s1-1, samples s0 .. s1
        lo, hi = np.searchsorted(i, s0, side="left"), np.searchsorted(i, s1 - 1, side="right")
        inc = acc.add(t[s0:s1 + 1], rate_of(s0, s1 + 1), b[lo:hi], i[lo:hi] - s0)
        if out is None:
            out = np.empty((b.size - 1, inc.shape[1]))
        out[done:done + inc.shape[0]] = inc
        done += inc.shape[0]
    return out


def interval_of(t_s, bounds_s) -> np.ndarray:
    """Index of the sample interval ``[t_s[i], t_s[i+1])`` holding each boundary (a boundary
    on a sample opens that sample's interval; one on the last sample closes the last)."""
    return np.clip(np.searchsorted(t_s, bounds_s, side="right") - 1, 0, t_s.size - 2)


class RateIntegrator:
    """:func:`integrate_rates` fed one block of samples at a time, the running integral
    carried from block to block (a file read in blocks is integrated as it is read).

    Each block's first sample is the previous block's last; the boundaries given with a
    block are those whose interval (:func:`interval_of` over the whole run) lies in it.
    The sums run in the order of the whole run's, so any blocking gives its increments to
    the last bit.
    """

    def __init__(self):
        self.cum0 = None  # the running integral at the previous block's last sample
        self.last = None  # the running integral at the previous block's last boundary

    def add(self, t, w, bounds, k) -> np.ndarray:
        """The increments between the boundaries seen so far that end in this block.

        Parameters
        ----------
        t : ndarray, shape (S+1,)
            The block's sample times (the first is the previous block's last).
        w : ndarray, shape (S+1, m)
            The rates at those samples.
        bounds : ndarray, shape (B,)
            The boundaries in the block's intervals, increasing.
        k : ndarray of int, shape (B,)
            The interval of each within the block (``0 .. S-1``).

        Returns
        -------
        ndarray, shape (B', m)
            One increment per boundary after the first of the run (``B - 1`` on the block
            holding the first boundary, else ``B``).
        """
        h = np.diff(t)
        area = 0.5 * (w[:-1] + w[1:]) * h[:, None]
        if self.cum0 is None:  # the running integral from zero, summed in order
            cum = np.concatenate([np.zeros((1, w.shape[1])), np.cumsum(area, axis=0)])
        else:  # ... carried on from the previous block's last sample
            cum = np.cumsum(np.concatenate([self.cum0[None], area]), axis=0)
        self.cum0 = cum[-1]
        tau = (bounds - t[:-1][k])[:, None]
        slope = (w[k + 1] - w[k]) / h[k, None]
        running = cum[k] + w[k] * tau + 0.5 * slope * tau * tau
        if self.last is not None and running.shape[0]:
            running = np.concatenate([self.last[None], running])
        if running.shape[0]:
            self.last = running[-1]
        return np.diff(running, axis=0)


def grid_bounds(t_first_s: float, t_last_s: float, rate_hz: float) -> np.ndarray:
    """Boundaries at whole multiples of ``1/rate_hz`` within ``[t_first_s, t_last_s]``."""
    k0 = int(np.ceil(t_first_s * rate_hz - 1e-9))
    k1 = int(np.floor(t_last_s * rate_hz + 1e-9))
    return np.arange(k0, k1 + 1) / float(rate_hz)
