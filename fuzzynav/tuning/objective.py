"""Score candidate rule sets: RMS errors on cached runs, normalised by a baseline filter.

For each (scenario, seed) of a run set the candidate's RMS position, velocity and attitude
errors are divided by the baseline filter's (the EKF by default) on the same data and the
same initial error; a run's score is the weighted mean of these ratios (1 = as good as the
baseline, lower is better).  A run that loses its covariance scores :data:`FAILED_RATIO`.
:func:`score_metrics` is the one place this is computed -- for the study's trials
(:class:`Objective`) and for the train/test tables (:mod:`fuzzynav.tuning.evaluate`) alike.
Sensor logs and baseline metrics are computed once per process and kept in memory.
"""
from __future__ import annotations

import math
import os
import socket
import time
from dataclasses import dataclass

import numpy as np

from fuzzynav.errors import FuzzynavError
from fuzzynav.experiment import as_source, run_on_log, setup_for
from fuzzynav.filters.catalog import bind_systems
from fuzzynav.filters.named import FilterSetup
from fuzzynav.realdata.dataspec import is_recording_name
from fuzzynav.realdata.studyruns import recording_run
from fuzzynav.runpath import RunOutcome
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.tuning.study_config import EXTRA_GROUP_METRICS, GROUP_METRICS
from fuzzynav.tuning.pareto import accuracy_and_worst
from fuzzynav.tuning.space import ControllerSpace, build_all

__all__ = ["FAILED_RATIO", "CANDIDATE", "HEARTBEAT_S", "RunScore", "weighted_score",
           "score_metrics", "setup_with_systems", "Evaluator", "TrialObjective", "Objective"]

#: ratio given to a metric when the candidate's run failed or is not finite
FAILED_RATIO = 10.0
#: the filter name a candidate's runs are recorded under
CANDIDATE = "tuned"
#: a running trial records a heartbeat at most this often [s] (and at its start)
HEARTBEAT_S = 10.0


@dataclass(frozen=True)
class RunScore:
    """One run of a filter scored against the baseline on the same run.

    Attributes
    ----------
    metrics : dict
        The run's RMS metrics (``rms_pos_m``, ...) and ``completed`` (1.0 or 0.0).
    ratios : dict
        Group (``pos``, ``vel``, ``att``) -> ratio to the baseline, :data:`FAILED_RATIO`
        where the run failed or the ratio is not finite.
    score : float
        The weighted mean of ``ratios``.
    """

    metrics: dict
    ratios: dict
    score: float


def weighted_score(ratios: dict, weights: dict) -> float:
    """The weighted mean of group ratios (weights: group -> non-negative weight; a group
    of weight 0 does not count, even when its ratio is NaN)."""
    return sum(w * ratios[g] for g, w in weights.items() if w) / sum(weights.values())


def score_metrics(metrics: dict, baseline: dict, weights: dict) -> RunScore:
    """Score a run's metrics against the baseline's metrics on the same run.

    Parameters
    ----------
    metrics, baseline : dict
        RMS metrics of the candidate and of the baseline (keys of :data:`GROUP_METRICS`;
        ``metrics["completed"]`` < 1 marks a run that failed).
    weights : dict
        Group -> weight of its ratio in the score (the core groups of
        :data:`GROUP_METRICS` are always scored; a weighted extra group of
        :data:`~fuzzynav.tuning.study_config.EXTRA_GROUP_METRICS` too).
    """
    ok = metrics.get("completed", 1.0) >= 1.0
    ratios = {}
    groups = {**GROUP_METRICS, **{g: EXTRA_GROUP_METRICS[g] for g in weights
                                  if g in EXTRA_GROUP_METRICS}}
    for g, key in groups.items():
        if key not in baseline:  # a recording scores no attitude (its weight is 0)
            if weights.get(g):  # else the score would be NaN: a silent wrong objective
                raise FuzzynavError(f"objective group {g!r} has weight {weights[g]:g}, but "
                                    f"this run has no {key} (e.g. attitude on a recording, "
                                    "r_use without a simulated magnetometer): set its "
                                    "weight to 0 or train on runs that measure it")
            ratios[g] = math.nan
            continue
        r = metrics[key] / baseline[key] if baseline[key] > 0 else math.nan
        ratios[g] = r if (ok and math.isfinite(r)) else FAILED_RATIO
    return RunScore(metrics, ratios, weighted_score(ratios, weights))


def setup_with_systems(log, systems: dict, filter_name: str = "fakf",
                       base: FilterSetup | None = None) -> FilterSetup:
    """The configuration of a log with the given fuzzy systems: bound to its sensors in the
    EKF (``fakf``, ``fuzzy``; ``base``: the log's EKF configuration, when the caller keeps
    it), or handed to another filter that takes rule files as its ``systems`` option (a
    filter bank that takes a share controller)."""
    items = [(fis, f"<candidate {name}>") for name, fis in systems.items()]
    if filter_name not in ("fakf", "fuzzy"):
        setup = setup_for(log, filter_name, {"systems": items})
        bank = setup.config.bank
        used = {getattr(a, "source", None) for a in setup.adapters.values()}
        used.add(getattr(getattr(bank, "controller", None), "source", None))
        if not {src for _, src in items} <= used:  # a filter that ignored the option
            raise FuzzynavError(f"filter {filter_name!r} does not take a study's candidate "
                                "rule sets (its systems option); use fakf or a bank such "
                                "as federated-fuzzy-beta")
        return setup
    base = base or setup_for(log, "ekf")
    return FilterSetup(base.config, bind_systems(items, log.sensors, required=True),
                       base.sensor_options, base.sigma_override)


class Evaluator:
    """Runs candidates on a study's training or test runs (one instance per process).

    Parameters
    ----------
    config : StudyConfig
    cache_dir : path or None
        Simulation cache shared by all processes.
    """

    def __init__(self, config, cache_dir=None):
        self.config = config
        self.cache_dir = cache_dir
        self._logs = {}
        self._scenarios = {}
        self._baseline = {}
        self._ekf = {}  # the EKF setup of a run, which every candidate starts from

    # -- data -------------------------------------------------------------------------------
    def source(self, scenario: str, seed: int):
        """The run source (:mod:`fuzzynav.runpath`) of a run: its log scored from the
        study's ``t_start_s``, or its recording window."""
        return as_source(self.log(scenario, seed), self.config.t_start_s)

    def log(self, scenario: str, seed: int):
        """The sensor log of a run (simulated once, cached on disk and in memory), or the
        :class:`~fuzzynav.realdata.studyruns.RecordingRun` of a recording."""
        key = (scenario, seed)
        if key not in self._logs and is_recording_name(scenario):
            try:
                self._logs[key] = recording_run(scenario, seed)  # loaded once per process
            except FuzzynavError as exc:  # found only now: say which study entry it is
                group = "train" if key in self.config.train else "test"
                raise FuzzynavError(f"{self.config.path}: {group}.recordings ({scenario}): "
                                    f"{exc}") from None
        if key not in self._logs:
            if scenario not in self._scenarios:
                self._scenarios[scenario] = load_scenario(scenario)
            scn, st = self._scenarios[scenario], self.config.streaming
            self._logs[key] = (simulate(scn, seed, self.cache_dir) if st is None
                               else st.log(scn, seed, self.cache_dir))
        return self._logs[key]

    def run(self, scenario: str, seed: int, filter_spec: str, options=None,
            setup=None) -> RunOutcome:
        """One run of the study: a named filter (or an explicit ``setup``) on a run's log,
        whole or, with the study's ``[streaming]`` table, chunk by chunk
        (:mod:`~fuzzynav.tuning.study_streaming`), scored from ``t_start_s``."""
        log, st = self.log(scenario, seed), self.config.streaming
        t0 = self.config.t_start_s
        if st is None:
            return run_on_log(log, filter_spec, options=options, t_start_s=t0, setup=setup)
        return st.run(log, filter_spec, options, setup, t0)

    def baseline(self, scenario: str, seed: int) -> dict:
        """Metrics of the baseline filter on a run."""
        key = (scenario, seed)
        if key not in self._baseline:
            self._baseline[key] = self.run(scenario, seed, self.config.baseline).metrics
        return self._baseline[key]

    def prepare(self, runs, known=None) -> "Evaluator":
        """Load the logs of ``runs`` and run the baseline on each now; returns self.

        ``known``: baseline metrics computed elsewhere ((scenario, seed) -> metrics, by
        this same code in a process forked from this one), taken instead of running them.
        """
        self._baseline.update(known or {})
        for scenario, seed in runs:
            self.log(scenario, seed)
            self.baseline(scenario, seed)
        return self

    def pending(self, runs) -> list:
        """The runs of ``runs`` (each once, in order) whose baseline is not computed yet."""
        return [run for run in dict.fromkeys(runs) if run not in self._baseline]

    # -- candidates -------------------------------------------------------------------------
    def run_systems(self, systems: dict, scenario: str, seed: int):
        """Run the candidate (controller name -> FuzzySystem) on one run: a
        :class:`~fuzzynav.experiment.RunOutcome` named :data:`CANDIDATE`."""
        log = self.log(scenario, seed)
        if (scenario, seed) not in self._ekf:
            self._ekf[(scenario, seed)] = setup_for(log, "ekf")
        return self.run(scenario, seed, CANDIDATE, setup=setup_with_systems(
            log, systems, self.config.filter, self._ekf[(scenario, seed)]))

    def judge(self, metrics: dict, scenario: str, seed: int) -> RunScore:
        """Score a filter's metrics on a run against the baseline on that run."""
        return score_metrics(metrics, self.baseline(scenario, seed), self.config.weights)

    def score_systems(self, systems: dict, scenario: str, seed: int) -> RunScore:
        """Run the candidate on one run and score it."""
        return self.judge(self.run_systems(systems, scenario, seed).metrics, scenario, seed)


class TrialObjective:
    """What every study kind's Optuna objective shares: the trust features of a worker.

    A subclass implements ``_run(trial)`` (score the trial's candidate, set ``n_runs``);
    this base names the worker as the trial's owner (:meth:`claim`, read by
    :func:`fuzzynav.tuning.optuna_study.reap_stale`), records heartbeats (:meth:`_beat`) and keeps
    the number of the trial being run and the exception that failed it (read by the
    worker loop, :func:`fuzzynav.tuning.optuna_study.run_worker`).

    Parameters
    ----------
    cfg : StudyConfig
        The study (its ``stale_after_s`` sets the heartbeat period).
    worker : int
        The worker's index (recorded in each trial it claims).
    """

    def __init__(self, cfg, worker: int = 0):
        self.cfg = cfg
        self.worker = worker
        self.current = None       # number of the trial being run (or last run) here
        self.last_error = None    # the exception that failed the last trial here
        self._claimed = None      # number of the last trial this worker named itself owner of
        self._last_beat = -math.inf
        # a heartbeat is one journal record: often enough for a reaper on another host
        # (stale_after_s), not after every run
        self._beat_every_s = min(HEARTBEAT_S, cfg.stale_after_s / 10.0)

    def _beat(self, trial, force: bool = False):
        now = time.time()
        if force or now - self._last_beat >= self._beat_every_s:
            trial.set_user_attr("heartbeat", now)
            self._last_beat = now

    def __call__(self, trial):
        self.current, self.last_error = trial.number, None
        try:
            return self._run(trial)
        except Exception as exc:
            self.last_error = exc
            raise

    def claim(self, trial) -> None:
        """Name this worker as ``trial``'s owner (host, pid, worker, first heartbeat); once
        per trial, as early as possible (see :func:`fuzzynav.tuning.optuna_study.reap_stale`)."""
        if self._claimed == trial.number:
            return
        trial.set_user_attr("host", socket.gethostname())
        trial.set_user_attr("pid", os.getpid())
        trial.set_user_attr("worker", self.worker)
        self._beat(trial, force=True)
        self._claimed = trial.number

    def _run(self, trial):  # pragma: no cover - abstract
        raise NotImplementedError


class Objective(TrialObjective):
    """Callable Optuna objective of a fuzzy study config (one per worker process).

    Single objective: the mean score over the training runs, each run's score reported with
    a stable step id in a per-trial shuffled order so that a pruner may stop the trial; a
    pruned trial returns the mean of the runs done so far and records ``n_runs``.
    Multi-objective: the three mean group ratios; ``robust``: the mean score and the worst
    training scenario's mean score (:func:`fuzzynav.tuning.pareto.accuracy_and_worst`).
    """

    def __init__(self, cfg, cache_dir=None, worker: int = 0, evaluator=None):
        super().__init__(cfg, worker)
        self.spaces = [ControllerSpace.from_config(c) for c in cfg.controllers]
        self.evaluator = evaluator if evaluator is not None else Evaluator(cfg, cache_dir)

    def _run(self, trial):
        self.claim(trial)
        systems = build_all(self.spaces, trial)
        runs = list(enumerate(self.cfg.train))
        np.random.default_rng(trial.number).shuffle(runs)
        scored = []
        for step, (scenario, seed) in runs:
            scored.append(self.evaluator.score_systems(systems, scenario, seed))
            self._beat(trial)
            if not self.cfg.multi_objective:
                trial.report(scored[-1].score, step=step)
                if trial.should_prune():
                    break
        means = {g: float(np.mean([s.ratios[g] for s in scored])) for g in scored[0].ratios}
        trial.set_user_attr("n_runs", len(scored))
        trial.set_user_attr("ratios", means)
        if self.cfg.robust:
            return accuracy_and_worst(trial, [scenario for _, (scenario, _) in runs],
                                      [s.score for s in scored])
        if self.cfg.multi_objective:
            return tuple(means[g] for g in GROUP_METRICS)
        return float(np.mean([s.score for s in scored]))
