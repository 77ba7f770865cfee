"""A study's ``[streaming]`` table: metrics streamed, outputs decimated, long runs never held.

Without the table a study simulates each training and test run whole, holds its log and
filters it in one piece (a run too long for that is refused, with the estimate).  With it::

    [streaming]
    chunk_s = 300.0        # IMU seconds per chunk of a run cut (default: 15 000 samples)
    output_rate_hz = 1.0   # the kept outputs' rate; the metrics accumulate at the filter's
    hold_log_mb = 128.0    # a run whose log needs no more is simulated once and held;
                           # one whose outputs need no more is filtered in one piece

every run of the study -- the baseline's, each trial's candidate, the compared filters of
the test table -- has its metrics accumulated as it is filtered
(:func:`fuzzynav.runpath.run`'s ``output_rate_hz``) and its outputs kept at
``output_rate_hz``.  A run whose log fits ``hold_log_mb``
(:func:`fuzzynav.sim.budget.held_log_bytes`) is simulated once, cached and held; a longer
one is held as its first chunk only (:func:`fuzzynav.experiment.streamed_source`) and
simulated again chunk by chunk for each of its runs (:func:`fuzzynav.experiment.
streamed_run`): memory bounded by the chunk, at the price of a simulation per trial.

A held run is filtered in one piece when all its outputs at the filter's rate would fit
``hold_log_mb`` too (:meth:`StudyStreaming.one_piece`), else over chunks of ``chunk_s`` cut
from its log (the event logs are kept whole either way, for the sensor-usage metrics).
Cutting a run that fits only costs time (the loop's call, scoring and keeping rows per
chunk): the metrics are the same to the last bit
however a run is cut, one piece included, because the streamed sums are cut into blocks
counted from the run's start, not at the chunks (:mod:`fuzzynav.block_sums`).  So a
streamed study's trials are a whole-run study's, held and long runs alike
(tests/tuning/test_study_streaming.py).

A recording (``[train] recordings``) is loaded once and held, as without the table; its
runs are filtered in one piece or over chunks of ``chunk_s`` by the same rule, their
outputs kept at ``output_rate_hz``, and scored chunk by chunk against the reference
(:mod:`fuzzynav.realdata.reference_scoring`): the metrics of the whole run to the last bit.
"""
from __future__ import annotations

from dataclasses import dataclass

from fuzzynav.errors import FuzzynavError, InputFileError, OutputRateError
from fuzzynav.experiment import as_source, streamed_run, streamed_source
from fuzzynav.filters.config import FilterConfig
from fuzzynav.realdata.studyruns import RecordingRun
from fuzzynav.runpath import make_setup, run
from fuzzynav.sim import budget
from fuzzynav.sim.sensor_log import SensorLog, simulate

__all__ = ["StudyStreaming", "read_streaming", "HOW"]

#: how a study asks for its runs streamed (the hint of a run too long to hold whole)
HOW = "give the study file a [streaming] table (docs/studies.md)"


@dataclass(frozen=True)
class StudyStreaming:
    """How a study streams its runs: which it holds, which it cuts (module docstring)."""

    #: IMU seconds per chunk; ``None``: :data:`fuzzynav.sim.budget.DEFAULT_CHUNK_SAMPLES`
    chunk_s: float | None = None
    #: rate of the kept outputs [Hz]; it must divide the filter's output rate
    output_rate_hz: float = 1.0
    #: the largest log a study holds [bytes] (a longer run is simulated again per run), and
    #: the most outputs a held run keeps in one piece
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

    def one_piece(self, duration_s: float, out_rate_hz: float) -> bool:
        """Whether a held run is filtered in one piece: its outputs at the filter's
        ``out_rate_hz``, every one of them, need no more than :attr:`hold_log_bytes`
        (:func:`fuzzynav.sim.budget.output_bytes`)."""
        return budget.output_bytes(duration_s * out_rate_hz) <= self.hold_log_bytes

    def working_bytes(self, duration_s: float, imu_rate_hz: float, sensors: dict) -> float:
        """What a run of a scenario holds while it is filtered, beside the held logs: the
        streamed estimate and, held, the outputs it may keep in one piece (at the filters'
        default output rate; at most :attr:`hold_log_bytes` at any rate)."""
        work = budget.streamed_estimate(duration_s, imu_rate_hz, sensors)
        if budget.held_log_bytes(duration_s, imu_rate_hz, sensors) <= self.hold_log_bytes:
            work += min(self.hold_log_bytes,
                        budget.output_bytes(duration_s * FilterConfig.out_rate_hz))
        return work

    def log(self, scenario, seed: int, cache_dir=None):
        """The log of a run: simulated whole (and cached) when held, else its
        :func:`~fuzzynav.experiment.streamed_source` (what filters configure themselves
        from, a chunk of it held)."""
        if self.holds(scenario):
            return simulate(scenario, seed, cache_dir)
        return streamed_source(scenario, seed, self.chunk_samples(scenario.imu.rate_hz))

    def run(self, log, filter_spec: str, options=None, setup=None, t_start_s: float = 0.0):
        """One run on ``log`` (:meth:`log`'s, or a recording's
        :class:`~fuzzynav.realdata.studyruns.RecordingRun`) with streamed metrics: a held
        one in one piece when :meth:`one_piece`, else over chunks.

        Raises
        ------
        FuzzynavError
            :attr:`output_rate_hz` cannot be kept by this filter (named as the study
            file's key, not the command line's option).
        """
        rate = self.output_rate_hz
        try:
            if isinstance(log, (RecordingRun, SensorLog)):  # held
                return self._held(log, filter_spec, options, setup, t_start_s)
            scenario = log.log.scenario
            chunk = self.chunk_samples(scenario.imu.rate_hz)
            return streamed_run(scenario, log.seed, filter_spec, options, t_start_s,
                                {"chunk_samples": chunk, "output_rate_hz": rate},
                                None, setup=setup)
        except OutputRateError as exc:
            raise FuzzynavError(f"[streaming] output_rate_hz = {self.output_rate_hz:g} Hz "
                                f"(filter {filter_spec}): {exc.reason}") from None

    def _held(self, log, filter_spec: str, options, setup, t_start_s: float):
        """A run on a held log (a recording's is scored in its own window): in one piece
        when :meth:`one_piece`, else over chunks."""
        if isinstance(log, RecordingRun):
            source, duration_s, imu_rate_hz = log, log.duration_s, log.imu_rate_hz
        else:
            source, scenario = as_source(log, t_start_s), log.scenario
            duration_s, imu_rate_hz = scenario.duration_s, scenario.imu.rate_hz
        setup = setup or make_setup(source, filter_spec, options)
        whole = self.one_piece(duration_s, setup.config.out_rate_hz)
        return run(source, filter_spec, options, setup, output_rate_hz=self.output_rate_hz,
                   chunk_samples=None if whole else self.chunk_samples(imu_rate_hz))


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
                out.working_bytes, "lower [streaming] hold_log_mb: the longest runs "
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
