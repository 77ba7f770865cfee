"""Navigation errors against truth, RMS metrics and Monte-Carlo statistics.

Metric names carry their unit: ``rms_pos_e_m``, ``rms_vel_n_mps``, ``rms_heading_deg``, ...
Aggregates over Monte-Carlo runs report the mean with a 95 % Student-t confidence interval;
comparisons between two filters on the same seeds are paired (bootstrap over seeds).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from fuzzynav.block_sums import BlockSums
from fuzzynav.live_cache import LiveCache
from fuzzynav.nav import attitude, earth

__all__ = ["AXES", "ATT_NAMES", "NavErrors", "errors_vs_trajectory", "errors_vs_reference",
           "rms_metrics", "StreamingRms", "Estimate", "mean_ci", "crossed_ci", "summary_json",
           "improvement_ci"]

AXES = ("e", "n", "u")
ATT_NAMES = ("pitch", "roll", "heading")


@dataclass(frozen=True)
class NavErrors:
    """Errors (estimate minus truth) at common epochs.

    Attributes
    ----------
    time_s : (K,)
    pos_m : (K, 3) ENU position error [m].
    vel_mps : (K, 3) ENU velocity error [m/s] (NaN when the truth has none).
    att_rad : (K, 3) pitch, roll, heading errors [rad], wrapped (NaN without attitude truth).
    """

    time_s: np.ndarray
    pos_m: np.ndarray
    vel_mps: np.ndarray
    att_rad: np.ndarray


def _enu_difference(lla, lla_ref):
    """ENU difference of nearby geodetic points, row by row (first order in the offset)."""
    d = lla - lla_ref
    return earth.delta_lla_to_enu(d[:, 0], d[:, 1], d[:, 2], lla_ref[:, 0], lla_ref[:, 2])


@dataclass(frozen=True)
class _TruthAt:
    """A trajectory's truth at a result's epochs, with the local radii of its positions."""

    time_s: np.ndarray
    lla: np.ndarray
    vel_n: np.ndarray
    att: np.ndarray
    r_m_h: np.ndarray      # R_M + h
    r_n_h: np.ndarray      # R_N + h
    cos_lat: np.ndarray


#: truth sampled at a result's epochs, per live trajectory: every run of a study on a log
#: asks for the same epochs (a few :class:`_TruthAt` per trajectory; an entry goes with its
#: trajectory, so the memo never keeps a log alive)
_TRUTH_AT = LiveCache()


def _truth_at(truth, time_s) -> _TruthAt:
    kept = _TRUTH_AT.get(truth, ())
    for got in kept:
        if got.time_s.shape == time_s.shape and np.array_equal(got.time_s, time_s):
            return got
    k = np.clip(np.searchsorted(truth.time_s, time_s - 1e-9), 0, truth.time_s.size - 1)
    if np.abs(truth.time_s[k] - time_s).max() > 1e-6:
        raise ValueError("result epochs are not on the truth's sample grid")
    lla = truth.lla[k]
    r_m, r_n = earth.radii(lla[:, 0])
    got = _TruthAt(time_s.copy(), lla, truth.vel_n[k], truth.att[k], r_m + lla[:, 2],
                   r_n + lla[:, 2], np.cos(lla[:, 0]))
    _TRUTH_AT.put(truth, kept[-3:] + (got,))  # a few grids per log (output rates, early stops)
    return got


def errors_vs_trajectory(result, truth) -> NavErrors:
    """Errors of a filter result against a simulated :class:`Trajectory` (same clock).

    The truth at the result's epochs is remembered per trajectory (runs on one log share
    their epochs); the errors are computed as :func:`_enu_difference` and
    :func:`~fuzzynav.nav.attitude.euler_error` compute them, to the last bit.
    """
    ref = _truth_at(truth, result.time_s)
    att_err = attitude.euler_error(result.att, ref.att)
    d = result.lla - ref.lla
    # earth.delta_lla_to_enu with the radii of the reference positions kept
    pos = np.stack([d[:, 1] * ref.r_n_h * ref.cos_lat, d[:, 0] * ref.r_m_h, d[:, 2]], -1)
    return NavErrors(result.time_s, pos, result.vel_n - ref.vel_n, att_err)


def errors_vs_reference(result, ref_time_s, ref_lla, ref_vel_n=None) -> NavErrors:
    """Errors against a reference trajectory sampled at other times (e.g. RTK fixes).

    The filter solution is interpolated linearly to the reference epochs inside its span.
    """
    t = np.asarray(ref_time_s, float)
    inside = (t >= result.time_s[0]) & (t <= result.time_s[-1])
    t = t[inside]
    lla = np.column_stack([np.interp(t, result.time_s, result.lla[:, i]) for i in range(3)])
    vel = np.column_stack([np.interp(t, result.time_s, result.vel_n[:, i]) for i in range(3)])
    pos_err = _enu_difference(lla, np.asarray(ref_lla, float)[inside])
    vel_err = vel - np.asarray(ref_vel_n, float)[inside] if ref_vel_n is not None \
        else np.full_like(vel, np.nan)
    return NavErrors(t, pos_err, vel_err, np.full_like(vel, np.nan))


def rms_metrics(err: NavErrors, t_start_s: float = 0.0) -> dict:
    """RMS of every axis after ``t_start_s`` (skips the initial convergence).

    Returns a dict with ``rms_pos_{e,n,u}_m``, ``rms_pos_h_m`` (horizontal),
    ``rms_pos_m`` (3-D), ``rms_vel_{e,n,u}_mps``, ``rms_vel_mps``, ``rms_vel_h_mps``
    (horizontal), ``final_pos_h_m`` (horizontal error at the end),
    ``rms_{pitch,roll,heading}_deg``, ``rms_att_deg`` (RMS over the three angles) and
    ``max_pos_h_m`` and ``mean_pos_h_m`` (largest and mean horizontal error, paper 004).

    It is :class:`StreamingRms` fed the whole run as one chunk, so a run scored chunk by
    chunk reports these figures to the last bit; up to :data:`~fuzzynav.block_sums.
    BLOCK_COLUMNS` epochs each RMS is ``sqrt(mean(x ** 2))`` as numpy computes it.
    """
    sel = err.time_s >= t_start_s
    if not sel.all():  # the usual case (no convergence skipped) needs no copies
        err = NavErrors(err.time_s[sel], err.pos_m[sel], err.vel_mps[sel], err.att_rad[sel])
    acc = StreamingRms(-np.inf)
    acc.add(err)
    return acc.metrics()


class StreamingRms:
    """:func:`rms_metrics` accumulated over consecutive chunks of errors.

    Each chunk adds its squares and horizontal errors to :class:`~fuzzynav.block_sums.
    BlockSums` and its maximum and last error; :meth:`metrics` gives the same names as
    :func:`rms_metrics` without any array of the run.  The maxima are exact (NaN propagates
    as in ``np.max``); the sums are cut into blocks counted from the run's first scored
    epoch, not at the chunks, so every figure is the same to the last bit whatever the
    chunking (:func:`rms_metrics` is the case of one chunk).

    Parameters
    ----------
    t_start_s : float
        Errors before this time are left out (as :func:`rms_metrics`).
    truth : Trajectory, optional
        What :meth:`add_result` scores a filter result against.
    segments : SegmentRms, optional
        Also fed every chunk of errors; its per-segment metrics join :meth:`metrics`
        (:class:`fuzzynav.metrics_segments.SegmentRms`).
    """

    #: the RMS quantities in :func:`rms_metrics`' order, with the metric each goes into
    _RMS = (*(f"rms_pos_{ax}_m" for ax in AXES), "rms_pos_h_m", "rms_pos_m",
            *(f"rms_vel_{ax}_mps" for ax in AXES), "rms_vel_mps", "rms_vel_h_mps",
            *(f"rms_{nm}_deg" for nm in ATT_NAMES), "rms_att_deg")

    def __init__(self, t_start_s: float = 0.0, truth=None, segments=None):
        self.t_start_s, self.truth, self.segments = float(t_start_s), truth, segments
        self._sums = BlockSums(len(self._RMS) + 1)  # the squares, then the horizontal errors
        self._max_h, self._final_h = float("nan"), float("nan")

    def add_result(self, result) -> None:
        """Add a chunk of a filter result, scored against :attr:`truth`."""
        self.add(errors_vs_trajectory(result, self.truth))

    def add(self, err: NavErrors) -> None:
        """Add the next chunk of errors (times after those added before)."""
        if self.segments is not None:
            self.segments.add(err)
        k = int(np.searchsorted(err.time_s, self.t_start_s, side="left"))  # times increase
        n = err.time_s.shape[0] - k
        if n <= 0:
            return
        p, v = err.pos_m[k:], err.vel_mps[k:]
        # every summed quantity a contiguous row, in _RMS's order, then the horizontal error
        q = np.empty((len(self._RMS) + 1, n))
        q[0:3] = p.T
        h = q[3]
        np.hypot(p[:, 0], p[:, 1], out=h)
        q[4] = np.linalg.norm(p, axis=1)
        q[5:8] = v.T
        q[8] = np.linalg.norm(v, axis=1)
        np.hypot(v[:, 0], v[:, 1], out=q[9])
        a = np.rad2deg(err.att_rad[k:])
        q[10:13] = a.T
        q[13] = np.linalg.norm(a, axis=1)
        q[14] = h
        # the first chunk's maximum as it is; later ones through np.maximum (NaN sticks)
        big = float(np.max(h))
        self._max_h = big if self._sums.n == 0 else float(np.maximum(self._max_h, big))
        self._final_h = float(h[-1])
        np.square(q[:-1], out=q[:-1])
        self._sums.add(q, own=True)

    def metrics(self) -> dict:
        """The metrics of everything added (:func:`rms_metrics`' names and order; NaN
        when nothing was added)."""
        n = self._sums.n
        sums = self._sums.sums().tolist()
        rms = {k: (float(np.sqrt(s / n)) if n else float("nan"))
               for k, s in zip(self._RMS, sums)}
        out = {k: rms[k] for k in self._RMS[:5]}
        out["max_pos_h_m"] = self._max_h
        out["mean_pos_h_m"] = sums[-1] / n if n else float("nan")
        out.update({k: rms[k] for k in self._RMS[5:10]})
        out["final_pos_h_m"] = self._final_h
        out.update({k: rms[k] for k in self._RMS[10:]})
        if self.segments is not None:
            out.update(self.segments.metrics())
        return out


@dataclass(frozen=True)
class Estimate:
    """Mean of a metric over runs with its 95 % confidence interval."""

    mean: float
    lo: float
    hi: float
    n: int

    def __str__(self) -> str:
        if self.n < 2:
            return f"{self.mean:.4g}"
        return f"{self.mean:.4g} ± {self.half_width:.2g}"

    @property
    def half_width(self) -> float:
        """Half width of the interval."""
        return 0.5 * (self.hi - self.lo)


def mean_ci(values, level: float = 0.95) -> Estimate:
    """Mean and Student-t confidence interval of independent per-run values."""
    x = np.asarray(values, float)
    x = x[np.isfinite(x)]
    if x.size == 0:
        return Estimate(float("nan"), float("nan"), float("nan"), 0)
    m = float(x.mean())
    if x.size < 2:
        return Estimate(m, m, m, 1)
    h = stats.t.ppf(0.5 + level / 2, x.size - 1) * x.std(ddof=1) / np.sqrt(x.size)
    return Estimate(m, m - h, m + h, int(x.size))


def crossed_ci(values, level: float = 0.95) -> Estimate:
    """Mean and confidence interval of a table of paired differences whose rows (say,
    tunings) and columns (test seeds) are both random samples: a crossed two-way
    random-effects design without replication.

    ``values[i, j]`` is the difference on test seed ``j`` under tuning ``i``.  The variance
    of the grand mean is ``(MS_rows + MS_cols - MS_resid) / (r c)`` (the expected mean
    squares of the model), floored at ``MS_resid / (r c)``; its degrees of freedom are
    Satterthwaite's.  The interval therefore covers the mean over *new* tunings as well as
    new seeds -- wider than a paired test over seeds when tunings disagree.  With one row it
    is :func:`mean_ci` over the columns; with one column, over the rows.
    """
    x = np.asarray(values, float)
    if x.ndim != 2 or x.size == 0 or not np.isfinite(x).all():
        raise ValueError(f"crossed_ci needs a finite 2-D table, got shape {x.shape}")
    r, c = x.shape
    if r == 1 or c == 1:
        return mean_ci(x.ravel())
    m = float(x.mean())
    rows, cols = x.mean(axis=1), x.mean(axis=0)
    ms_r = c * float(((rows - m) ** 2).sum()) / (r - 1)
    ms_c = r * float(((cols - m) ** 2).sum()) / (c - 1)
    resid = x - rows[:, None] - cols[None, :] + m
    ms_e = float((resid ** 2).sum()) / ((r - 1) * (c - 1))
    num = ms_r + ms_c - ms_e
    if num <= ms_e:  # the estimate is no smaller than the residual noise alone
        num, df = ms_e, (r - 1) * (c - 1)
    else:
        df = num ** 2 / (ms_r ** 2 / (r - 1) + ms_c ** 2 / (c - 1)
                         + ms_e ** 2 / ((r - 1) * (c - 1)))
    if num == 0.0:
        return Estimate(m, m, m, int(x.size))
    h = stats.t.ppf(0.5 + level / 2, df) * np.sqrt(num / (r * c))
    return Estimate(m, m - h, m + h, int(x.size))


def summary_json(values) -> dict:
    """The JSON of per-run values in every table: ``{"mean", "ci95": [lo, hi], "values"}``
    (:func:`mean_ci`; non-finite values stay as floats: see :func:`fuzzynav.fileio.
    json_ready`)."""
    est = mean_ci(values)
    return {"mean": est.mean, "ci95": [est.lo, est.hi], "values": [float(x) for x in values]}


def improvement_ci(baseline, candidate, level: float = 0.95, n_boot: int = 2000,
                   seed: int = 0) -> Estimate:
    """Improvement [%] of ``candidate`` over ``baseline``: ``100 (1 - mean(c) / mean(b))``.

    Values are paired per run (same seeds); the interval is a percentile bootstrap over runs.
    Positive means the candidate's error is smaller.
    """
    b = np.asarray(baseline, float)
    c = np.asarray(candidate, float)
    ok = np.isfinite(b) & np.isfinite(c)
    b, c = b[ok], c[ok]
    if b.size == 0 or b.mean() == 0:
        return Estimate(float("nan"), float("nan"), float("nan"), 0)
    point = 100.0 * (1.0 - c.mean() / b.mean())
    if b.size < 2:
        return Estimate(point, point, point, 1)
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, b.size, (n_boot, b.size))
    boot = 100.0 * (1.0 - c[idx].mean(1) / b[idx].mean(1))
    lo, hi = np.percentile(boot, [50 * (1 - level), 50 * (1 + level)])
    return Estimate(point, float(lo), float(hi), int(b.size))
