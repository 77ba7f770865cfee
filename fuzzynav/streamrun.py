"""A filter run on a scenario simulated chunk by chunk: memory bounded by the chunk.

:func:`run_streamed` simulates ``(scenario, seed)`` in chunks
(:class:`fuzzynav.sim.stream.SimulatedChunks`; or cuts its cached whole log alike,
:class:`fuzzynav.sim.log_chunks.LogChunks`) as a run source, :class:`StreamedSource`, and
runs it through the one run path, :func:`fuzzynav.runpath.run`, as every other source:
its chunk feed brings each chunk's epochs to the compiled loop (``events_per_chunk``) and
scores each chunk's outputs against that chunk's truth as it goes
(:class:`~fuzzynav.metrics.StreamingRms`).  Nothing of the run's length is held but the
kept (decimated) outputs, the epoch indices of the streams simulated whole and, in a short
run (:data:`fuzzynav.sim.budget.TRUTH_STORE_BYTES`), its truth or cached log; the event
logs of each chunk are written to ``output_dir`` (or dropped), as are its kept outputs.

For the same seed the metrics are those of :func:`fuzzynav.experiment.run_on_log` on the
whole log with the same output rate (the same data, the same filter arithmetic, the same
streamed sums; tests/test_streamrun.py), and the run is what ``fuzzynav run --output-rate``
does on a simulated scenario.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters.sensor_tables import concat_event_logs
from fuzzynav.metrics import StreamingRms
from fuzzynav.metrics_rscale import KIND as USAGE_KIND, usage_metrics
from fuzzynav.metrics_segments import for_scenario
from fuzzynav.runpath import RunInputs, make_setup, run
from fuzzynav.sim import budget
from fuzzynav.sim.log_chunks import LogChunks, chunks_of
from fuzzynav.sim.stream import SimulatedChunks
from fuzzynav.simsource import OnSimulatedLog, perturbed_initial_state
from fuzzynav.streamtrace import StreamTrace

__all__ = ["DEFAULT_CHUNK_SAMPLES", "Start", "StreamedSource", "run_streamed"]

#: IMU samples per chunk when none is given (:data:`fuzzynav.sim.budget.DEFAULT_CHUNK_SAMPLES`)
DEFAULT_CHUNK_SAMPLES = budget.DEFAULT_CHUNK_SAMPLES


class StreamedSource(OnSimulatedLog):
    """A scenario simulated chunk by chunk as a run source (:mod:`fuzzynav.runpath`).

    What named filters configure themselves from are the scenario's IMU figures and the
    first chunk's streams (their kinds and constant ``meta``).  :meth:`inputs` makes one
    run's chunk feed (:class:`_Feed`): it iterates ``chunks`` (once), so a source serves
    one run.

    Parameters
    ----------
    chunks : SimulatedChunks or LogChunks
    t_start_s : float
        Scoring starts here.
    start : callable, optional
        ``start(chunks, setup) -> Start`` (:func:`run_streamed`).
    segments : bool
        Score each motion segment of the scenario too.
    output_rate_hz : float, optional
        The kept outputs' rate, for the trace's thinned event logs.
    keep_events : bool
        Keep the chunks' event logs in the result.
    trace : bool
        Keep the kept outputs' errors and thinned event logs for figures.
    """

    def __init__(self, chunks: SimulatedChunks | LogChunks, t_start_s: float = 0.0,
                 start=None, segments: bool = False, output_rate_hz: float | None = None,
                 keep_events: bool = False, trace: bool = False):
        self.chunks = chunks
        self.log = SimpleNamespace(scenario=chunks.scenario, seed=chunks.seed,
                                   sensors=chunks.header)
        self.t_start_s, self.start, self.segments = float(t_start_s), start, bool(segments)
        self.output_rate_hz, self.keep_events, self.trace = output_rate_hz, keep_events, trace

    @property
    def sensors(self) -> dict:
        """The streams filters configure themselves from (their kinds and ``meta``)."""
        return self.log.sensors

    def inputs(self, setup) -> RunInputs:
        """The run's chunk feed, its start (the truth plus an error from P0, or ``start``'s)
        and the first chunk's streams."""
        feed = _Feed(self, setup)
        return RunInputs(feed, self.chunks.header, feed.init, config=feed.config)


class _Feed:
    """One streamed run's chunks as :func:`~fuzzynav.filters.runner.run_filter` takes a
    feed whose chunks bring their own epochs, and what it keeps per chunk: the scorer's
    truth, the magnetometer usage and the trace (the ``--output-dir`` files are the run
    path's, :mod:`fuzzynav.filters.chunk_files`)."""

    events_per_chunk = True

    def __init__(self, source: StreamedSource, setup):
        chunks = source.chunks
        stream, self.begun = iter(chunks), None
        if source.start is not None:
            self.begun = source.start(stream, setup)
            stream = itertools.chain(self.begun.pieces, stream)
        first = next(stream)
        self._stream = itertools.chain([first], stream)
        self.init = self.begun.init if self.begun is not None else perturbed_initial_state(
            SimpleNamespace(seed=chunks.seed, truth=first.truth), setup)
        self.config = None if self.begun is None else self.begun.config
        self.dt_nom_s = float(np.median(np.diff(first.imu.time_s))) \
            if first.k1 > first.k0 else 0.01
        self.n_samples, self.chunk_samples = chunks.n_samples, chunks.chunk_samples
        self.span_s = (chunks.grid.t0_s, chunks.grid.t_end_s)
        self.setup, self.keep_events = setup, source.keep_events
        header = setup.sensors_for(chunks.header)
        self.names = sorted(header)
        self.usage = _Usage([nm for nm in self.names if header[nm].kind == USAGE_KIND
                             and "deflection_rad" in header[nm].meta][:1])
        self.scorer = StreamingRms(source.t_start_s, None, for_scenario(
            chunks.scenario, source.t_start_s) if source.segments else None)
        self.tracer = StreamTrace(source.output_rate_hz) if source.trace else None
        self._chunk = self._logs = None

    def chunks(self, n: int):
        """The run's chunks as ``(imu, epochs)``, the scorer's truth set to each's."""
        if n != self.chunk_samples:
            raise ValueError(f"the chunks are of {self.chunk_samples} samples, not {n}")
        for ch in self._stream:
            self._chunk = ch
            self.scorer.truth = ch.truth
            sensors = self.setup.sensors_for(ch.sensors)
            self.usage.add_chunk(sensors)
            yield ch.imu, {nm: sensors[nm] for nm in self.names}

    def on_events(self, logs: dict) -> None:
        """A chunk's event logs, from the filter."""
        self.usage.add_events(logs)
        self._logs = logs

    def chunk_fed(self, kept) -> None:
        """After each chunk: its kept outputs (``kept()``) traced, if asked."""
        if self.tracer is not None:
            self.tracer.add_chunk(kept(), self._chunk.truth, self._logs)

    def streaming_scorer(self) -> StreamingRms:
        """The scorer the chunks set their truth on."""
        return self.scorer

    def score_streamed(self, result, scorer: StreamingRms) -> dict:
        """The streamed error metrics, the magnetometer usage and the start's metrics."""
        metrics = scorer.metrics()
        metrics.update(self.usage.metrics())
        if self.begun is not None:
            metrics.update(self.begun.metrics)
        return metrics

    def trace(self):
        """The run's :class:`~fuzzynav.streamtrace.Trace`, or ``None`` when not asked."""
        return None if self.tracer is None else self.tracer.trace()


@dataclass(frozen=True)
class Start:
    """Where a streamed run starts when it does not start on the truth (``start=``).

    Attributes
    ----------
    init : InitialState
    config : FilterConfig
        The filter's configuration from there (e.g. the aligned attitude's sigma).
    pieces : list of Chunk
        The chunks taken from the stream to find the start, cut to begin at it (their IMU
        from the start sample, their sensors' epochs from its time): fed first.
    metrics : dict
        Metrics of the start itself, added to the run's.
    """

    init: object
    config: object
    pieces: list
    metrics: dict


class _Usage:
    """The magnetometer streams' epochs and event logs, kept for the usage metrics (a
    magnetometer runs at a few hertz: the only streams held whole)."""

    def __init__(self, names):
        self.names, self.data, self.logs = tuple(names), {n: [] for n in names}, \
            {n: [] for n in names}

    def add_chunk(self, sensors) -> None:
        for nm in self.names:
            self.data[nm].append(sensors[nm])

    def add_events(self, logs) -> None:
        for nm in self.names:
            self.logs[nm].append(logs[nm])

    def metrics(self) -> dict:
        if not self.names:
            return {}
        sensors, events = {}, {}
        for nm in self.names:
            parts = self.data[nm]
            defl = np.concatenate([np.asarray(p.meta["deflection_rad"]) for p in parts])
            sensors[nm] = SimpleNamespace(kind=USAGE_KIND, time_s=defl,
                                          meta={"deflection_rad": defl})
            events[nm] = concat_event_logs(self.logs[nm])
        return usage_metrics(SimpleNamespace(events=events), sensors)


def run_streamed(scenario, seed: int, filter_spec: str, options=None, setup=None,
                 chunk_samples: int = DEFAULT_CHUNK_SAMPLES, output_rate_hz: float | None = None,
                 t_start_s: float = 0.0, output_dir=None, keep_events: bool = False,
                 cache_dir=None, trace: bool = False, start=None, segments: bool = False):
    """Simulate ``(scenario, seed)`` chunk by chunk and run one named filter on it.

    Parameters
    ----------
    scenario : Scenario
    seed : int
    filter_spec : str
        ``NAME`` or ``NAME@FILE[+FILE]`` (with ``setup``: its label).
    options : dict, optional
        Filter options.
    setup : FilterSetup, optional
        A configuration made elsewhere (a study's candidate).
    chunk_samples : int
        IMU samples per chunk.
    output_rate_hz : float, optional
        Keep the recorded solution at this rate only (it must divide the filter's output
        rate); default every output.
    t_start_s : float
        Scoring starts here.
    output_dir : path-like, optional
        Write each chunk's kept outputs and event logs to ``chunk-NNNNNN.npz`` there.
    keep_events : bool
        Keep the event logs in the result (default: only written, or dropped).
    cache_dir : path-like, optional
        A simulation cache: the run's whole log is cut into the chunks when it is there
        (and small: :func:`fuzzynav.sim.log_chunks.chunks_of`), the same data; a streamed
        run never writes one.
    trace : bool
        Keep the kept outputs' errors and the event logs thinned to the output rate
        (:class:`fuzzynav.streamtrace.StreamTrace`) in the outcome's ``trace``, for figures.
    start : callable, optional
        ``start(chunks, setup) -> Start``: where the filter starts instead of the truth
        plus an error from P0 (``run --align``: behind an alignment on the opening chunks,
        :func:`fuzzynav.align.chain.run_aligned_streamed`); ``chunks`` is the iterator of
        the run's chunks, of which it may take the first few.
    segments : bool
        Score each motion segment of the scenario too: the run's per-segment metrics
        (:mod:`fuzzynav.metrics_segments`) join its metrics.

    Returns
    -------
    RunOutcome
        Its ``result`` holds the kept outputs (and the events only with ``keep_events``).

    Raises
    ------
    FuzzynavError
        A filter told per-epoch sigmas of the whole run (``ekf-true``), or an output rate
        that does not divide the filter's.
    """
    source = StreamedSource(chunks_of(scenario, seed, chunk_samples, cache_dir), t_start_s,
                            start, segments, output_rate_hz, keep_events, trace)
    setup = setup or make_setup(source, filter_spec, options)
    if setup.sigma_override:
        raise FuzzynavError(f"{filter_spec}: told each epoch's sigma of the whole run "
                            f"({', '.join(sorted(setup.sigma_override))}); a streamed run "
                            "has its epochs one chunk at a time (run without --output-rate/"
                            "--chunk)")
    return run(source, filter_spec, setup=setup, chunk_samples=chunk_samples,
               output_rate_hz=output_rate_hz, output_dir=output_dir)
