"""The one run path: a source of data, a named filter, one compiled run, its metrics.

Every way of running a filter on data goes through :func:`run` — a simulated log
(:class:`fuzzynav.experiment.SimulatedSource`), the car recording under the validation
protocol (:class:`fuzzynav.realdata.session.GnssSource`), an A-KIT trajectory
(:class:`fuzzynav.realdata.akit.AkitSource`), a window of either as a study run
(:mod:`fuzzynav.realdata.studyruns`), a start behind an alignment
(:class:`fuzzynav.align.chain.AlignedSource`), a scenario simulated chunk by chunk
(:class:`fuzzynav.streamrun.StreamedSource`, with or without an alignment ahead) and the
free inertial run ALS fits its noise on.  :func:`run` is the only caller of :func:`fuzzynav.filters.runner.run_filter` outside
``filters/``, so what holds for one source holds for all:

* ``NAME@FILE[+FILE]`` filter specs are resolved (the rule or parameter files become the
  filter's options);
* the sensors' extra states (DVL scale, log bias, ...) are added by
  :func:`~fuzzynav.filters.sensor_states.with_sensor_states`;
* the filter sees the streams as its setup selects them (subsets, sigma overrides), cut
  to the source's start;
* every outcome says whether the run completed (``metrics["completed"]``) and which of the
  metrics its source requires finite are not (:attr:`RunOutcome.diverged`), and
  :func:`check_outcomes` refuses a table with any (exit 3 on the command line);
* run settings a source does not use (simulated outages on an A-KIT recording, recording
  options on a scenario) are refused by name (:func:`refuse_settings`, from the source's
  ``SETTINGS``) before anything is loaded.

A source is any object with the :class:`Source` attributes and methods; adding a dataset
is one such class.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from fuzzynav.chunk_feed import EpochsByChunk
from fuzzynav.errors import FuzzynavError, OutputRateError, RunDivergedError
from fuzzynav.filters.named import FilterContext, FilterSetup, get_filter, parse_filter_spec
from fuzzynav.filters.runner import HeldChunks, InitialState, run_filter
from fuzzynav.filters.sensor_states import with_sensor_states
from fuzzynav.sim.budget import DEFAULT_CHUNK_SAMPLES, check_run_outputs

#: bytes of one increment held: its time and its angle and velocity increments, float64
BYTES_PER_INCREMENT = 8 * 7

__all__ = ["RUN_SETTINGS", "STREAMING_SETTINGS", "RunInputs", "RunOutcome", "Source",
           "check_outcomes", "keep_every", "make_setup", "nonfinite", "refuse_settings", "run",
           "start_cut"]


@dataclass(frozen=True)
class RunInputs:
    """What a source feeds one run of a filter configuration.

    Attributes
    ----------
    imu : ImuData
        The increments from the start on.
    sensors : dict
        Aiding streams by name, before the filter's selection (:meth:`FilterSetup.
        sensors_for`).
    init : InitialState
        The navigation state at ``imu.time_s[0]``.
    sensor_options : dict
        Per-sensor options merged over the setup's (e.g. ``{"gnss": {"use_velocity": False}}``).
    config : FilterConfig or None
        Replaces the setup's configuration (e.g. an aligned start's attitude sigma).
    from_s : float or None
        Epochs of the streams before this time are dropped, after the selection (a start
        behind an alignment).
    """

    imu: object
    sensors: dict
    init: InitialState
    sensor_options: dict = dataclasses.field(default_factory=dict)
    config: object = None
    from_s: float | None = None


class Source(Protocol):
    """A source of data to run named filters on.

    Attributes
    ----------
    name : str
        What tables call it (scenario name, recording spec).
    seed : int
        The seed of what was drawn for it (0 for a recording run without noise).
    """

    name: str
    seed: int
    #: class attributes: the :data:`RUN_SETTINGS` the source uses, what to call its kind
    #: and why the other settings do not apply (:func:`refuse_settings`)
    SETTINGS: frozenset
    KIND: str
    SETTINGS_NOTE: str

    def context(self, options=None) -> FilterContext:
        """What named filters configure themselves from (IMU model, sensors, options)."""

    def inputs(self, setup: FilterSetup) -> RunInputs:
        """The IMU, streams and start of one run of ``setup``."""

    def score(self, result) -> dict:
        """Metrics of a :class:`~fuzzynav.filters.runner.FilterResult` (SI, units in names)."""

    def required(self, metrics: dict) -> tuple:
        """The names of ``metrics`` that must be finite unless the filter diverged."""


@dataclass(frozen=True)
class RunOutcome:
    """One filter on one source.

    Attributes
    ----------
    filter : str
        The filter spec as given.
    scenario : str
        The source's name.
    seed : int
    result : FilterResult
    metrics : dict
        The source's score and ``completed`` (1.0, or 0.0 when the filter stopped early).
    diverged : tuple
        Names of required metrics that are not finite (empty for a healthy run).
    trace : Trace, optional
        A streamed run's errors and thinned event logs for figures, when asked for
        (:class:`fuzzynav.streamtrace.Trace`).
    """

    filter: str
    scenario: str
    seed: int
    result: object
    metrics: dict
    diverged: tuple = ()
    trace: object = None


def make_setup(source: Source, filter_spec: str, options=None) -> FilterSetup:
    """The configuration of a named filter (``NAME`` or ``NAME@FILE[+FILE]``) on a source."""
    name, own = parse_filter_spec(filter_spec)
    ctx = source.context({**dict(options or {}), **own})
    return with_sensor_states(get_filter(name).make(ctx), ctx.sensors, ctx.options)


def _merged(base: dict, extra: dict) -> dict:
    if not extra:
        return base
    out = {k: dict(v) for k, v in base.items()}
    for nm, opts in extra.items():
        out.setdefault(nm, {}).update(opts)
    return out


def start_cut(data, t0: float):
    """A stream without its epochs before ``t0`` (per-epoch ``meta`` arrays cut alike)."""
    keep = data.time_s >= t0
    meta = {k: (v[keep] if isinstance(v, np.ndarray) and v.shape[:1] == keep.shape else v)
            for k, v in data.meta.items()}
    return dataclasses.replace(data, time_s=data.time_s[keep], z=data.z[keep],
                               sigma=data.sigma[keep], meta=meta)


def run(source: Source, filter_spec: str, options=None,
        setup: FilterSetup | None = None, chunk_samples: int | None = None,
        output_rate_hz: float | None = None, output_dir=None) -> RunOutcome:
    """Run one named filter (or an explicit ``setup``) on a source and score it.

    A source whose IMU is read from its file chunk by chunk (increments with ``chunks``)
    is also given its streams' epochs a chunk at a time
    (:class:`~fuzzynav.chunk_feed.EpochsByChunk`): its event logs are not held (they go
    to ``output_dir``, or are dropped), so its memory grows with the streams' epochs only,
    not with the logs the filter makes of them.

    Parameters
    ----------
    source : Source
    filter_spec : str
        ``NAME`` or ``NAME@FILE[+FILE]``; with ``setup`` only its label.
    options : dict, optional
        Filter options (``rules``, initial sigmas, ...).
    setup : FilterSetup, optional
        A configuration made elsewhere (a study's candidate); its sensor states are the
        caller's.
    chunk_samples : int, optional
        Run the compiled loop over chunks of this many IMU samples, carrying its state
        (:class:`~fuzzynav.filters.runner.FilterRun`: the same result to the last bit);
        default one chunk.
    output_rate_hz : float, optional
        Keep the recorded solution at this rate only (``--output-rate``): it must divide
        the filter's output rate (``config.out_rate_hz``).  The metrics are then
        accumulated chunk by chunk at the filter's output rate (the source's
        ``streaming_scorer()``, :class:`~fuzzynav.metrics.StreamingRms`, finished by its
        ``score_streamed(result, scorer)``), so they are those of the undecimated run
        (the same sums, :mod:`fuzzynav.block_sums`); a source without a ``scorer``
        refuses it.
    output_dir : path-like, optional
        Write each chunk's kept outputs and event logs there (``--output-dir``;
        :mod:`fuzzynav.filters.chunk_files`); a held source's increments are then cut into
        chunks of ``chunk_samples`` (default :data:`~fuzzynav.sim.budget.
        DEFAULT_CHUNK_SAMPLES`, :class:`~fuzzynav.filters.runner.HeldChunks`), its epochs given
        chunk by chunk alike: the same arithmetic.

    Raises
    ------
    FuzzynavError
        An output rate that does not divide the filter's, or a source that cannot score
        chunk by chunk.
    """
    setup = setup or make_setup(source, filter_spec, options)
    inp = source.inputs(setup)
    sensors = setup.sensors_for(inp.sensors)
    if inp.from_s is not None:
        sensors = {nm: start_cut(d, inp.from_s) for nm, d in sensors.items()}
    config = inp.config or setup.config
    feed = inp.imu
    # a feed whose chunks bring their own truth scores them itself, always chunk by chunk
    scoring = feed if hasattr(feed, "score_streamed") else source
    keep, scorer = 1, None
    if output_rate_hz is not None:
        keep = keep_every(config.out_rate_hz, output_rate_hz)
        if not hasattr(scoring, "streaming_scorer"):
            raise OutputRateError(f"{source.KIND} score their whole result, so their "
                                  "output cannot be decimated")
    if output_rate_hz is not None or scoring is feed:
        scorer = scoring.streaming_scorer()
    if hasattr(feed, "chunks") and chunk_samples is None:  # read from a file
        chunk_samples = DEFAULT_CHUNK_SAMPLES
    fed = sensors  # whole: what the run holds beside its outputs
    if output_dir is not None and not hasattr(feed, "chunks"):  # chunk files of held data
        feed = HeldChunks(feed)
        chunk_samples = DEFAULT_CHUNK_SAMPLES if chunk_samples is None else chunk_samples
    if hasattr(feed, "chunks") and not getattr(feed, "events_per_chunk", False):
        feed = EpochsByChunk(feed, sensors)
        sensors = feed.header
    _check_outputs(source, feed, fed, config, keep, chunk_samples)
    res = run_filter(feed, sensors, inp.init, config, setup.adapters,
                     _merged(setup.sensor_options, inp.sensor_options),
                     chunk_samples=chunk_samples, keep_every=keep,
                     on_chunk=None if scorer is None else scorer.add_result,
                     output_dir=output_dir)
    metrics = source.score(res) if scorer is None else scoring.score_streamed(res, scorer)
    metrics["completed"] = float(res.ok)
    return RunOutcome(filter_spec, source.name, int(source.seed), res, metrics,
                      nonfinite(source, metrics), feed.trace() if hasattr(feed, "trace")
                      else None)


def _check_outputs(source, imu, sensors: dict, config, keep: int, chunk_samples) -> None:
    """:func:`fuzzynav.sim.budget.check_run_outputs` of a run about to be filtered: the
    solution rows it will keep (one per output period, every ``keep``-th) and, decimated,
    those made at a time before (a chunk's; the whole run's in one piece), the epochs its
    event logs record (given chunk by chunk, :class:`EpochsByChunk`: a chunk's share),
    beside the IMU and sensor arrays it is given (of increments made chunk by chunk, one
    chunk)."""
    if hasattr(imu, "chunks"):
        n, (t0, t1) = imu.n_samples + 1, imu.span_s
        held = getattr(imu, "held_bytes", None) or \
            min(n, int(chunk_samples) + 1) * BYTES_PER_INCREMENT
    else:
        n, t0, t1 = int(np.size(imu.time_s)), None, None
        held = sum(getattr(imu, f).nbytes for f in ("time_s", "dtheta_b", "dv_b"))
    if n < 2:
        return
    if t0 is None:
        t0, t1 = imu.time_s[0], imu.time_s[-1]
    dt = float(t1 - t0) / (n - 1)
    stride = max(1, round(1.0 / (config.out_rate_hz * dt))) if dt > 0 else 1
    held += sum(d.time_s.nbytes + d.z.nbytes + d.sigma.nbytes for d in sensors.values())
    epochs = sum(d.time_s.size for d in sensors.values())
    if isinstance(imu, EpochsByChunk):  # its event logs are a chunk's at a time
        epochs *= min(1.0, (int(chunk_samples) + 1) / n)
    # decimated rows are made a chunk at a time (the whole run's in one piece) first
    made = 0.0 if keep == 1 else (n if chunk_samples is None else
                                  min(n, int(chunk_samples) + 1)) / stride
    check_run_outputs(source.name, held, n / stride / keep, epochs, made_rows=made)


def keep_every(filter_rate_hz: float, output_rate_hz: float) -> int:
    """How many of the filter's recorded outputs (at ``filter_rate_hz``) make one kept at
    ``output_rate_hz``; refused unless a whole number >= 1."""
    ratio = float(filter_rate_hz) / float(output_rate_hz) if output_rate_hz > 0 else math.nan
    keep = round(ratio) if math.isfinite(ratio) else 0
    if keep < 1 or abs(ratio - keep) > 1e-9 * ratio:
        raise OutputRateError(f"must be the filter's output rate {filter_rate_hz:g} Hz "
                              f"divided by a whole number (e.g. {filter_rate_hz:g}, "
                              f"{filter_rate_hz / 2:g}, {filter_rate_hz / 10:g} Hz)",
                              output_rate_hz)
    return int(keep)


def nonfinite(source: Source, metrics: dict) -> tuple:
    """The metrics ``source`` requires finite that are not (a diverged run), in its order."""
    return tuple(m for m in source.required(metrics)
                 if not math.isfinite(float(metrics.get(m, math.nan))))


def check_outcomes(outcomes, what: str = "scenario") -> None:
    """Refuse a table of runs of which any diverged (:attr:`RunOutcome.diverged`).

    Every command that prints a table of runs passes its outcomes here first, so a run
    whose required metrics are not finite prints no table on any source (exit 3).

    Parameters
    ----------
    outcomes : iterable of RunOutcome
    what : str
        What :attr:`RunOutcome.scenario` names, in the message ("scenario", "recording").

    Raises
    ------
    RunDivergedError
        Naming the first such run's filter, source and seed, and how many there are.
    """
    outcomes = list(outcomes)
    bad = [o for o in outcomes if o.diverged]
    if not bad:
        return
    o = bad[0]
    stopped = " (it stopped early: covariance lost)" if o.metrics["completed"] < 1 else ""
    raise RunDivergedError(f"filter {o.filter} diverged on {what} {o.scenario} seed {o.seed}"
                           f"{stopped}: {o.diverged[0]} = {o.metrics.get(o.diverged[0])}; "
                           f"{len(bad)} of {len(outcomes)} run(s) have non-finite metrics, "
                           "no table printed")


def refuse_settings(source_type, given: dict) -> None:
    """Refuse, by name, run settings given for a source that does not use them.

    Parameters
    ----------
    source_type : type
        A source class: its ``SETTINGS`` (the names of :data:`RUN_SETTINGS` it uses),
        ``KIND`` (what to call it) and ``SETTINGS_NOTE`` (why the others do not apply).
    given : dict
        Setting name (a key of :data:`RUN_SETTINGS`) -> how the user spelled it (a flag
        such as ``--noise``, a study key), for each setting given a non-default value.

    Raises
    ------
    FuzzynavError
        Listing every given setting the source does not use (they would change nothing).
    """
    unknown = sorted(set(given) - set(RUN_SETTINGS))
    if unknown:
        raise ValueError(f"not run settings: {', '.join(unknown)}")
    unused = [label for name, label in given.items() if name not in source_type.SETTINGS]
    if unused:
        verb = "do" if len(unused) > 1 else "does"
        raise FuzzynavError(f"{', '.join(unused)}: {verb} not apply to {source_type.KIND} "
                            f"({source_type.SETTINGS_NOTE})")


#: the run settings a command or study may give, by name -> what they set
RUN_SETTINGS = {
    "mc": "Monte-Carlo runs (seeds of simulated or added noise)",
    "t_start": "time the scoring starts [s]",
    "noise": "white noise added to the fed positions [m]",
    "vel_noise": "white noise added to the fed velocities [m/s]",
    "outage_period": "period of simulated GNSS outages [s]",
    "outage_duration": "length of each simulated outage [s]",
    "first_outage": "start of the first simulated outage [s]",
    "gnss_velocity": "how the receiver's velocities are fed",
    "velocity_lag": "lag of the receiver's velocities [s]",
    "nhc": "non-holonomic constraints fed [m/s]",
    "mounting": "mounting file of the recording (IMU to body, lever arm)",
    "imu_delay": "IMU sample-to-logger delay [s]",
    "span": "stretch of the recording used [s]",
    "output_rate": "rate of the kept recorded solution [Hz] (metrics streamed)",
    "chunk": "IMU seconds per chunk of the compiled loop",
    "output_dir": "files of each chunk's kept solution and event logs",
}

#: the run settings of a streaming run (:func:`run`'s ``output_rate_hz``,
#: ``chunk_samples`` and ``output_dir``): only sources that can score chunk by chunk take them
STREAMING_SETTINGS = frozenset({"output_rate", "chunk", "output_dir"})
