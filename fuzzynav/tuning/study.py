"""Optuna studies over the rule search space: storage, samplers, pruning, workers.

Storage: by default a journal file next to the study config (safe for many processes on one
machine); any Optuna storage URL (``postgresql://...``) lets many machines share a study.
Journal storage has no heartbeat, so each worker first *reaps*: a ``RUNNING`` trial whose
worker process is gone (same host) or whose heartbeat is older than ``stale_after_s`` is
marked ``FAIL`` and its parameters are enqueued again (once).  RDB storages use Optuna's
heartbeat with :class:`optuna.storages.RetryHeartbeatStaleTrialCallback` instead.

Pruning (single objective): each training run's score is reported with a stable step id in
a per-trial shuffled order; when pruned, the trial returns the mean of the runs done so far
(so the sampler still learns from it) and records ``n_runs``; exports only consider trials
that ran every training run.
"""
from __future__ import annotations

import math
import os
import socket
import time

import numpy as np
import optuna
from optuna.trial import TrialState

from fuzzynav.tuning.config import GROUP_METRICS
from fuzzynav.tuning.objective import Evaluator
from fuzzynav.tuning.space import ControllerSpace, build_all

optuna.logging.set_verbosity(optuna.logging.WARNING)
FINISHED = (TrialState.COMPLETE, TrialState.PRUNED)
MAX_RETRIES = 2


# -- storage, sampler, pruner ------------------------------------------------------------------
def make_storage(url: str, heartbeat: bool = True):
    """An Optuna storage from ``journal:PATH`` or an RDB URL."""
    if url.startswith("journal:"):
        from optuna.storages.journal import JournalFileBackend, JournalStorage

        path = url[len("journal:"):]
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        return JournalStorage(JournalFileBackend(path))
    if not heartbeat:
        return optuna.storages.RDBStorage(url)
    return optuna.storages.RDBStorage(
        url, heartbeat_interval=10, grace_period=60,
        failed_trial_callback=optuna.storages.RetryFailedTrialCallback(max_retry=MAX_RETRIES))


def make_sampler(cfg, worker: int = 0):
    """The configured sampler; each worker gets its own seed (base + index)."""
    seed = cfg.seed + worker
    s = cfg.sampler
    if s == "tpe" or s == "pso":  # pso drives the study itself; tpe is never asked then
        return optuna.samplers.TPESampler(seed=seed, multivariate=True, group=True,
                                          constant_liar=True, n_startup_trials=10)
    if s == "random":
        return optuna.samplers.RandomSampler(seed=seed)
    if s == "qmc":
        return optuna.samplers.QMCSampler(seed=seed, warn_independent_sampling=False)
    if s == "cmaes":
        return optuna.samplers.CmaEsSampler(seed=seed, warn_independent_sampling=False)
    return optuna.samplers.NSGAIISampler(seed=seed)


def make_pruner(cfg):
    if cfg.multi_objective or cfg.pruner == "none" or cfg.sampler == "pso":
        return optuna.pruners.NopPruner()
    if cfg.pruner == "median":
        return optuna.pruners.MedianPruner(n_startup_trials=5, n_warmup_steps=2)
    return optuna.pruners.WilcoxonPruner(p_threshold=0.1, n_startup_steps=2)


def open_study(cfg, storage_url=None, worker: int = 0, create: bool = False):
    """Create (``create=True``, in the parent) or load the study of a config."""
    storage = make_storage(storage_url or cfg.storage_url)
    kw = dict(study_name=cfg.name, storage=storage, sampler=make_sampler(cfg, worker),
              pruner=make_pruner(cfg))
    if create:
        study = optuna.create_study(directions=cfg.directions, load_if_exists=True, **kw)
        if cfg.multi_objective:
            study.set_metric_names([f"{g}_ratio" for g in GROUP_METRICS])
        return study
    return optuna.load_study(**kw)


# -- bookkeeping ---------------------------------------------------------------------------------
def n_finished(study) -> int:
    """Trials that count towards the study's total (complete or pruned)."""
    return len(study.get_trials(deepcopy=False, states=FINISHED))


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def reap_stale(study, stale_after_s: float) -> int:
    """Fail and re-enqueue ``RUNNING`` trials whose worker is dead; returns how many."""
    now, host, n = time.time(), socket.gethostname(), 0
    for t in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        ua = t.user_attrs
        beat = ua.get("heartbeat", t.datetime_start.timestamp() if t.datetime_start else now)
        gone = ua.get("host") == host and "pid" in ua and not _alive(int(ua["pid"]))
        if not (gone or now - beat > stale_after_s):
            continue
        try:
            study.tell(t.number, state=TrialState.FAIL)
        except Exception:  # another worker reaped it first
            continue
        n += 1
        retries = int(ua.get("retries", 0))
        if retries < MAX_RETRIES and t.params:
            study.enqueue_trial(t.params, user_attrs={"retry_of": t.number,
                                                      "retries": retries + 1})
    return n


# -- the objective -------------------------------------------------------------------------------
class Objective:
    """Callable Optuna objective of a study config (one per worker process)."""

    def __init__(self, cfg, cache_dir=None, worker: int = 0):
        self.cfg = cfg
        self.spaces = [ControllerSpace.from_config(c) for c in cfg.controllers]
        self.evaluator = Evaluator(cfg, cache_dir)
        self.worker = worker

    def _beat(self, trial):
        trial.set_user_attr("heartbeat", time.time())

    def __call__(self, trial):
        trial.set_user_attr("host", socket.gethostname())
        trial.set_user_attr("pid", os.getpid())
        trial.set_user_attr("worker", self.worker)
        self._beat(trial)
        systems = build_all(self.spaces, trial)
        runs = list(enumerate(self.cfg.train))
        np.random.default_rng(trial.number).shuffle(runs)
        scores, groups = [], {g: [] for g in GROUP_METRICS}
        for step, (scenario, seed) in runs:
            _, m = self.evaluator.run_systems(systems, scenario, seed)
            r = self.evaluator.ratios(m, scenario, seed)
            for g in GROUP_METRICS:
                groups[g].append(r[g])
            scores.append(self.evaluator.score(r))
            self._beat(trial)
            if not self.cfg.multi_objective:
                trial.report(scores[-1], step=step)
                if trial.should_prune():
                    break
        means = {g: float(np.mean(v)) for g, v in groups.items()}
        trial.set_user_attr("n_runs", len(scores))
        trial.set_user_attr("ratios", means)
        if self.cfg.multi_objective:
            return tuple(means[g] for g in GROUP_METRICS)
        return float(np.mean(scores))


def run_worker(cfg, n_total: int, storage_url=None, worker: int = 0, cache_dir=None,
               progress=None) -> int:
    """Run trials until the study has ``n_total`` finished ones; returns trials run here.

    Trials running in other workers count towards the total, so parallel workers do not
    overshoot it; a PSO study only runs the trials the swarm enqueued.
    """
    study = open_study(cfg, storage_url, worker)
    objective = Objective(cfg, cache_dir, worker)
    done = 0
    while True:
        reap_stale(study, cfg.stale_after_s)
        busy = len(study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)))
        waiting = len(study.get_trials(deepcopy=False, states=(TrialState.WAITING,)))
        if n_finished(study) + busy >= n_total or (cfg.sampler == "pso" and not waiting):
            return done
        study.optimize(objective, n_trials=1, catch=(FloatingPointError, ValueError))
        done += 1
        if progress is not None:
            progress(n_finished(study))


def best_trials(study, cfg):
    """Fully evaluated finished trials, best first (single objective) or the Pareto set."""
    full = [t for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))
            if t.user_attrs.get("n_runs") == len(cfg.train)]
    if cfg.multi_objective:
        from optuna.study._multi_objective import _get_pareto_front_trials_by_trials

        return _get_pareto_front_trials_by_trials(full, study.directions)
    return sorted(full, key=lambda t: t.value if math.isfinite(t.value) else math.inf)
