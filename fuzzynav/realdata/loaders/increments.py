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

__all__ = ["SampleClock", "regular_sample_times", "integrate_rates", "grid_bounds"]


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
    """

    time_ms: np.ndarray
    period_ms: float
    n_missing: int
    max_gap_ms: float
    jitter_ms: float
    regular: bool


def regular_sample_times(tick_ms) -> SampleClock:
    """Fit a regular sample clock through jittered, increasing ticks [ms]."""
    tick = np.asarray(tick_ms, dtype=float)
    step = np.diff(tick)
    p0 = float(np.median(step))
    counts = np.maximum(np.rint(step / p0), 1.0)
    n = np.concatenate([[0.0], np.cumsum(counts)])
    period, c0 = np.polyfit(n, tick, 1)
    resid = tick - (c0 + period * n)
    jitter = float(np.max(np.abs(resid)))
    regular = jitter < 0.5 * period
    times = c0 + period * n if regular else tick
    return SampleClock(time_ms=times, period_ms=float(period),
                       n_missing=int(n[-1] - (tick.size - 1)),
                       max_gap_ms=float(np.max(np.diff(times))), jitter_ms=jitter,
                       regular=bool(regular))


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
        is the same to the last bit (the running integral is carried across blocks and
        summed in the same order).

    Returns
    -------
    ndarray, shape (M, m)
        ``int_{bounds[j]}^{bounds[j+1]} rate dt`` [unit].
    """
    t = np.asarray(t_s, dtype=float)
    b = np.asarray(bounds_s, dtype=float)
    rate_of = rate if callable(rate) else (lambda lo, hi, w=np.asarray(rate, float): w[lo:hi])
    # the sample interval of each boundary (the last interval holds the last sample)
    i = np.clip(np.searchsorted(t, b, side="right") - 1, 0, t.size - 2)
    step = t.size - 1 if block_samples is None else max(int(block_samples), 1)
    out, done, cum0, last = None, 0, None, None  # last: the previous block's last running
    for s0 in range(0, t.size - 1, step):
        s1 = min(s0 + step, t.size - 1)  # intervals s0 .. s1-1, samples s0 .. s1
        w = rate_of(s0, s1 + 1)
        h = np.diff(t[s0:s1 + 1])
        area = 0.5 * (w[:-1] + w[1:]) * h[:, None]
        if cum0 is None:  # the running integral from zero, summed in order
            cum = np.concatenate([np.zeros((1, w.shape[1])), np.cumsum(area, axis=0)])
        else:  # ... carried on from the previous block's last sample
            cum = np.cumsum(np.concatenate([cum0[None], area]), axis=0)
        cum0 = cum[-1]
        lo, hi = np.searchsorted(i, s0, side="left"), np.searchsorted(i, s1 - 1, side="right")
        k = i[lo:hi] - s0
        tau = (b[lo:hi] - t[s0:s1][k])[:, None]
        slope = (w[k + 1] - w[k]) / h[k, None]
        running = cum[k] + w[k] * tau + 0.5 * slope * tau * tau
        if last is not None and running.shape[0]:
            running = np.concatenate([last[None], running])
        if running.shape[0]:
            last = running[-1]
        inc = np.diff(running, axis=0)
        if out is None:
            out = np.empty((b.size - 1, w.shape[1]))
        out[done:done + inc.shape[0]] = inc
        done += inc.shape[0]
    return out


def grid_bounds(t_first_s: float, t_last_s: float, rate_hz: float) -> np.ndarray:
    """Boundaries at whole multiples of ``1/rate_hz`` within ``[t_first_s, t_last_s]``."""
    k0 = int(np.ceil(t_first_s * rate_hz - 1e-9))
    k1 = int(np.floor(t_last_s * rate_hz + 1e-9))
    return np.arange(k0, k1 + 1) / float(rate_hz)
