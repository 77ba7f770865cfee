"""A study's start-up shares the baseline runs with forked helpers: the metrics equal those of
the serial start-up, the parent runs only its share, a helper that fails costs nothing but
time; the supervising parent wakes when a forked worker ends."""
from __future__ import annotations

import math
import multiprocessing
import os
import sys
import threading
import time

import optuna
import pytest
from optuna.trial import TrialState

from fuzzynav.tuning import objective, prefetch
from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.objective import Evaluator, Objective
from fuzzynav.tuning.study_run import run_study, wait_for_exit
from tests.tuning.studies import TINY, write_study

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="helpers are forked (Linux only)")
SEEDS = [0, 1, 2, 3]


@pytest.fixture
def cfg(tmp_path):
    return load_study_config(write_study(  # (random sampler, no pruner: every run scored)
        tmp_path, train={"scenarios": [str(TINY)], "seeds": SEEDS}))


@pytest.fixture
def counted_runs(monkeypatch):
    """The baseline runs made in this process (a forked helper counts into its own copy)."""
    calls = []
    real = objective.run_on_log

    def counting(log, name, **kw):
        calls.append(name)
        return real(log, name, **kw)

    monkeypatch.setattr(objective, "run_on_log", counting)
    return calls


def same_metrics(a: dict, b: dict) -> bool:
    """Equal keys, values equal within 1e-12 relative (NaN matching NaN)."""
    return a.keys() == b.keys() and all(
        (math.isnan(a[k]) and math.isnan(b[k])) or math.isclose(a[k], b[k], rel_tol=1e-12)
        for k in a)


def test_split_gives_every_run_once_in_shares_of_equal_size():
    runs = [("s", k) for k in range(8)]
    for processes in (2, 3):
        own, shares = prefetch.split(runs, processes)
        assert sorted(own + [r for s in shares for r in s]) == runs
        assert len(shares) == processes - 1
        sizes = [len(own)] + [len(s) for s in shares]
        assert max(sizes) - min(sizes) <= 1


def test_shared_baselines_equal_the_serial_ones(cfg, sim_cache, counted_runs):
    serial = Evaluator(cfg, sim_cache).prepare(cfg.train)
    del counted_runs[:]
    shared = prefetch.prepare_shared(Evaluator(cfg, sim_cache), cfg.train, 2)
    own, _ = prefetch.split(list(cfg.train), 2)
    assert len(counted_runs) == len(own) < len(cfg.train)  # the rest came from the helper
    for run in cfg.train:
        assert same_metrics(shared.baseline(*run), serial.baseline(*run)), run
        assert shared.log(*run) is not None
    assert len(counted_runs) == len(own)  # nothing recomputed on asking


def test_the_warm_start_with_two_processes_equals_the_serial_one(cfg, sim_cache,
                                                                 counted_runs):
    serial = Evaluator(cfg, sim_cache).prepare(cfg.train)
    del counted_runs[:]
    warm = prefetch.warm_shared(cfg, sim_cache, 2)
    baselines = [name for name in counted_runs if name == cfg.baseline]
    assert 0 < len(baselines) < len(cfg.train)  # the rest came from the helper
    for run in cfg.train:
        assert same_metrics(warm.baseline(*run), serial.baseline(*run)), run
    assert len([name for name in counted_runs if name == cfg.baseline]) == len(baselines)


def test_a_failing_helper_leaves_its_runs_to_the_parent(cfg, sim_cache, monkeypatch):
    serial = Evaluator(cfg, sim_cache).prepare(cfg.train)
    parent, real = os.getpid(), objective.run_on_log

    def only_here(log, name, **kw):
        if os.getpid() != parent:
            raise RuntimeError("a helper that fails")
        return real(log, name, **kw)

    monkeypatch.setattr(objective, "run_on_log", only_here)
    shared = prefetch.prepare_shared(Evaluator(cfg, sim_cache), cfg.train, 2)
    for run in cfg.train:
        assert same_metrics(shared.baseline(*run), serial.baseline(*run)), run


def test_a_failed_start_up_stops_the_log_loader(cfg, sim_cache, monkeypatch):
    """The kernels fail to load while the thread loads logs: the error is raised, the thread
    ends after the log it was loading (not after every log: a cold cache simulates them)."""
    from fuzzynav.errors import FuzzynavError
    from fuzzynav.tuning import warmup

    started, loaded = threading.Event(), []

    def slow_log(self, scenario, seed):
        loaded.append(seed)
        started.set()
        time.sleep(1.0)  # still loading when the start-up fails

    def failing_compile(cfg, cache_dir, evaluator):
        started.wait(30)
        raise FuzzynavError("no kernels")

    monkeypatch.setattr(Evaluator, "log", slow_log)
    monkeypatch.setattr(warmup, "compile_by_running", failing_compile)
    threads = threading.active_count()
    with pytest.raises(FuzzynavError, match="no kernels"):
        prefetch.warm_shared(cfg, sim_cache, 2)
    assert threading.active_count() == threads
    assert len(loaded) == 1 < len(cfg.train) - 1


def test_a_two_worker_study_scores_as_a_serial_evaluator_does(cfg, sim_cache):
    """Every trial of a two-worker study (baselines from the shared start-up) has the value
    its parameters get from an evaluator that ran every baseline itself."""
    total = 4
    study = run_study(cfg, trials=total, workers=2, cache_dir=sim_cache, progress=False)
    done = study.get_trials(states=(TrialState.COMPLETE,))
    assert len(done) == total
    assert {t.user_attrs["worker"] for t in done} <= {0, 1}
    for t in done:
        value = Objective(cfg, sim_cache)(optuna.trial.FixedTrial(t.params))
        assert math.isclose(t.value, value, rel_tol=1e-12), t.number


def test_the_parent_wakes_when_a_forked_worker_ends():
    class Worker:  # what wait_for_exit reads of a ForkedWorker
        def __init__(self, proc):
            self.proc, self.sentinel = proc, proc.sentinel

    ctx = multiprocessing.get_context("fork")
    quick, slow = ctx.Process(target=int), ctx.Process(target=ctx.Event().wait)
    quick.start()
    slow.start()
    try:
        wait_for_exit([Worker(quick), Worker(slow)], None)  # None: no timeout to fall back on
        quick.join()
        assert quick.exitcode == 0 and slow.exitcode is None
    finally:
        slow.kill()
        slow.join()
