"""A filter run on a scenario simulated chunk by chunk: memory bounded by the chunk.

:func:`run_streamed` simulates ``(scenario, seed)`` in chunks
(:class:`fuzzynav.sim.stream.SimulatedChunks`; or cuts its cached whole log alike,
:class:`fuzzynav.sim.log_chunks.LogChunks`) and feeds each to one
:class:`~fuzzynav.filters.runner.FilterRun` with that chunk's epochs
(``events_per_chunk``), scoring each chunk's outputs against its truth as it goes
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
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters.runner import FilterRun
from fuzzynav.filters.sensor_tables import concat_event_logs
from fuzzynav.fileio import write_npz
from fuzzynav.metrics import StreamingRms
from fuzzynav.metrics_rscale import KIND as USAGE_KIND, usage_metrics
from fuzzynav.metrics_segments import for_scenario
from fuzzynav.runpath import RunOutcome, keep_every, make_setup, nonfinite
from fuzzynav.sim import budget
from fuzzynav.sim.sensors import SensorData
from fuzzynav.sim.log_chunks import LogChunks, chunks_of
from fuzzynav.sim.stream import SimulatedChunks
from fuzzynav.simsource import OnSimulatedLog, perturbed_initial_state
from fuzzynav.streamtrace import StreamTrace

__all__ = ["DEFAULT_CHUNK_SAMPLES", "Start", "StreamedSource", "run_streamed"]

#: IMU samples per chunk when none is given (:data:`fuzzynav.sim.budget.DEFAULT_CHUNK_SAMPLES`)
DEFAULT_CHUNK_SAMPLES = budget.DEFAULT_CHUNK_SAMPLES


class StreamedSource(OnSimulatedLog):
    """What named filters configure themselves from on a streamed simulation: the scenario's
    IMU figures and the first chunk's streams (their kinds and constant ``meta``)."""

    def __init__(self, chunks: SimulatedChunks | LogChunks):
        self.chunks = chunks
        self.log = SimpleNamespace(scenario=chunks.scenario, seed=chunks.seed,
                                   sensors=chunks.header)

    @property
    def sensors(self) -> dict:
        """The streams filters configure themselves from (their kinds and ``meta``)."""
        return self.log.sensors


def _output_arrays(result, logs: dict) -> dict:
    """A chunk's kept outputs and event logs as flat ``npz`` arrays."""
    out = {"time_s": result.time_s, "lla": result.lla, "vel_n": result.vel_n,
           "q_bn": result.q_bn, "sigma": result.sigma, "sensor_states": result.sensor_states,
           "state_labels": np.array(result.state_labels, dtype=str)}
    for nm, ev in logs.items():
        out.update({f"events.{nm}.{f}": getattr(ev, f)
                    for f in ("time_s", "residual", "S_diag", "nis", "flag", "diag")})
        out[f"events.{nm}.diag_names"] = np.array(ev.diag_names, dtype=str)
    return out


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
    chunks = chunks_of(scenario, seed, chunk_samples, cache_dir)
    source = StreamedSource(chunks)
    setup = setup or make_setup(source, filter_spec, options)
    if setup.sigma_override:
        raise FuzzynavError(f"{filter_spec}: told each epoch's sigma of the whole run "
                            f"({', '.join(sorted(setup.sigma_override))}); a streamed run "
                            "has its epochs one chunk at a time (run without --output-rate/"
                            "--chunk)")
    stream, begun = iter(chunks), None
    if start is not None:
        begun = start(stream, setup)
        stream = itertools.chain(begun.pieces, stream)
    config = setup.config if begun is None else begun.config
    keep = 1 if output_rate_hz is None else keep_every(config.out_rate_hz, output_rate_hz)
    header = setup.sensors_for(chunks.header)
    names = sorted(header)
    scorer = StreamingRms(t_start_s, None,
                          for_scenario(scenario, t_start_s) if segments else None)
    usage = _Usage([nm for nm in names if header[nm].kind == USAGE_KIND
                    and "deflection_rad" in header[nm].meta][:1])
    out_dir = None if output_dir is None else Path(output_dir)
    pending = {}
    tracer = StreamTrace(output_rate_hz) if trace else None

    def on_events(logs):
        usage.add_events(logs)
        pending["logs"] = logs

    first = True
    fr = None
    for i, ch in enumerate(stream):
        if first:
            init = begun.init if begun is not None else perturbed_initial_state(
                SimpleNamespace(seed=chunks.seed, truth=ch.truth), setup)
            dt_nom = float(np.median(np.diff(ch.imu.time_s))) if ch.k1 > ch.k0 else 0.01
            fr = FilterRun(header, init, config, setup.adapters,
                           setup.sensor_options, dt_nom, keep,
                           on_chunk=scorer.add_result, events_per_chunk=True,
                           on_events=on_events, keep_events=keep_events)
            first = False
        scorer.truth = ch.truth
        sensors = setup.sensors_for(ch.sensors)
        usage.add_chunk(sensors)
        fr.feed_arrays(np.ascontiguousarray(ch.imu.time_s), np.ascontiguousarray(ch.imu.dtheta_b),
                       np.ascontiguousarray(ch.imu.dv_b), {nm: sensors[nm] for nm in names})
        kept = fr.kept() if tracer is not None or out_dir is not None else None
        if tracer is not None:
            tracer.add_chunk(kept, ch.truth, pending["logs"])
        if out_dir is not None:
            write_npz(out_dir / f"chunk-{i:06d}.npz", _output_arrays(kept, pending["logs"]),
                      "streamed run output (--output-dir)")
    res = fr.result()
    metrics = scorer.metrics()
    metrics.update(usage.metrics())
    if begun is not None:
        metrics.update(begun.metrics)
    metrics["completed"] = float(res.ok)
    return RunOutcome(filter_spec, scenario.name, chunks.seed, res, metrics,
                      nonfinite(source, metrics), None if tracer is None else tracer.trace())
