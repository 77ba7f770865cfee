"""Run a study: create it once, then one or more worker processes on the same storage.

The parent first loads everything a trial needs -- the kernels (compiling them if the cache
is cold), the training logs and the baseline's metrics on them -- and then, on Linux, forks
its workers: they start warm, without importing the package, loading kernels or running the
baseline again (on other platforms they start as new interpreters, :data:`WORKER_BOOT`).
The parent supervises its workers: it polls every one of them (so a worker that dies is
reaped at once and never lingers as a zombie), fails and re-enqueues the trial a dead worker
left ``RUNNING`` (:func:`fuzzynav.tuning.optuna_study.reap_stale`), and starts a replacement while
the study is short of its total.  A worker that exits with code 2 (a user error such as
repeated failed trials) is not restarted: the run ends with that error.
"""
from __future__ import annotations

import multiprocessing
import multiprocessing.connection
import os
import signal
import subprocess
import sys
import time
import warnings

from tqdm.auto import tqdm

from fuzzynav.errors import FuzzynavError
from fuzzynav.tuning.samplers import get_optimiser
from fuzzynav.tuning.optuna_study import NewStudy, n_finished, open_study, reap_orphans, \
    run_worker

__all__ = ["WORKER_BOOT", "FORK", "MAX_RESTARTS", "USER_ERROR", "POLL_S", "worker_command",
           "ForkedWorker", "wait_for_exit", "supervise", "run_study", "run_plan",
           "open_plan_studies"]

#: a worker is started with this program instead of ``python -m``, which would put the
#: current directory first on its import path (a stray ``inspect.py`` there broke workers)
WORKER_BOOT = ("import sys\n"
               "if sys.path and sys.path[0] in ('', '.'):\n"
               "    del sys.path[0]\n"
               "from fuzzynav.tuning.worker import main\n"
               "sys.exit(main())\n")
#: workers are forked from the warm parent (Linux; macOS forks unsafely with some system
#: libraries, Windows cannot)
FORK = sys.platform.startswith("linux")
#: replacements the parent starts for workers that died, per worker slot
MAX_RESTARTS = 3
#: the exit code of a worker that stopped on a user error (not restarted)
USER_ERROR = 2
#: the supervising parent looks at its workers at least this often [s]
POLL_S = 0.5


def worker_command(cfg, total, storage, index, cache_dir, part: str = "",
                   study_seed=None) -> list:
    """The command line of study worker ``index`` (see :data:`WORKER_BOOT`); ``part``: the
    key of the file's study it runs (:mod:`fuzzynav.tuning.kinds`); ``study_seed``: the
    tuning seed of a ``--study-seeds`` run (:mod:`fuzzynav.tuning.tuning_seeds`)."""
    cmd = [sys.executable, "-c", WORKER_BOOT, str(cfg.path), "--total", str(total),
           "--index", str(index), "--storage", storage or cfg.storage_url]
    if cache_dir:
        cmd += ["--cache", str(cache_dir)]
    if part:
        cmd += ["--part", part]
    if study_seed is not None:
        cmd += ["--study-seed", str(study_seed)]
    return cmd


class ForkedWorker:
    """A worker forked from this process, with the ``poll``/``kill``/``wait`` of a Popen."""

    def __init__(self, cfg, total, storage, index, cache_dir, make_objective):
        self._proc = multiprocessing.get_context("fork").Process(
            target=_forked_main, args=(cfg, total, storage, index, cache_dir, make_objective),
            daemon=True)  # (daemon: never outlives the parent)
        self._proc.start()
        self.pid = self._proc.pid
        #: becomes readable when the worker ends (see :func:`wait_for_exit`)
        self.sentinel = self._proc.sentinel

    def poll(self):
        """The exit code (negative: killed by that signal), None while it runs."""
        return self._proc.exitcode

    def kill(self):
        self._proc.kill()

    def wait(self):
        self._proc.join()


def _forked_main(cfg, total, storage, index, cache_dir, make_objective):
    """A forked worker: :func:`run_worker` with the objective of the parent's warm plan."""
    warnings.simplefilter("ignore")
    try:
        run_worker(cfg, total, storage, index, cache_dir, make_objective=make_objective)
    except FuzzynavError as exc:
        print(f"fuzzynav worker {index}: error: {exc}", file=sys.stderr)
        sys.exit(USER_ERROR)


def _spawn(cfg, total, storage, index, cache_dir, make_objective=None, part="",
           study_seed=None):
    if FORK and make_objective is not None:
        return ForkedWorker(cfg, total, storage, index, cache_dir, make_objective)
    return subprocess.Popen(worker_command(cfg, total, storage, index, cache_dir, part,
                                           study_seed),
                            env=dict(os.environ, PYTHONWARNINGS="ignore"))


def wait_for_exit(procs, timeout: float) -> None:
    """Sleep until one of ``procs`` ends or ``timeout`` passes.

    Forked workers wake the parent the moment one ends (their sentinels): the study's end is
    noticed at once, not up to a poll interval later (a quarter of a second on average, 2 %
    of a 60-trial study with two workers).  Started interpreters (no sentinel) are polled.
    """
    sentinels = [getattr(p, "sentinel", None) for p in procs]
    if sentinels and None not in sentinels:
        multiprocessing.connection.wait(sentinels, timeout)
    else:
        time.sleep(timeout)


def _exit_text(code: int) -> str:
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"


def supervise(cfg, study, total, workers, storage=None, cache_dir=None, on_poll=None,
              make_objective=None, part="", study_seed=None):
    """Run ``workers`` worker processes until they stop; restart the ones that die.

    Parameters
    ----------
    cfg : StudyConfig
    study : optuna.Study
        The study the workers run (the parent's handle, used to reap and count).
    total : int
        Finished trials the workers stop at.
    workers : int
    storage, cache_dir
        Passed to the workers.
    on_poll : callable, optional
        Called about twice a second (progress display).
    make_objective : callable, optional
        ``make_objective(worker)``: the objective forked workers run, made from the warm
        plan they inherit (None: start new interpreters, which load the plan themselves).
    part : str
        The key of the file's study the workers run (:mod:`fuzzynav.tuning.kinds`).
    study_seed : int, optional
        The tuning seed of a ``--study-seeds`` run, passed to started workers.

    Raises
    ------
    FuzzynavError
        A worker stopped on a user error, or workers kept dying, and the study is short of
        ``total``.
    """
    url = storage or cfg.storage_url
    procs = {i: _spawn(cfg, total, storage, i, cache_dir, make_objective, part, study_seed)
             for i in range(workers)}
    restarts = dict.fromkeys(procs, 0)
    errors = []
    try:
        while procs:
            wait_for_exit(procs.values(), POLL_S)
            for i, p in list(procs.items()):
                code = p.poll()  # poll every worker: reaps the dead (no zombie)
                if code is None:
                    continue
                del procs[i]
                if code == 0:
                    if procs:  # a CPU is free until the others end: read the journal now,
                        n_finished(study)  # so the final count reads only their last trials
                    continue
                reap_orphans(study, cfg, url)  # its RUNNING trial: FAIL + retry
                if code != USER_ERROR and restarts[i] < MAX_RESTARTS \
                        and n_finished(study) < total:
                    restarts[i] += 1
                    tqdm.write(f"fuzzynav: worker {i} {_exit_text(code)}; its trial will be "
                               "retried, worker restarted", file=sys.stderr)
                    procs[i] = _spawn(cfg, total, storage, i, cache_dir, make_objective, part,
                                      study_seed)
                else:
                    errors.append((i, code))
            if on_poll is not None:
                on_poll()
    finally:  # interrupted: stop and reap the workers still running
        for p in procs.values():
            p.kill()
            p.wait()
    reap_orphans(study, cfg, url)
    done = n_finished(study)
    if errors and (done < total or any(code == USER_ERROR for _, code in errors)):
        what = "; ".join(f"worker {i} {_exit_text(code)}" for i, code in errors)
        raise FuzzynavError(f"study {cfg.name!r}: {what}; {done} of {total} trials finished")


def run_study(cfg, trials=None, workers: int = 1, storage=None, cache_dir=None,
              progress: bool = True, plan=None, part: str = ""):
    """Run ``cfg`` until its study holds ``trials`` finished trials (resumes if it exists).

    Parameters
    ----------
    cfg : StudyConfig
        The study (for a plan's part: ``plan.config(part)``).
    trials : int, optional
        Total number of finished trials wanted (default: the config's).
    workers : int
        Processes running trials at once (1 = in this process).
    storage : str, optional
        Optuna storage URL overriding the config's (``journal:PATH`` or an RDB URL).
    cache_dir : path, optional
        Simulation cache shared by the workers (the training runs are simulated into it
        here, before the workers start).
    plan : optional
        The study file's plan (:mod:`fuzzynav.tuning.kinds`), which makes the trials'
        objective; default: ``cfg`` as a fuzzy study.
    part : str
        Which of the plan's studies ``cfg`` is.

    Returns
    -------
    optuna.Study

    A study this call creates is removed again when the run stops before any of its
    trials finished (:class:`~fuzzynav.tuning.optuna_study.NewStudy`): a refused first
    run leaves no empty study behind.
    """
    from fuzzynav.tuning.kinds.fuzzy import FuzzyPlan

    plan = plan if plan is not None else FuzzyPlan(cfg, cache_dir)
    total = get_optimiser(cfg.sampler).budget(cfg, int(trials or cfg.trials))
    if workers < 1:
        raise FuzzynavError(f"--workers must be >= 1, got {workers}")
    if workers > 1 and cfg.path is None:
        raise FuzzynavError("several workers need the study config as a file")
    created = NewStudy(cfg, storage)
    study = open_study(cfg, storage, create=True, opened=created.storage)
    try:
        _run(cfg, study, plan, part, total, workers, storage, cache_dir, progress)
    except BaseException:
        created.discard(study)  # stopped before any trial finished: nothing left behind
        raise
    return study


def _run(cfg, study, plan, part, total, workers, storage, cache_dir, progress):
    """:func:`run_study`'s work on the opened ``study``."""
    if not study.trials:  # a new study: a warm start's first trial (a plan's, if it has one)
        for params in getattr(plan, "first_trials", list)():
            study.enqueue_trial(params, user_attrs={"warm_start": True})
    # what the (forked) workers start with, prepared by as many processes as will run trials
    plan.warm(workers if FORK else 1, progress)

    def make_objective(worker):
        return plan.objective(part, worker)

    start = n_finished(study)
    bar = tqdm(total=total, initial=min(start, total), disable=not progress, unit="trial",
               desc=cfg.name)
    if workers == 1:
        run_worker(cfg, total, storage, 0, cache_dir, make_objective=make_objective,
                   progress=lambda n: (bar.update(min(n, total) - bar.n)))
    else:
        # without a bar the parent only sleeps and reaps: reading the workers' journal
        # records would take CPU time from them
        supervise(cfg, study, total, workers, storage, cache_dir,
                  make_objective=make_objective, part=part,
                  study_seed=getattr(plan, "study_seed", None),
                  on_poll=(lambda: bar.update(min(n_finished(study), total) - bar.n))
                  if progress else None)
    bar.update(min(n_finished(study), total) - bar.n)
    bar.close()


def run_plan(plan, trials=None, workers: int = 1, storage=None, progress: bool = True):
    """Run every study of a study file's plan (:mod:`fuzzynav.tuning.kinds`) in turn, each
    until it holds ``trials`` finished trials, then let the plan write its product.

    Returns
    -------
    (dict, list)
        ``part -> optuna.Study`` and the lines :meth:`finish` returned (what was written).
    """
    studies = {}
    for part in plan.parts():
        studies[part] = run_study(plan.config(part), trials, workers, storage,
                                  plan.cache_dir, progress, plan=plan, part=part)
    return studies, plan.finish(studies, storage)


def open_plan_studies(plan, storage=None) -> dict:
    """``part -> optuna.Study`` of a plan's studies, loaded (a missing study:
    :class:`~fuzzynav.errors.FuzzynavError` naming it; no file is created)."""
    return {part: open_study(plan.config(part), storage) for part in plan.parts()}
