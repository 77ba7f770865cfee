"""Errors per motion segment of a simulated run, accumulated chunk by chunk.

A scenario is a sequence of motion segments (rest, accelerate, cruise, turn, ...); a
mission of a day is dozens of legs, and whether a fuzzy controller holds through the turns
is read from the legs, not from one RMS over the day.  :class:`SegmentRms` keeps, per
segment, the sums of squares, the exact maximum and the last horizontal error of the
epochs inside it, so a run of any length reports per-segment metrics without any array of
its length (the whole run is the case of one chunk).

Segment ``j`` (0-based) covers ``[edges_s[j], edges_s[j + 1])``: an epoch on a boundary
belongs to the segment that starts there; epochs at or after the last edge (the run's end)
belong to the last segment.  Its metrics are named :func:`key` ``(j, metric)``, e.g.
``seg3_rms_pos_h_m`` for the third segment; those of a segment with no epoch scored (it
ended before ``t_start_s``) are NaN.
"""
from __future__ import annotations

import numpy as np

from fuzzynav.block_sums import BlockSums
from fuzzynav.metrics import NavErrors

__all__ = ["SEGMENT_METRICS", "key", "scenario_edges_s", "SegmentRms", "segment_metrics",
           "for_scenario"]

#: metric -> description (SI, units in names): what each segment reports
SEGMENT_METRICS = {
    "rms_pos_h_m": "horizontal position RMS [m]",
    "max_pos_h_m": "largest horizontal position error [m]",
    "end_pos_h_m": "horizontal position error at the segment's last epoch [m]",
    "rms_pos_u_m": "vertical position RMS [m]",
    "rms_vel_h_mps": "horizontal velocity RMS [m/s]",
    "rms_heading_deg": "heading RMS [deg]",
}
#: the metrics summed as squares, in the order of the rows :meth:`SegmentRms.add` stacks
_RMS = ("rms_pos_h_m", "rms_pos_u_m", "rms_vel_h_mps", "rms_heading_deg")


def key(j: int, metric: str) -> str:
    """The metric name of ``metric`` of segment ``j`` (0-based): ``seg{j + 1}_{metric}``."""
    return f"seg{j + 1}_{metric}"


def scenario_edges_s(scenario) -> np.ndarray:
    """The segment boundaries of a scenario [s]: 0, then each segment's end (its
    trajectory starts at 0 s)."""
    return np.concatenate([[0.0], np.cumsum([s.duration_s for s in scenario.segments])])


class SegmentRms:
    """Per-segment metrics (:data:`SEGMENT_METRICS`) accumulated over chunks of errors.

    The maxima and end errors are exact; each segment's squares are summed in blocks
    counted from its first scored epoch (:class:`fuzzynav.block_sums.BlockSums`), so the
    RMS are the same to the last bit whatever the chunking, as
    :class:`fuzzynav.metrics.StreamingRms` has them.  A segment's part of a block waiting
    for more epochs is summed once a chunk starts after the segment's end.

    Parameters
    ----------
    edges_s : array_like, shape (K + 1,)
        Increasing segment boundaries [s] (:func:`scenario_edges_s`).
    t_start_s : float
        Errors before this time are left out (the run's scoring start).
    """

    def __init__(self, edges_s, t_start_s: float = 0.0):
        edges = np.asarray(edges_s, dtype=float)
        if edges.ndim != 1 or edges.size < 2 or not np.all(np.diff(edges) > 0):
            raise ValueError(f"segment edges must increase, at least two, got {edges_s!r}")
        self.edges_s, self.t_start_s = edges, float(t_start_s)
        k = edges.size - 1
        self._n = np.zeros(k, np.int64)
        self._sq = np.zeros((k, len(_RMS)))   # a segment's sums once it has ended
        self._open: dict = {}                  # segment -> BlockSums of a segment not ended
        self._max = np.full(k, np.nan)
        self._end = np.full(k, np.nan)

    def add(self, err: NavErrors) -> None:
        """Add the next chunk of errors (times after those added before)."""
        k = int(np.searchsorted(err.time_s, self.t_start_s, side="left"))
        t = err.time_s[k:]
        if not t.size:
            return
        # where each segment's epochs begin in this chunk: contiguous runs, times increase
        bounds = np.concatenate([[0], np.searchsorted(t, self.edges_s[1:-1], side="left"),
                                 [t.size]])
        active = np.flatnonzero(np.diff(bounds) > 0)
        self._close(int(active[0]))
        for j in active:
            rows = slice(k + bounds[j], k + bounds[j + 1])
            p, v = err.pos_m[rows], err.vel_mps[rows]
            q = np.empty((len(_RMS), p.shape[0]))
            h = q[0]
            np.hypot(p[:, 0], p[:, 1], out=h)
            q[1] = p[:, 2]
            np.hypot(v[:, 0], v[:, 1], out=q[2])
            q[3] = np.rad2deg(err.att_rad[rows, 2])
            big = float(np.max(h))   # the first part's as it is; NaN sticks after
            self._max[j] = big if self._n[j] == 0 else float(np.maximum(self._max[j], big))
            self._end[j] = h[-1]
            self._n[j] += p.shape[0]
            self._open.setdefault(int(j), BlockSums(len(_RMS))).add(np.square(q, out=q),
                                                                  own=True)

    def _close(self, before: int) -> None:
        """Sum the segments before ``before``: no later chunk reaches them."""
        for j in [j for j in self._open if j < before]:
            self._sq[j] = self._open.pop(j).sums()

    def metrics(self) -> dict:
        """``{key(j, metric): value}`` for every segment and :data:`SEGMENT_METRICS`."""
        out, sq = {}, self._sq.copy()
        for j, acc in self._open.items():
            sq[j] = acc.sums()
        for j, n in enumerate(self._n.tolist()):
            rms = dict(zip(_RMS, np.sqrt(sq[j] / n).tolist() if n else
                           [float("nan")] * len(_RMS)))
            vals = {**rms, "max_pos_h_m": float(self._max[j]),
                    "end_pos_h_m": float(self._end[j])}
            out.update({key(j, m): vals[m] for m in SEGMENT_METRICS})
        return out


def segment_metrics(err: NavErrors, edges_s, t_start_s: float = 0.0) -> dict:
    """:class:`SegmentRms` of a whole run's errors (one chunk)."""
    acc = SegmentRms(edges_s, t_start_s)
    acc.add(err)
    return acc.metrics()


def for_scenario(scenario, t_start_s: float = 0.0) -> SegmentRms:
    """The per-segment metrics of a run on ``scenario``, to be fed chunk by chunk."""
    return SegmentRms(scenario_edges_s(scenario), t_start_s)
