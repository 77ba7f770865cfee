"""A study's ``[streaming]`` table: its runs filtered chunk by chunk, long ones never held.

Without the table a study simulates each training and test run whole, holds its log and
filters it in one piece (a run too long for that is refused, with the estimate).  With it::

    [streaming]
    chunk_s = 300.0        # IMU seconds per chunk (default: 15 000 samples)
    output_rate_hz = 1.0   # the kept outputs' rate; the metrics accumulate at the filter's
    hold_log_mb = 128.0    # a run whose log needs no more is simulated once and held

every run of the study -- the baseline's, each trial's candidate, the compared filters of
the test table -- is filtered over chunks with its metrics accumulated chunk by chunk
(:func:`fuzzynav.runpath.run`'s ``chunk_samples`` and ``output_rate_hz``), so no run's
outputs are held whole.  A run whose log fits ``hold_log_mb``
(:func:`fuzzynav.sim.budget.held_log_bytes`) is simulated once, cached and held, and its
chunks are cut from it, which costs a trial what a whole run costs; a longer one is held
as its first chunk only (:func:`fuzzynav.experiment.streamed_source`) and simulated again
chunk by chunk for each of its runs (:func:`fuzzynav.experiment.streamed_run`): memory
bounded by the chunk, at the price of a simulation per trial.  Both give the metrics of
the other to the last bit (the same data, the same filter arithmetic, the same streamed
sums: tests/tuning/test_study_streaming.py), and so do they against a whole-run study:
the streamed sums are cut into blocks counted from each run's start, not at the chunks
(:mod:`fuzzynav.block_sums`).

A recording (``[train] recordings``) is loaded once and held, as without the table; its
runs are filtered over chunks of ``chunk_s`` alike, their outputs kept at
``output_rate_hz``, and scored chunk by chunk against the reference
(:mod:`fuzzynav.realdata.reference_scoring`): the metrics of the whole run to the last bit.
``hold_log_mb`` applies to simulated runs only.
"""
from __future__ import annotations

from dataclasses import dataclass

from fuzzynav.errors import FuzzynavError, InputFileError, OutputRateError
from fuzzynav.experiment import run_on_log, streamed_run, streamed_source
from fuzzynav.realdata.studyruns import RecordingRun
from fuzzynav.runpath import run
from fuzzynav.sim import budget
from fuzzynav.sim.sensor_log import SensorLog, simulate

__all__ = ["StudyStreaming", "read_streaming", "HOW"]

#: how a study asks for its runs streamed (the hint of a run too long to hold whole)
HOW = "give the study file a [streaming] table (docs/studies.md)"


@dataclass(frozen=True)
class StudyStreaming:
    """How a study filters its simulated runs chunk by chunk (module docstring)."""

    #: IMU seconds per chunk; ``None``: :data:`fuzzynav.sim.budget.DEFAULT_CHUNK_SAMPLES`
    chunk_s: float | None = None
    #: rate of the kept outputs [Hz]; it must divide the filter's output rate
    output_rate_hz: float = 1.0
    #: the largest log a study holds [bytes]; a longer run is simulated again per run
    hold_log_bytes: float = float(budget.TRUTH_STORE_BYTES)

    def chunk_samples(self, imu_rate_hz: float) -> int:
        """IMU samples per chunk of runs whose IMU runs at ``imu_rate_hz`` (at least one)."""
        if self.chunk_s is None:
            return budget.DEFAULT_CHUNK_SAMPLES
        return max(1, round(self.chunk_s * imu_rate_hz))

    def holds(self, scenario) -> bool:
        """Whether ``scenario``'s runs are simulated once and held (their log fits
        :attr:`hold_log_bytes`)."""
        return budget.held_log_bytes(scenario.duration_s, scenario.imu.rate_hz,
                                     scenario.sensors) <= self.hold_log_bytes

    def log(self, scenario, seed: int, cache_dir=None):
        """The log of a run: simulated whole (and cached) when held, else its
        :func:`~fuzzynav.experiment.streamed_source` (what filters configure themselves
        from, a chunk of it held)."""
        if self.holds(scenario):
            return simulate(scenario, seed, cache_dir)
        return streamed_source(scenario, seed, self.chunk_samples(scenario.imu.rate_hz))

    def run(self, log, filter_spec: str, options=None, setup=None, t_start_s: float = 0.0):
        """One run on ``log`` (:meth:`log`'s, or a recording's
        :class:`~fuzzynav.realdata.studyruns.RecordingRun`), filtered over chunks with
        streamed metrics.

        Raises
        ------
        FuzzynavError
            :attr:`output_rate_hz` cannot be kept by this filter (named as the study
            file's key, not the command line's option).
        """
        rate = self.output_rate_hz
        try:
            if isinstance(log, RecordingRun):  # held, scored in its own window
                return run(log, filter_spec, options, setup, output_rate_hz=rate,
                           chunk_samples=self.chunk_samples(log.imu_rate_hz))
            scenario = log.scenario if isinstance(log, SensorLog) else log.log.scenario
            chunk = self.chunk_samples(scenario.imu.rate_hz)
            if isinstance(log, SensorLog):
                return run_on_log(log, filter_spec, options, t_start_s, setup,
                                  chunk_samples=chunk, output_rate_hz=rate)
            return streamed_run(scenario, log.seed, filter_spec, options, t_start_s,
                                {"chunk_samples": chunk, "output_rate_hz": rate},
                                None, setup=setup)
        except OutputRateError as exc:
            raise FuzzynavError(f"[streaming] output_rate_hz = {self.output_rate_hz:g} Hz "
                                f"(filter {filter_spec}): {exc.reason}") from None


def read_streaming(top, runs: tuple, scenarios: dict) -> StudyStreaming | None:
    """The ``[streaming]`` table of a study file (``top``: its :class:`~fuzzynav.sim.
    tomltable.Table`; ``runs``: its training and test runs; ``scenarios``: the simulated
    runs' scenarios by name, as read), or ``None`` without one.

    Raises
    ------
    InputFileError
        A bad key; the table in a study with recordings; without it, a simulated run too
        long to hold whole (the estimate, and how to stream it); with it or without, runs
        whose logs held at once (every run a study simulates stays in memory) and a run
        filtered meanwhile need more than :func:`fuzzynav.sim.budget.memory_limit`.
    """
    st = top.table("streaming", required=False)
    simulated = [run for run in dict.fromkeys(runs) if run[0] in scenarios]
    if st is None:
        for name, scn in scenarios.items():
            try:
                budget.check_whole_run(scn.duration_s, scn.imu.rate_hz, scn.sensors,
                                       f"scenario {name}", HOW)
            except InputFileError as exc:
                raise top.error("streaming", exc.what) from None
        _check_held(top, "streaming", simulated, scenarios, lambda scn: True,
                    budget.whole_estimate, HOW)
        return None
    chunk_s = st.number("chunk_s", 0.0, lo=0.0, lo_open=True) if "chunk_s" in st.data \
        else None
    out = StudyStreaming(chunk_s=chunk_s,
                         output_rate_hz=st.number("output_rate_hz", 1.0, lo=0.0, lo_open=True),
                         hold_log_bytes=st.number("hold_log_mb", budget.TRUTH_STORE_BYTES
                                                  / 2**20, lo=0.0) * 2**20)
    st.finish()
    _check_held(st, "hold_log_mb", simulated, scenarios, out.holds,
                budget.streamed_estimate, "lower [streaming] hold_log_mb: the longest runs "
                "are then simulated again for each of their runs instead of held")
    return out


def _check_held(table, key, runs, scenarios, holds, working, how) -> None:
    """:func:`fuzzynav.sim.budget.check_held_logs` of the study's runs that ``holds``, as an
    error of the study file's ``table`` at ``key``; ``working``: the estimate of a run
    filtered meanwhile."""
    def size(scn, estimate):
        return estimate(scn.duration_s, scn.imu.rate_hz, scn.sensors)

    held = {f"{name} seed {seed}": size(scenarios[name], budget.held_log_bytes)
            for name, seed in runs if holds(scenarios[name])}
    work = max((size(scn, working) for scn in scenarios.values()), default=0.0)
    try:
        budget.check_held_logs(held, work, "the study", how)
    except InputFileError as exc:
        raise table.error(key, exc.what) from None
