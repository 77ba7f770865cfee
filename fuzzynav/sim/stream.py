"""A scenario simulated chunk by chunk: truth, IMU and aiding streams in bounded memory.

:func:`fuzzynav.sim.sensor_log.simulate` makes the whole log at once; a run as long as a
mission (a ship's day at 200 Hz is 17 M IMU samples) does not fit that way.
:class:`SimulatedChunks` makes the same data in consecutive chunks of IMU samples:

* the trajectory block by block (:class:`fuzzynav.sim.trajectory.Blocks`, its running
  integrals carried);
* the IMU errors by :class:`fuzzynav.sim.imu.ImuStream` (every error term its own
  generator, drawn in sample order, the Gauss-Markov and random-walk states carried);
* a sensor with a ``stream`` method (the high-rate ones: log, ship constraints, neutral
  points) epoch by epoch in the same way (:class:`fuzzynav.sim.sensors.EpochStream`);
* any other sensor (GNSS, polarization, magnetometer, BDS, DVL: their outage, cloud and
  dropout spells span the run) whole, once, from the truth at its epochs only, gathered
  by one pass of the trajectory at the start (:class:`_RowsTruth`); its epochs are handed
  out chunk by chunk.  Such sensors run at a few hertz: their streams are what a
  :class:`~fuzzynav.filters.runner.FilterRun` held anyway.  When the whole truth of the
  run fits ``truth_store_bytes`` (:data:`~fuzzynav.sim.budget.TRUTH_STORE_BYTES`; 184 B
  a sample), that pass keeps its blocks, cut as the chunks are, and the chunks take them
  instead of generating the trajectory a second time (it is most of a short run's
  simulation cost); a longer run regenerates each chunk's block, in bounded memory.

Each component's generator is the one :func:`~fuzzynav.sim.sensor_log.simulate` seeds
(:func:`~fuzzynav.sim.sensor_log.component_rng`), and numpy draws of ``n1`` then ``n2``
values are the draw of ``n1 + n2``: every chunk's arrays are the whole log's rows to the
last bit, whatever the chunk size (tests/sim/test_stream.py), and the whole log is the
one-chunk case.  Only the oracle's ``true_sigma`` of the ship constraints, a whole-run
RMS, is left out of a streamed log (:class:`~fuzzynav.sim.sensors.nhc.NhcStream`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.sim.imu import ImuData
from fuzzynav.sim.scenario import Scenario
from fuzzynav.sim.sensors import Grid, SensorData, epoch_indices
from fuzzynav.sim.trajectory import BLOCK_SAMPLES, Blocks, Trajectory

__all__ = ["Chunk", "SimulatedChunks", "epochs_between"]


@dataclass(frozen=True)
class Chunk:
    """Samples ``k0..k1`` of a run.

    Attributes
    ----------
    k0, k1 : int
        First and last sample (the chunk has ``k1 - k0`` increments).
    truth : Trajectory
        Truth at samples ``k0..k1``.
    imu : ImuData
        Measured increments ``k0..k1-1``.
    sensors : dict
        Sensor name -> :class:`SensorData` of the epochs after sample ``k0`` up to ``k1``
        (from ``k0`` itself in the run's first chunk).
    """

    k0: int
    k1: int
    truth: Trajectory
    imu: ImuData
    sensors: dict


def epochs_between(data: SensorData, t_after_s, t_last_s) -> SensorData:
    """The epochs of ``data`` in ``(t_after_s, t_last_s]`` (all up to ``t_last_s`` when
    ``t_after_s`` is ``None``), per-epoch ``meta`` arrays cut alike."""
    t = data.time_s
    a = 0 if t_after_s is None else int(np.searchsorted(t, t_after_s, "right"))
    b = int(np.searchsorted(t, t_last_s, "right"))
    m = t.shape[0]
    meta = {k: (v[a:b] if isinstance(v, np.ndarray) and v.ndim and v.shape[0] == m
                and k not in _RUN_META else v) for k, v in data.meta.items()}
    return SensorData(kind=data.kind, time_s=t[a:b], z=data.z[a:b], sigma=data.sigma[a:b],
                      meta=meta)


#: meta arrays of a whole stream that are not per epoch (a window list could have as many
#: rows as the stream has epochs)
_RUN_META = frozenset({"outage_windows", "dropout_windows", "cloud_windows"})


class _Wanted(Exception):
    """Raised by :class:`_Probe` with the epoch indices a sensor asked for."""

    def __init__(self, idx):
        super().__init__("probe")
        self.idx = idx


class _Probe(Grid):
    """A grid whose :func:`epoch_indices` stops the sensor with the indices it wants."""

    def remap(self, idx):
        raise _Wanted(idx)


class _RowsTruth:
    """The truth of a run at some samples only (``rows``, sorted, with the first and the
    last): :func:`epoch_indices` maps a sensor's samples to these rows."""

    def __init__(self, grid: Grid, rows, arrays: dict):
        self.grid, self.imu_rate_hz, self.sea = grid.grid, grid.imu_rate_hz, grid.sea
        self.rows = rows
        for k, v in arrays.items():
            setattr(self, k, v)

    def remap(self, idx):
        pos = np.searchsorted(self.rows, idx)
        if pos.size and (pos.max() >= self.rows.size or np.any(self.rows[pos] != idx)):
            raise RuntimeError("a sensor asked for truth at samples it did not name first")
        return pos


_ROW_ARRAYS = ("time_s", "lla", "vel_n", "att", "q_bn", "omega_nb_b")


class SimulatedChunks:
    """``(scenario, seed)`` simulated in chunks of ``chunk_samples`` IMU samples.

    Parameters
    ----------
    scenario : Scenario
    seed : int
    chunk_samples : int
        IMU increments per chunk (the last chunk may be shorter).
    truth_store_bytes : float, optional
        Keep the first pass's truth for the chunks when it needs no more than this
        (default :data:`fuzzynav.sim.budget.TRUTH_STORE_BYTES`; 0 never keeps it).  The
        chunks are the same to the last bit either way.

    Attributes
    ----------
    n_samples : int
        Increments of the run.
    grid : Grid
    header : dict
        Sensor name -> what filters configure themselves from: a sensor simulated whole,
        its whole :class:`SensorData`; a streamed one, its first chunk's (its kind, constant
        ``meta`` and epoch spacing).

    Iterate (once) for the :class:`Chunk` s in order.
    """

    def __init__(self, scenario: Scenario, seed: int, chunk_samples: int,
                 truth_store_bytes: float | None = None):
        from fuzzynav.sim.budget import keeps_truth
        from fuzzynav.sim.sensor_log import check_seed, component_rng

        if int(chunk_samples) != chunk_samples or chunk_samples < 1:
            raise ValueError(f"chunk_samples must be a positive integer, got {chunk_samples}")
        self.scenario, self.seed = scenario, check_seed(seed)
        self.chunk_samples = int(chunk_samples)
        args = (scenario.start_lla_rad, scenario.segments, scenario.imu.rate_hz,
                scenario.initial_speed_mps, np.deg2rad(scenario.initial_heading_deg))
        self._blocks = Blocks(*args, sea=scenario.sea)
        self._args = args
        n = self.n_samples = self._blocks.n_samples
        self.grid = Grid(0.0, float(self._blocks.times(n, n)[0]), n + 1,
                         self._blocks.rate_hz, scenario.sea)
        self._imu = scenario.imu.stream(component_rng(self.seed, "imu"))
        self._streams, whole = {}, {}
        for name, spec in scenario.sensors.items():
            rng = component_rng(self.seed, f"sensor:{name}")
            if hasattr(spec, "stream"):
                self._streams[name] = spec.stream(self.grid, rng, scenario.start_utc)
            else:
                whole[name] = (spec, rng)
        keep = keeps_truth(n, self.chunk_samples, scenario.sensors, truth_store_bytes)
        self._stored = {} if keep else None
        self._whole = self._simulate_whole(whole)
        self._first = self._header = None
        self._used = False

    def _simulate_whole(self, specs: dict) -> dict:
        """The sensors without a stream, simulated whole from the truth at their epochs."""
        if not specs:
            return {}
        probe = _Probe(*self.grid.grid, self.grid.imu_rate_hz, self.grid.sea)
        wanted = [np.array([0, self.n_samples], np.int64)]
        for name, (spec, _) in specs.items():
            try:
                # a throwaway generator: the probe stops the sensor before it draws
                spec.simulate(probe, np.random.default_rng(0), self.scenario.start_utc)
            except _Wanted as got:
                wanted.append(got.idx)
            else:  # pragma: no cover - every sensor places its epochs first
                raise RuntimeError(f"sensor {name!r} did not ask for its epochs")
        rows = np.unique(np.concatenate(wanted))
        arrays = {k: np.empty((rows.size,) + ((4,) if k == "q_bn" else () if k == "time_s"
                                              else (3,))) for k in _ROW_ARRAYS}
        gen = Blocks(*self._args, sea=self.scenario.sea)
        step = min(BLOCK_SAMPLES, self.chunk_samples)  # the chunk's memory, not a block's
        for k0 in range(0, self.n_samples, step):
            k1 = min(k0 + step, self.n_samples)
            blk = gen.block(k0, k1)
            if self._stored is not None:
                self._stored[k0] = blk
            a, b = np.searchsorted(rows, [k0, k1 + 1])
            for k in _ROW_ARRAYS:
                arrays[k][a:b] = getattr(blk, k)[rows[a:b] - k0]
        truth = _RowsTruth(self.grid, rows, arrays)
        return {name: spec.simulate(truth, rng, self.scenario.start_utc)
                for name, (spec, rng) in specs.items()}

    @property
    def header(self) -> dict:
        if self._header is None:
            self._first = self._make(0, min(self.chunk_samples, self.n_samples))
            # a sensor simulated whole is its own header (a filter may read statistics of
            # its epochs, e.g. strong tracking the median interval); a streamed one's is
            # its first chunk
            head = {**self._first.sensors, **self._whole}
            self._header = {nm: head[nm] for nm in sorted(head)}
        return self._header

    def _make(self, k0: int, k1: int) -> Chunk:
        truth = self._stored.pop(k0) if self._stored else self._blocks.block(k0, k1)
        imu = self._imu.corrupt(truth)
        lo = k0 if k0 == 0 else k0 + 1
        whole = k0 == 0 and k1 == self.n_samples  # the run in one chunk: the whole log
        sensors = {nm: s.chunk(truth, k0, lo, whole) for nm, s in self._streams.items()}
        t_after = None if k0 == 0 else float(truth.time_s[0])
        sensors.update({nm: epochs_between(d, t_after, float(truth.time_s[-1]))
                        for nm, d in self._whole.items()})
        return Chunk(k0, k1, truth, imu, {nm: sensors[nm] for nm in sorted(sensors)})

    def __iter__(self):
        if self._used:
            raise RuntimeError("a SimulatedChunks is iterated once (its generators move on)")
        self._used = True
        _ = self.header
        first, self._first = self._first, None
        yield first
        for k0 in range(first.k1, self.n_samples, self.chunk_samples):
            yield self._make(k0, min(k0 + self.chunk_samples, self.n_samples))
