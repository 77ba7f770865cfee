"""A cached whole log handed out in the chunks of a streamed run.

A streamed run (:func:`fuzzynav.streamrun.run_streamed`) of a scenario whose whole log is
already in the simulation cache (:func:`fuzzynav.sim.sensor_log.simulate` wrote it) need
not simulate it again: :class:`LogChunks` cuts that log into the chunks
:class:`~fuzzynav.sim.stream.SimulatedChunks` would make, row for row (the cache holds the
same numbers to the last bit; tests/sim/test_log_chunks.py), with the same header and the
same whole-run ``meta`` left out of a run of several chunks.  :func:`chunks_of` picks one
or the other; a cached log is read only when its file fits
:data:`~fuzzynav.sim.budget.TRUTH_STORE_BYTES`, the most of a run a streamed one keeps.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from fuzzynav.sim.sensors import Grid, SensorData
from fuzzynav.sim.stream import Chunk, SimulatedChunks, epochs_between

__all__ = ["LogChunks", "chunks_of"]


def _rows(obj, k0: int, k1: int, n: int):
    """``obj`` (a Trajectory or ImuData) cut to samples ``k0..k1``: arrays of ``n + 1``
    rows (per sample) to ``k0..k1``, of ``n`` rows (per increment) to ``k0..k1-1``."""
    cut = {}
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        if isinstance(v, np.ndarray) and v.ndim and v.shape[0] in (n, n + 1):
            cut[f.name] = v[k0:k1 + 1] if v.shape[0] == n + 1 else v[k0:k1]
    return dataclasses.replace(obj, **cut)


class LogChunks:
    """A whole :class:`~fuzzynav.sim.sensor_log.SensorLog` in chunks of ``chunk_samples``.

    The attributes and the iteration are :class:`~fuzzynav.sim.stream.SimulatedChunks`'.
    """

    def __init__(self, log, chunk_samples: int):
        if int(chunk_samples) != chunk_samples or chunk_samples < 1:
            raise ValueError(f"chunk_samples must be a positive integer, got {chunk_samples}")
        self.scenario, self.seed, self.log = log.scenario, log.seed, log
        self.chunk_samples = int(chunk_samples)
        n = self.n_samples = log.imu.n_samples
        self.grid = Grid(0.0, float(log.truth.time_s[-1]), n + 1, log.truth.imu_rate_hz,
                         self.scenario.sea)
        self._bounds = [(k0, min(k0 + self.chunk_samples, n))
                        for k0 in range(0, max(n, 1), self.chunk_samples)]
        # as a streamed sensor's chunks: a whole-run figure only in a run of one chunk
        drop = {nm: () if len(self._bounds) == 1 else
                getattr(self.scenario.sensors[nm], "whole_run_meta", ())
                for nm in log.sensors}
        self._sensors = {nm: d if not drop[nm] else dataclasses.replace(
            d, meta={k: v for k, v in d.meta.items() if k not in drop[nm]})
            for nm, d in log.sensors.items()}
        self._used = False
        self._first = self._make(*self._bounds[0])
        streamed = {nm for nm, sp in self.scenario.sensors.items() if hasattr(sp, "stream")}
        head = {nm: self._first.sensors[nm] if nm in streamed else d
                for nm, d in self._sensors.items()}
        self.header = {nm: head[nm] for nm in sorted(head)}

    def _make(self, k0: int, k1: int) -> Chunk:
        truth = _rows(self.log.truth, k0, k1, self.n_samples)
        t_after = None if k0 == 0 else float(truth.time_s[0])
        sensors = {nm: epochs_between(d, t_after, float(truth.time_s[-1]))
                   for nm, d in self._sensors.items()}
        return Chunk(k0, k1, truth, _rows(self.log.imu, k0, k1, self.n_samples),
                     {nm: sensors[nm] for nm in sorted(sensors)})

    def __iter__(self):
        if self._used:
            raise RuntimeError("a LogChunks is iterated once, as a SimulatedChunks")
        self._used = True
        first, self._first = self._first, None
        yield first
        for k0, k1 in self._bounds[1:]:
            yield self._make(k0, k1)


def chunks_of(scenario, seed: int, chunk_samples: int, cache_dir=None):
    """The chunks of ``(scenario, seed)``: of its cached whole log when ``cache_dir`` holds
    one no larger than :data:`~fuzzynav.sim.budget.TRUTH_STORE_BYTES`, else simulated
    (:class:`~fuzzynav.sim.stream.SimulatedChunks`; nothing is written to the cache)."""
    from fuzzynav.sim import budget
    from fuzzynav.sim.sensor_log import cached_log

    log = None if cache_dir is None else cached_log(Path(cache_dir), scenario, seed,
                                                    budget.TRUTH_STORE_BYTES)
    if log is None:
        return SimulatedChunks(scenario, seed, chunk_samples)
    return LogChunks(log, chunk_samples)
