"""Optuna studies over the rule search space: storage, samplers, pruning, workers.

Storage: by default a journal file next to the study config (safe for many processes on one
machine); any Optuna storage URL (``postgresql://...``) lets many machines share a study.
Journal storage has no heartbeat, so each worker first *reaps*: a ``RUNNING`` trial whose
worker process is gone (same host: its pid no longer exists) or, from another host, whose
heartbeat is older than ``stale_after_s`` is marked ``FAIL`` and its parameters are enqueued
again (at most :data:`MAX_RETRIES` times).  RDB storages also use Optuna's heartbeat with
:class:`optuna.storages.RetryHeartbeatStaleTrialCallback`.

Totals: a worker counts the finished and running trials and starts one more only while the
total is below the target; the count and the start of the trial hold a lock
(:mod:`fuzzynav.tuning.slots`: the journal file, or a PostgreSQL advisory lock), so the
workers reach the total exactly.

Pruning (single objective): each training run's score is reported with a stable step id in
a per-trial shuffled order; when pruned, the trial returns the mean of the runs done so far
(so the sampler still learns from it) and records ``n_runs``; exports only consider trials
that ran every training run.
"""
from __future__ import annotations

import os
import re
import socket
import time
import warnings

import numpy as np
import optuna
from optuna.trial import TrialState

from fuzzynav.errors import FuzzynavError
from fuzzynav.fileio import process_alive
from fuzzynav.tuning.study_config import GROUP_METRICS
from fuzzynav.tuning.objective import Objective
from fuzzynav.tuning.samplers import get_optimiser
from fuzzynav.tuning.slots import TrialSlots

__all__ = ["FINISHED", "MAX_RETRIES", "MAX_FAILS_IN_ROW", "READY_POLL_S", "RUN_ATTRS",
           "journal_path", "with_driver", "make_storage", "sampler_seed", "make_sampler",
           "make_pruner", "open_study", "NewStudy", "n_finished", "reap_stale", "reap_orphans",
           "run_worker", "pareto_front", "best_trials"]

optuna.logging.set_verbosity(optuna.logging.WARNING)
FINISHED = (TrialState.COMPLETE, TrialState.PRUNED)
MAX_RETRIES = 2
#: a worker gives up after this many failed trials in a row (a broken setup, not bad luck)
MAX_FAILS_IN_ROW = 10
#: how often a worker whose sampler is not ready for a new trial looks again [s]
READY_POLL_S = 0.05
#: user attributes of a trial's run (its worker, results, retry count): a retry does not
#: inherit them; it keeps every other one (a sampler's, e.g. which swarm particle it is)
RUN_ATTRS = ("host", "pid", "worker", "heartbeat", "n_runs", "ratios", "retry_of", "retries")


# -- storage, sampler, pruner ------------------------------------------------------------------
def journal_path(url: str):
    """The file of a ``journal:PATH`` storage URL (None for other storages)."""
    return url[len("journal:"):] if url.startswith("journal:") else None


def _hide_password(url: str) -> str:
    return re.sub(r"://([^:/@]+):[^@]*@", r"://\1:***@", url)


def with_driver(url: str) -> str:
    """``postgresql://`` with the PostgreSQL driver that is installed.

    SQLAlchemy 2.1 reads a bare ``postgresql://`` as psycopg 3, 2.0 as psycopg2 (which is
    what the ``studies`` extra installs): name whichever is importable.
    """
    m = re.match(r"^postgres(?:ql)?://", url)
    if not m:
        return url
    import importlib.util

    for module, driver in (("psycopg", "psycopg"), ("psycopg2", "psycopg2")):
        if importlib.util.find_spec(module) is not None:
            return f"postgresql+{driver}://" + url[m.end():]
    return url


def make_storage(url: str, heartbeat: bool = True):
    """An Optuna storage from ``journal:PATH`` or an RDB URL."""
    path = journal_path(url)
    if path is not None:
        from fuzzynav.tuning.journal import open_journal

        if os.path.isdir(path):
            raise FuzzynavError(f"storage {url}: {path} is a directory; name a journal "
                                f"file, e.g. journal:{path}/study.log")
        try:
            os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
            return open_journal(path)  # repairs a record cut off by a full disk
        except OSError as exc:  # /proc, read-only, no permission: one line, not a traceback
            raise FuzzynavError(f"storage {url}: cannot open the journal file "
                                f"({exc.strerror or type(exc).__name__})") from None
    if "://" not in url:  # a bare path: SQLAlchemy's "could not parse" says nothing useful
        raise FuzzynavError(f"storage {url}: not a storage URL; for a journal file write "
                            f"journal:{url}, for a database a URL such as "
                            "sqlite:///study.db or postgresql://user@host/db")
    try:
        with warnings.catch_warnings():  # the heartbeat and its retry, chosen knowingly
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            kw = dict(heartbeat_interval=10, grace_period=60,
                      heartbeat_stale_trial_callback=optuna.storages.
                      RetryHeartbeatStaleTrialCallback(max_retry=MAX_RETRIES)) \
                if heartbeat else {}
            return optuna.storages.RDBStorage(with_driver(url), **kw)
    except Exception as exc:  # sqlalchemy: bad URL, missing driver, server down
        raise FuzzynavError(f"storage {_hide_password(url)}: cannot open it "
                            f"({type(exc).__name__}: {str(exc).splitlines()[0]})") from None


def sampler_seed(cfg, worker: int = 0, start: int = 0) -> int:
    """Seed of worker ``worker``'s sampler in a process that starts with ``start`` trials
    in the study: each worker draws its own numbers, and a resumed run does not redraw the
    parameters the first run drew (Optuna keeps no sampler state in the storage)."""
    return int(np.random.SeedSequence([cfg.seed, worker, start]).generate_state(1)[0])


def make_sampler(cfg, worker: int = 0, start: int = 0):
    """The configured optimiser's sampler, seeded by :func:`sampler_seed` (or by the
    config's seed when the optimiser shares one sequence among workers and runs, QMC)."""
    opt = get_optimiser(cfg.sampler)
    return opt.make(cfg, cfg.seed if opt.shared_seed else sampler_seed(cfg, worker, start))


def make_pruner(cfg):
    """The configured pruner (none for multi-objective studies and for optimisers that
    need every training run of a trial)."""
    if cfg.multi_objective or cfg.pruner == "none" or not get_optimiser(cfg.sampler).pruning:
        return optuna.pruners.NopPruner()
    if cfg.pruner == "median":
        return optuna.pruners.MedianPruner(n_startup_trials=5, n_warmup_steps=2)
    return optuna.pruners.WilcoxonPruner(p_threshold=0.1, n_startup_steps=2)


def open_study(cfg, storage_url=None, worker: int = 0, create: bool = False, opened=None):
    """Create (``create=True``, in the parent) or load the study of a config.

    Loading a study that does not exist raises :class:`FuzzynavError` (and creates no
    journal file).  ``opened``: the storage of ``storage_url`` already opened
    (:class:`NewStudy`'s).
    """
    url = storage_url or cfg.storage_url
    missing = f"no study named {cfg.name!r} in {_hide_password(url)}; run it first"
    path = journal_path(url)
    if not create and path is not None and not os.path.isfile(path):
        raise FuzzynavError(missing)
    with warnings.catch_warnings():  # group=True, Wilcoxon, heartbeat: chosen knowingly
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        kw = dict(study_name=cfg.name, storage=opened or make_storage(url),
                  sampler=make_sampler(cfg, worker), pruner=make_pruner(cfg))
    if create:
        study = optuna.create_study(directions=cfg.directions, load_if_exists=True, **kw)
        if cfg.multi_objective:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
                study.set_metric_names(["accuracy", "worst_scenario"] if cfg.robust else
                                       [f"{g}_ratio" for g in GROUP_METRICS])
        return study
    try:
        study = optuna.load_study(**kw)
    except KeyError:
        raise FuzzynavError(missing) from None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        study.sampler = make_sampler(cfg, worker, len(study.get_trials(deepcopy=False)))
    return study


def _sqlite_path(url: str):
    """The database file of a ``sqlite:///PATH`` URL (None for other storages)."""
    return url[len("sqlite:///"):] or None if url.startswith("sqlite:///") else None


class NewStudy:
    """Whether a config's study is new to its storage, and undoing its creation.

    Made before :func:`open_study` creates the study: a study that a run creates and that
    stops before any trial finished (a refused objective, a bad rule template, Ctrl-C while
    the training runs are simulated) is removed again by :meth:`discard`, so a failed first
    run leaves nothing behind -- a journal or SQLite file it created is deleted, and in a
    storage that held the study's neighbours (a shared journal, a database) only that study
    goes.
    """

    def __init__(self, cfg, storage_url=None):
        self.name = cfg.name
        self.url = storage_url or cfg.storage_url
        path = journal_path(self.url) or _sqlite_path(self.url)
        self.file = path if path is not None and not os.path.isfile(path) else None
        #: the storage, opened once: :func:`open_study` takes it (a journal is replayed once)
        self.storage = make_storage(self.url)
        self.new = self.file is not None or \
            self.name not in optuna.get_all_study_names(self.storage)

    def discard(self, study) -> None:
        """Remove the study when this run created it and none of its trials finished."""
        if not self.new or n_finished(study):
            return
        if self.file is not None:
            if os.path.isfile(self.file):
                os.unlink(self.file)
        else:
            optuna.delete_study(study_name=self.name, storage=self.storage)


# -- bookkeeping ---------------------------------------------------------------------------------
def n_finished(study) -> int:
    """Trials that count towards the study's total (complete or pruned)."""
    return len(study.get_trials(deepcopy=False, states=FINISHED))


def _owner(t, now: float):
    """``(host, pid, last heartbeat)`` of a running trial's worker.

    Attributes older than the trial's start were inherited from the trial it retries
    (Optuna's heartbeat retry copies them): they say nothing about this run.
    """
    ua = t.user_attrs
    start = t.datetime_start.timestamp() if t.datetime_start else now
    beat = ua.get("heartbeat")
    if beat is None or beat < start:
        return None, None, start
    return ua.get("host"), ua.get("pid"), beat


def reap_stale(study, stale_after_s: float, exclusive: bool = False) -> int:
    """Fail and re-enqueue ``RUNNING`` trials whose worker is gone; returns how many.

    A worker on this host is gone when its process no longer exists (a live process keeps
    its trial, however long it runs); a worker elsewhere when its heartbeat is older than
    ``stale_after_s``.  When two workers reap the same trial, only the one whose ``FAIL``
    lands first re-enqueues it.

    ``exclusive``: the caller holds the study's slot lock (:class:`TrialSlots`), which a
    worker keeps from before it creates a trial until the trial names its owner.  A trial
    that names no owner then has none (its worker was killed in between) and is reaped at
    once, not after ``stale_after_s``.
    """
    now, host, n = time.time(), socket.gethostname(), 0
    for t in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        w_host, pid, beat = _owner(t, now)
        if w_host == host and pid is not None:
            if process_alive(int(pid)):
                continue
        elif w_host is None and exclusive:
            pass  # ownerless under the lock: an orphan
        elif now - beat <= stale_after_s:
            continue
        try:
            study.tell(t.number, state=TrialState.FAIL)
        except Exception:  # another worker reaped it first (or its worker just finished)
            continue
        n += 1
        retries = int(t.user_attrs.get("retries", 0))
        if retries < MAX_RETRIES and t.params:
            keep = {k: v for k, v in t.user_attrs.items() if k not in RUN_ATTRS}
            study.enqueue_trial(t.params, user_attrs={**keep, "retry_of": t.number,
                                                      "retries": retries + 1})
    return n


def _room(study, cfg, n_total: int) -> bool:
    """Whether another trial may start (finished + running < total)."""
    busy = len(study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)))
    return n_finished(study) + busy < n_total


def reap_orphans(study, cfg, url: str) -> int:
    """:func:`reap_stale` under the study's slot lock (a supervisor, between trials)."""
    slots = TrialSlots(with_driver(url), cfg.name)
    try:
        slots.acquire()
        return reap_stale(study, cfg.stale_after_s, exclusive=slots.exclusive)
    finally:
        slots.close()


def _run_one(study, objective, slots) -> TrialState:
    """Run one trial (the slot lock is released once the trial names its owner, so that a
    trial without one, seen under the lock, is an orphan); its final state."""
    def run(trial):
        objective.claim(trial)
        slots.release()
        return objective(trial)

    objective.current = None
    try:
        study.optimize(run, n_trials=1, catch=(FloatingPointError, ValueError))
    except (ValueError, optuna.exceptions.UpdateFinishedTrialError):
        # Raised by Optuna's final tell when another worker already failed this trial
        # (its heartbeat looked stale to a worker on another host): the trial is retried
        # there, this worker carries on.
        if objective.current is None or _state(study, objective.current) == TrialState.RUNNING:
            raise
    return _state(study, objective.current) if objective.current is not None else TrialState.FAIL


def _state(study, number: int) -> TrialState:
    return study.get_trials(deepcopy=False)[number].state


def run_worker(cfg, n_total: int, storage_url=None, worker: int = 0, cache_dir=None,
               progress=None, evaluator=None, make_objective=None) -> int:
    """Run trials until the study has ``n_total`` finished ones; returns trials run here.

    Trials running in other workers count towards the total, so parallel workers do not
    overshoot it (:func:`fuzzynav.tuning.study_run.run_study` rounds the total to what the
    optimiser runs: whole swarms for PSO).  ``evaluator``: a warm
    :class:`~fuzzynav.tuning.objective.Evaluator` to use (logs, baselines loaded).
    ``make_objective``: ``make_objective(worker) ->``
    :class:`~fuzzynav.tuning.objective.TrialObjective`, the objective of the study's kind
    (:mod:`fuzzynav.tuning.kinds`; default: a fuzzy study's
    :class:`~fuzzynav.tuning.objective.Objective` of ``cfg``).

    Raises
    ------
    FuzzynavError
        :data:`MAX_FAILS_IN_ROW` trials in a row failed in this worker.
    """
    url = storage_url or cfg.storage_url
    study = open_study(cfg, url, worker)
    objective = (make_objective(worker) if make_objective is not None
                 else Objective(cfg, cache_dir, worker, evaluator))
    slots = TrialSlots(with_driver(url), cfg.name)
    try:
        return _trials_until(study, cfg, n_total, objective, slots, progress)
    finally:
        slots.close()


def _trials_until(study, cfg, n_total, objective, slots, progress) -> int:
    ready = get_optimiser(cfg.sampler).ready
    done = fails = 0
    while True:
        slots.acquire()
        try:
            reap_stale(study, cfg.stale_after_s, exclusive=slots.exclusive)
            if not _room(study, cfg, n_total):
                return done
            if not ready(study, cfg):  # let the other workers finish what it waits for
                slots.release()
                time.sleep(READY_POLL_S)
                continue
            state = _run_one(study, objective, slots)
        finally:
            slots.release()
        done += 1
        fails = fails + 1 if state == TrialState.FAIL else 0
        if fails >= MAX_FAILS_IN_ROW:
            raise FuzzynavError(f"study {cfg.name!r}: {fails} trials in a row failed in worker "
                                f"{objective.worker}; the last with {objective.last_error!r}")
        if progress is not None:
            progress(n_finished(study))


def pareto_front(trials) -> list:
    """The trials no other trial dominates (every objective minimised)."""
    if not trials:
        return []
    vals = np.array([t.values for t in trials], dtype=float)
    keep = [not np.any(np.all(vals <= v, axis=1) & np.any(vals < v, axis=1)) for v in vals]
    return [t for t, k in zip(trials, keep) if k]


def best_trials(study, cfg):
    """Fully evaluated finished trials, best first (single objective) or the Pareto set."""
    full = [t for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))
            if t.user_attrs.get("n_runs") == len(cfg.train)]
    if cfg.multi_objective:
        return pareto_front(full)
    return sorted(full, key=lambda t: t.value if np.isfinite(t.value) else np.inf)
