"""Scoring a run on a recording against its reference, whole or chunk by chunk.

Every recording source (:class:`~fuzzynav.realdata.session.GnssSource` for the car's RTK
fixes, :class:`~fuzzynav.realdata.akit.AkitSource` for the AUV's post-processed track)
scores through one :class:`ReferenceScoring`: ``errors(result)`` forms the errors at the
reference epochs inside the solution's span (the solution interpolated linearly to them,
:func:`fuzzynav.metrics.errors_vs_reference`), ``finish(errors, solution_times, result)``
turns them into the source's metrics.

A streamed run (``fuzzynav run --data ... --output-rate HZ``) hands each chunk of the
undecimated solution to a :class:`StreamedReferenceErrors`.  It forms the errors at the
reference epochs each chunk covers, with the previous chunk's last output row put in
front so that an epoch between two chunks is interpolated from the same two rows as in
the whole run; only the errors at the reference epochs (1-4 Hz; the reference itself is
held whole) and the few solution times ``finish`` reads are kept, never the solution.
Each error is computed from the same two rows by the same arithmetic, so the streamed
metrics equal the whole run's to the last bit, whatever the chunking (tests assert it).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable

import numpy as np

from fuzzynav.metrics import NavErrors

__all__ = ["ReferenceScoring", "StreamedReferenceErrors"]


@dataclass(frozen=True)
class ReferenceScoring:
    """How a recording's runs are scored against its reference.

    Attributes
    ----------
    errors : callable
        ``errors(result) -> NavErrors`` at the reference epochs inside ``result``'s span
        (it reads ``time_s``, ``lla``, ``vel_n``, ``q_bn`` only).
    finish : callable
        ``finish(errors, solution_time_s, result) -> metrics``; ``solution_time_s`` holds at
        least, for each of :attr:`marks_s`, the last solution time before it, and the last
        solution time; ``result`` is the run's (decimated) result, for its status.
    marks_s : tuple of float
        Instants before which ``finish`` reads the last solution time (outage ends).
    """

    errors: Callable
    finish: Callable
    marks_s: tuple = ()

    def __call__(self, result) -> dict:
        """The metrics of a whole result."""
        return self.finish(self.errors(result), result.time_s, result)

    def streaming(self) -> "StreamedReferenceErrors":
        """An accumulator to feed each chunk of a run's solution."""
        return StreamedReferenceErrors(self)

    def streamed(self, result, scorer: "StreamedReferenceErrors") -> dict:
        """The metrics of a run whose chunks were fed to ``scorer``."""
        return self.finish(scorer.errors(), scorer.solution_times(), result)


@dataclass(frozen=True)
class _Track:
    """The solution rows the errors read (:func:`~fuzzynav.realdata.score.antenna_track`
    replaces ``lla``)."""

    time_s: np.ndarray
    lla: np.ndarray
    vel_n: np.ndarray
    q_bn: np.ndarray

    @classmethod
    def of(cls, result, rows=slice(None)) -> "_Track":
        return cls(result.time_s[rows], result.lla[rows], result.vel_n[rows],
                   result.q_bn[rows])

    def then(self, other: "_Track") -> "_Track":
        return _Track(*(np.concatenate([getattr(self, f.name), getattr(other, f.name)])
                        for f in dataclasses.fields(self)))


def _rows(err: NavErrors, keep) -> NavErrors:
    return NavErrors(err.time_s[keep], err.pos_m[keep], err.vel_mps[keep], err.att_rad[keep])


class StreamedReferenceErrors:
    """The errors at the reference epochs of a run fed chunk by chunk (module docstring).

    Parameters
    ----------
    scoring : ReferenceScoring
    """

    def __init__(self, scoring: ReferenceScoring):
        self.scoring = scoring
        self._marks = np.asarray(scoring.marks_s, float).reshape(-1)
        self._before = np.full(self._marks.shape, np.nan)  # last solution time before each
        self._last = None   # the previous chunk's last row
        self._parts = []

    def add_result(self, chunk) -> None:
        """Add the next chunk of the solution (rows after those added before)."""
        if not np.size(chunk.time_s):
            return
        track = _Track.of(chunk)
        if self._last is None:
            err = self.scoring.errors(track)
        else:  # epochs up to the previous chunk's last row were scored with it
            err = self.scoring.errors(self._last.then(track))
            err = _rows(err, err.time_s > self._last.time_s[0])
        self._parts.append(err)
        t = track.time_s
        k = np.searchsorted(t, self._marks, side="left")  # rows before each mark
        has = k > 0
        self._before[has] = t[k[has] - 1]
        self._last = _Track.of(chunk, slice(-1, None))

    def errors(self) -> NavErrors:
        """The errors of everything added, in time order."""
        if not self._parts:
            empty = np.zeros((0, 3))
            return NavErrors(np.zeros(0), empty, empty.copy(), empty.copy())
        if len(self._parts) == 1:
            return self._parts[0]
        return NavErrors(*(np.concatenate([getattr(p, f) for p in self._parts])
                           for f in ("time_s", "pos_m", "vel_mps", "att_rad")))

    def solution_times(self) -> np.ndarray:
        """The solution times ``finish`` reads: the last before each mark and the last."""
        if self._last is None:
            return np.zeros(0)
        t = np.concatenate([self._before[np.isfinite(self._before)], self._last.time_s])
        return np.unique(t)
