"""Worker processes of ``run_study``: whichever worker is killed, it is reaped, its trial
failed and retried, and the study still reaches its total; workers do not import from the
current directory."""
from __future__ import annotations

import os
import signal
import threading
import time
from pathlib import Path

import optuna
import pytest
from optuna.storages.journal import JournalFileBackend, JournalStorage
from optuna.trial import TrialState

from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.study_run import run_study
from fuzzynav.fileio import process_alive as _alive
from fuzzynav.tuning.optuna_study import open_study
from tests.tuning.studies import write_study

optuna.logging.set_verbosity(optuna.logging.ERROR)
LONG = Path(__file__).resolve().parent / "data" / "long.toml"
SEEDS = [0, 1, 2, 3, 4, 5]


def zombie_children() -> list:
    """Children of this process that died and were never reaped."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_bytes().rsplit(b")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == os.getpid() and fields[0] == b"Z":
            out.append(int(stat.parent.name))
    return out


@pytest.fixture(scope="module")
def long_cache(tmp_path_factory):
    cache = tmp_path_factory.mktemp("long-cache")
    scn = load_scenario(LONG)
    for sd in SEEDS:
        simulate(scn, sd, cache)  # the workers find the logs cached
    return cache


def _kill_mid_trial(watcher, worker, timeout_s=120.0):
    """SIGKILL worker ``worker`` in the middle of a trial (a run reported, more to come)."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        for t in watcher.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
            if t.user_attrs.get("worker") == worker and t.intermediate_values \
                    and len(t.intermediate_values) < len(SEEDS) - 1:
                os.kill(t.user_attrs["pid"], signal.SIGKILL)
                return t
        time.sleep(0.02)
    raise AssertionError(f"worker {worker} never ran a trial")


def run_and_kill(cfg, cache, worker):
    """Run ``cfg`` with two workers, kill worker ``worker`` mid-trial; ``(the killed trial,
    every trial at the end)``.  The run must end without an error."""
    open_study(cfg, create=True)
    watcher = optuna.load_study(study_name=cfg.name, storage=JournalStorage(
        JournalFileBackend(cfg.storage_url[len("journal:"):])))
    result = {}
    runner = threading.Thread(target=lambda: result.update(study=run_study(
        cfg, workers=2, cache_dir=cache, progress=False)))
    runner.start()
    killed = _kill_mid_trial(watcher, worker)
    runner.join(300)
    assert not runner.is_alive()
    assert "study" in result, "run_study raised (see the captured output)"
    return killed, watcher.get_trials(deepcopy=False)


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")
@pytest.mark.parametrize("worker", [1, pytest.param(0, marks=pytest.mark.slow)],
                         ids=["second", "first"])
def test_a_killed_worker_is_reaped_and_its_trial_retried(tmp_path, long_cache, worker,
                                                          capfd):
    total = 4
    cfg = load_study_config(write_study(
        tmp_path, train={"scenarios": [str(LONG)], "seeds": SEEDS},
        study={"trials": total, "stale_after_s": 600.0}))  # only a dead pid gets reaped
    killed, trials = run_and_kill(cfg, long_cache, worker)
    assert len([t for t in trials if t.state == TrialState.COMPLETE]) == total
    assert not [t for t in trials if t.state in (TrialState.RUNNING, TrialState.WAITING)]
    assert trials[killed.number].state == TrialState.FAIL
    retry = [t for t in trials if t.user_attrs.get("retry_of") == killed.number]
    assert len(retry) == 1 and retry[0].state == TrialState.COMPLETE
    assert retry[0].params == killed.params
    assert not _alive(killed.user_attrs["pid"]) and zombie_children() == []
    assert f"worker {worker} killed by SIGKILL" in capfd.readouterr().err


def test_a_zombie_is_not_alive(tmp_path):
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    while proc.pid not in zombie_children():  # exited; not waited for yet
        time.sleep(0.01)
    assert not _alive(proc.pid)
    proc.wait()
    assert not _alive(proc.pid)
    assert _alive(os.getpid())


def test_workers_do_not_import_from_the_current_directory(tmp_path, sim_cache, monkeypatch):
    cfg = load_study_config(write_study(tmp_path, study={"trials": 2}))
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    for name in ("inspect", "optuna", "numpy"):  # shadows of modules every worker imports
        (cwd / f"{name}.py").write_text(f"raise SystemExit('imported the stray {name}.py')\n")
    monkeypatch.chdir(cwd)
    study = run_study(cfg, workers=2, cache_dir=sim_cache, progress=False)
    assert len(study.get_trials(states=(TrialState.COMPLETE,))) == 2


@pytest.mark.slow
def test_a_killed_pso_worker_is_replaced_and_the_swarm_completes(tmp_path, long_cache, capfd):
    cfg = load_study_config(write_study(
        tmp_path, train={"scenarios": [str(LONG)], "seeds": SEEDS},
        study={"sampler": "pso", "seed": 7, "trials": 100, "stale_after_s": 600.0,
               "pso": {"particles": 3, "iterations": 2, "inertia": [0.9, 0.4],
                       "c1": 1.5, "c2": 1.5}}))
    killed, trials = run_and_kill(cfg, long_cache, 1)
    done = sorted((t.user_attrs["pso_iteration"], t.user_attrs["particle"]) for t in trials
                  if t.state == TrialState.COMPLETE)
    assert done == [(k, i) for k in range(2) for i in range(3)]
    assert trials[killed.number].state == TrialState.FAIL
    assert zombie_children() == []
    assert "worker 1 killed by SIGKILL" in capfd.readouterr().err
