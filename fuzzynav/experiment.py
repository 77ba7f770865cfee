"""Run named filters on scenarios and seeds; collect metrics (the layer under CLI and studies).

Every filter in a comparison sees the same sensor logs (simulated once per (scenario, seed)
and cached) and the same initial error, drawn from the filter's initial covariance with a
generator derived from the seed, so differences between filters are paired.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from fuzzynav.errors import FuzzynavError, UnknownNameError
from fuzzynav.filters.chunk_files import run_files
from fuzzynav.filters.named import FilterContext, FilterSetup
from fuzzynav.metrics import (StreamingRms, errors_vs_trajectory, improvement_ci, mean_ci,
                              rms_metrics)
from fuzzynav.metrics_rscale import usage_metrics
from fuzzynav.metrics_segments import for_scenario, scenario_edges_s, segment_metrics
from fuzzynav.runpath import RunInputs, RunOutcome, check_outcomes, make_setup, run
from fuzzynav.simsource import OnSimulatedLog, perturbed_initial_state  # noqa: F401 (API)
from fuzzynav.sim.sensor_log import SensorLog, simulate
from fuzzynav.sim.scenario import Scenario, load_scenario

__all__ = ["SimulatedSource", "as_source", "filter_context", "setup_for",
           "run_on_log", "monte_carlo", "streamed_run", "streamed_source", "summary_table"]


@dataclass(frozen=True)
class SimulatedSource(OnSimulatedLog):
    """A simulated :class:`SensorLog` as a run source (:mod:`fuzzynav.runpath`): the filter
    starts from the truth with the error :func:`perturbed_initial_state` draws and is scored
    against the truth from ``t_start_s`` on (every RMS and maximum must be finite)."""

    log: SensorLog
    t_start_s: float = 0.0
    #: False: the free inertial run (no aiding streams fed)
    aided: bool = True
    #: True: also score each motion segment of the scenario (:mod:`fuzzynav.
    #: metrics_segments`, ``seg<j>_...`` metrics; ``fuzzynav run --segments``)
    segments: bool = False

    def inputs(self, setup: FilterSetup) -> RunInputs:
        return RunInputs(self.log.imu, self.log.sensors if self.aided else {},
                         perturbed_initial_state(self.log, setup))

    # the streaming options of fuzzynav run apply to a simulated log (its truth scores
    # chunk by chunk)
    SETTINGS = OnSimulatedLog.SETTINGS | {"output_rate", "chunk", "output_dir"}

    def score(self, result) -> dict:
        err = errors_vs_trajectory(result, self.log.truth)
        metrics = rms_metrics(err, self.t_start_s)
        if self.segments:
            metrics.update(segment_metrics(err, scenario_edges_s(self.log.scenario),
                                           self.t_start_s))
        # how much the run still uses its magnetometer (a study may penalise switching it off)
        metrics.update(usage_metrics(result, self.log.sensors))
        return metrics

    def streaming_scorer(self) -> StreamingRms:
        """A streaming form of :meth:`score`: fed each chunk of the result."""
        return StreamingRms(self.t_start_s, self.log.truth, for_scenario(
            self.log.scenario, self.t_start_s) if self.segments else None)

    def score_streamed(self, result, scorer: StreamingRms) -> dict:
        """:meth:`score` of a run scored chunk by chunk: the accumulated error metrics and
        the sensor-usage ones (from the event logs, which are kept whole)."""
        metrics = scorer.metrics()
        metrics.update(usage_metrics(result, self.log.sensors))
        return metrics



def as_source(log, t_start_s: float = 0.0, segments: bool = False):
    """A run source of a log: a :class:`SensorLog` becomes a :class:`SimulatedSource`
    (``segments``: scored per motion segment too); a source (a recording run,
    :mod:`fuzzynav.realdata.studyruns`) is itself (it scores in its own window:
    ``t_start_s`` and ``segments`` do not apply)."""
    if isinstance(log, SensorLog):
        return SimulatedSource(log, t_start_s, segments=segments)
    if segments:
        raise FuzzynavError(f"{log.name}: per-segment metrics are for simulated scenarios "
                            "(a recording has no motion segments)")
    return log


def filter_context(log, options=None) -> FilterContext:
    """What named filters configure themselves from on a log or a run source."""
    return as_source(log).context(options)


def setup_for(log, filter_name: str, options=None) -> FilterSetup:
    """Configuration and adapters of a named filter for a log (:func:`~fuzzynav.runpath.
    make_setup`)."""
    return make_setup(as_source(log), filter_name, options)


def run_on_log(log, filter_name: str, options=None, t_start_s: float = 0.0,
               setup: FilterSetup | None = None, segments: bool = False,
               **streaming) -> RunOutcome:
    """Run one named filter (or an explicit ``setup``) on a log and score it
    (:func:`fuzzynav.runpath.run` on :func:`as_source`; ``segments``: per motion segment
    too; ``streaming``: its ``chunk_samples`` and ``output_rate_hz``)."""
    return run(as_source(log, t_start_s, segments), filter_name, options, setup, **streaming)


def monte_carlo(scenario, filters, seeds, options=None, cache_dir=None, t_start_s=0.0,
                progress=False, refuse_diverged=False, seed_runs=None,
                streaming=None, segments: bool = False) -> pd.DataFrame:
    """Metrics of every filter on every seed, one row per (filter, seed).

    Parameters
    ----------
    scenario : Scenario or str
        A scenario object, a built-in name or a TOML path (with ``seed_runs``: any object
        with a ``name``, e.g. an alignment scenario).
    filters : sequence of str
        Named filters, or ``NAME@RULES[+RULES]`` (a named filter with its own rule files);
        per-filter options may be given as ``options[name]`` (a dict) in addition to shared
        options.
    seeds : sequence of int
    options : dict, optional
        Shared filter options; ``options[filter_name]`` (dict) overrides per filter.
    cache_dir : path, optional
        Where simulated logs are cached.
    refuse_diverged : bool
        Refuse the table when a run diverged (:func:`fuzzynav.runpath.check_outcomes`,
        ``RunDivergedError``), as the command line does; by default such runs are rows
        with their non-finite metrics.
    seed_runs : callable, optional
        ``seed_runs(seed) -> run``, ``run(filter) -> metrics``: the runs of one seed, for
        filters that are not navigation filters on a simulated log (the alignment's:
        :func:`fuzzynav.align.alignment_run.seed_runs`); ``options``, ``cache_dir``,
        ``t_start_s`` and ``refuse_diverged`` are then its own business and refused here.
    streaming : dict, optional
        ``chunk_samples``, ``output_rate_hz`` and ``output_dir`` of every navigation run:
        each is then simulated chunk by chunk (:func:`fuzzynav.streamrun.run_streamed`, the
        same data and filter arithmetic as the whole log, nothing of the run's length
        held) instead of simulated whole and cached.
    segments : bool
        Score every run per motion segment of the scenario too (``seg<j>_...`` columns:
        :mod:`fuzzynav.metrics_segments`), whole or streamed alike.
    """
    outcomes = []
    if seed_runs is None:
        scn = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
        seed_runs = _navigation_runs(scn, dict(options or {}), cache_dir, t_start_s, outcomes,
                                     dict(streaming or {}), segments)
    else:
        given = [k for k, v in (("options", options), ("cache_dir", cache_dir),
                                ("t_start_s", t_start_s), ("refuse_diverged", refuse_diverged),
                                ("streaming", streaming), ("segments", segments))
                 if v]
        if given:  # not silently ignored: the runs of seed_runs take their own
            raise FuzzynavError(f"monte_carlo: {', '.join(given)} apply to navigation filters "
                                "on simulated logs, not to seed_runs")
        scn = scenario
    rows = []
    seeds = list(seeds)
    bar = _progress(len(seeds) * len(filters), progress, f"{scn.name}")
    for seed in seeds:
        run_one = seed_runs(int(seed))
        for name in filters:
            rows.append({"scenario": scn.name, "filter": name, "seed": int(seed),
                         **run_one(name)})
            bar.update(1)
    bar.close()
    if refuse_diverged:
        check_outcomes(outcomes)
    return pd.DataFrame(rows)


def _navigation_runs(scn, options, cache_dir, t_start_s, outcomes, streaming, segments=False):
    """``seed -> (filter -> metrics)`` of named navigation filters on ``scn``'s logs (each
    run's outcome appended to ``outcomes``)."""
    def of_seed(seed):
        # a streamed run simulates its chunks itself: nothing of the run's length is held
        log = None if streaming else simulate(scn, seed, cache_dir)

        def run_one(name):
            opts = {k: v for k, v in options.items() if not isinstance(v, dict)}
            opts.update(options.get(name, {}) if isinstance(options.get(name), dict) else {})
            # NAME@FILE: resolved by the run
            if streaming:
                out = streamed_run(scn, seed, name, opts, t_start_s, streaming, cache_dir,
                                   segments=segments)
            else:
                out = run_on_log(log, name, opts, t_start_s, segments=segments)
            outcomes.append(out)
            return out.metrics
        return run_one
    return of_seed


def streamed_run(scn, seed, name, opts, t_start_s, streaming, cache_dir,
                 setup: FilterSetup | None = None, segments: bool = False) -> RunOutcome:
    """One run of :func:`fuzzynav.streamrun.run_streamed` (``streaming``: its chunk, output
    rate and output directory, one sub-directory per filter and seed; ``cache_dir``: read,
    never written; ``setup``: a configuration made elsewhere, e.g. on
    :func:`streamed_source`; ``segments``: scored per motion segment too)."""
    from fuzzynav.streamrun import DEFAULT_CHUNK_SAMPLES, run_streamed

    kw = run_files(streaming, name, seed)
    out_dir = kw.pop("output_dir", None)
    return run_streamed(scn, seed, name, opts, chunk_samples=kw.pop(
        "chunk_samples", DEFAULT_CHUNK_SAMPLES), t_start_s=t_start_s, output_dir=out_dir,
        cache_dir=cache_dir, setup=setup, segments=segments, **kw)


def streamed_source(scn, seed: int, chunk_samples: int):
    """The run source of ``(scn, seed)`` streamed in chunks of ``chunk_samples``
    (:class:`fuzzynav.streamrun.StreamedSource`): what filters configure themselves from
    (``sensors``: the first chunk's streams and those simulated whole) without the run's
    length held; run on by :func:`streamed_run`, which simulates the chunks again."""
    from fuzzynav.sim.stream import SimulatedChunks
    from fuzzynav.streamrun import StreamedSource

    return StreamedSource(SimulatedChunks(scn, seed, chunk_samples, truth_store_bytes=0))


def _progress(total, enabled, desc):
    from tqdm.auto import tqdm

    return tqdm(total=total, disable=not enabled, desc=desc, unit="run", leave=False)


def summary_table(df: pd.DataFrame, metrics, baseline: str | None = None) -> pd.DataFrame:
    """Mean with 95 % CI per filter and metric, and paired improvement over ``baseline``.

    Returns a table indexed by metric with, per filter, ``mean``, ``ci`` (half width) and,
    for non-baseline filters, ``improvement_pct`` with ``improvement_lo`` / ``_hi``.

    Raises
    ------
    UnknownNameError
        (a ``KeyError``) for a ``baseline`` not among the filters of ``df`` or a metric
        that is not one of its columns.
    """
    out = {}
    filters = list(dict.fromkeys(df["filter"]))
    # names the caller typed: one clear error instead of pandas' bare KeyError
    if baseline is not None and baseline not in filters:
        raise UnknownNameError("baseline filter", baseline, filters)
    for m in metrics:
        if m not in df.columns or m in ("scenario", "filter", "seed"):
            raise UnknownNameError("metric", m, [c for c in df.columns
                                                 if c.startswith(("rms_", "max_"))])
    for m in metrics:
        row = {}
        piv = df.pivot_table(index="seed", columns="filter", values=m)
        for f in filters:
            est = mean_ci(piv[f].to_numpy())
            row[(f, "mean")], row[(f, "ci")] = est.mean, est.half_width
            if baseline is not None and f != baseline:
                imp = improvement_ci(piv[baseline].to_numpy(), piv[f].to_numpy())
                row[(f, "improvement_pct")] = imp.mean
                row[(f, "improvement_lo")], row[(f, "improvement_hi")] = imp.lo, imp.hi
        out[m] = row
    table = pd.DataFrame(out).T
    table.columns = pd.MultiIndex.from_tuples(table.columns)
    return table
