"""Run a study: create it once, then one or more worker processes on the same storage."""
from __future__ import annotations

import os
import subprocess
import sys
import time

from tqdm.auto import tqdm

from fuzzynav.errors import FuzzynavError
from fuzzynav.tuning.study import n_finished, open_study, run_worker


def _spawn(cfg, total, storage, index, cache_dir):
    cmd = [sys.executable, "-m", "fuzzynav.tuning.worker", str(cfg.path), "--total", str(total),
           "--index", str(index), "--storage", storage or cfg.storage_url]
    if cache_dir:
        cmd += ["--cache", str(cache_dir)]
    return subprocess.Popen(cmd, env=dict(os.environ, PYTHONWARNINGS="ignore"))


def run_study(cfg, trials=None, workers: int = 1, storage=None, cache_dir=None,
              progress: bool = True):
    """Run ``cfg`` until its study holds ``trials`` finished trials (resumes if it exists).

    Parameters
    ----------
    cfg : StudyConfig
    trials : int, optional
        Total number of finished trials wanted (default: the config's).
    workers : int
        Processes running trials at once (1 = in this process).
    storage : str, optional
        Optuna storage URL overriding the config's (``journal:PATH`` or an RDB URL).
    cache_dir : path, optional
        Simulation cache shared by the workers (simulate the data before starting
        several workers, or let the first trials do it).

    Returns
    -------
    optuna.Study
    """
    total = int(trials or cfg.trials)
    if workers < 1:
        raise FuzzynavError(f"--workers must be >= 1, got {workers}")
    if workers > 1 and cfg.path is None:
        raise FuzzynavError("several workers need the study config as a file")
    study = open_study(cfg, storage, create=True)
    if cfg.sampler == "pso":
        from fuzzynav.tuning.pso import run_pso

        return run_pso(cfg, study, total, workers, storage, cache_dir, progress)
    start = n_finished(study)
    bar = tqdm(total=total, initial=min(start, total), disable=not progress, unit="trial",
               desc=cfg.name)
    if workers == 1:
        run_worker(cfg, total, storage, 0, cache_dir,
                   progress=lambda n: (bar.update(min(n, total) - bar.n)))
    else:
        _prepare_cache(cfg, cache_dir)
        procs = [_spawn(cfg, total, storage, i, cache_dir) for i in range(workers)]
        while any(p.poll() is None for p in procs):
            time.sleep(0.5)
            bar.update(min(n_finished(study), total) - bar.n)
        bad = [p.returncode for p in procs if p.returncode not in (0, None)]
        if bad:
            raise FuzzynavError(f"{len(bad)} worker(s) failed (exit codes {bad})")
    bar.update(min(n_finished(study), total) - bar.n)
    bar.close()
    return study


def _prepare_cache(cfg, cache_dir):
    """Simulate every training run once so that workers do not race to create the cache."""
    from fuzzynav.sim.log import simulate
    from fuzzynav.sim.scenario import load_scenario

    scenarios = {}
    for name, seed in cfg.train:
        scenarios.setdefault(name, load_scenario(name))
        simulate(scenarios[name], seed, cache_dir)
