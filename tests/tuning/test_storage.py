"""Journal storage and workers: exact totals with parallel workers, resuming, killed workers
(SIGKILL mid-trial), the reaper and its races, missing studies."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import optuna
import pytest
from optuna.storages.journal import JournalFileBackend, JournalStorage
from optuna.trial import TrialState

from fuzzynav.errors import FuzzynavError
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.tuning import optuna_study as study_mod
from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.study_run import run_study
from fuzzynav.tuning.slots import TrialSlots
from fuzzynav.tuning.space import build_all
from fuzzynav.tuning.optuna_study import (Objective, open_study, run_worker)
from tests.tuning.studies import ROOT, write_study

optuna.logging.set_verbosity(optuna.logging.ERROR)
LONG = Path(__file__).resolve().parent / "data" / "long.toml"


def journal(cfg):
    return Path(cfg.storage_url[len("journal:"):])


def states(study) -> dict:
    out = {}
    for t in study.get_trials(deepcopy=False):
        out[t.state] = out.get(t.state, 0) + 1
    return out


def assert_clean(directory):
    """No lock or temporary file left next to the journal."""
    left = [p.name for p in Path(directory).iterdir() if ".lock" in p.name or ".tmp" in p.name]
    assert not left, left


def dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


# -- totals, resuming ---------------------------------------------------------------------------
def test_parallel_workers_reach_the_total_exactly(tmp_path, sim_cache):
    cfg = load_study_config(write_study(tmp_path, study={"trials": 12}))
    study = run_study(cfg, workers=2, cache_dir=sim_cache, progress=False)
    trials = study.get_trials(deepcopy=False)
    assert states(study) == {TrialState.COMPLETE: 12}
    assert [t.number for t in trials] == list(range(12))
    # each worker samples with its own seed: no parameter set was drawn twice
    assert len({tuple(sorted(t.params.items())) for t in trials}) == 12
    assert {t.user_attrs["worker"] for t in trials} <= {0, 1}
    assert all(t.user_attrs["n_runs"] == len(cfg.train) for t in trials)
    assert_clean(tmp_path)


def test_two_workers_racing_for_the_last_trial_start_it_once(tmp_path, monkeypatch):
    """Both count the study at the same moment (a barrier holds whoever counted first until
    the other has counted too, or 2 s): without the count-then-start lock both would see
    room for one more trial and start it."""
    cfg = load_study_config(write_study(tmp_path))
    open_study(cfg, create=True)
    monkeypatch.setattr(Objective, "_run", lambda self, trial: 1.0)
    barrier = threading.Barrier(2, timeout=2.0)
    room = study_mod._room

    def count_then_wait(*args):
        ok = room(*args)
        try:
            barrier.wait()
        except threading.BrokenBarrierError:  # the other worker is held by the lock
            pass
        return ok

    monkeypatch.setattr(study_mod, "_room", count_then_wait)
    done = []
    workers = [threading.Thread(target=lambda: done.append(run_worker(cfg, 1)))
               for _ in range(2)]
    for w in workers:
        w.start()
    for w in workers:
        w.join(60)
    assert sorted(done) == [0, 1]
    assert states(open_study(cfg)) == {TrialState.COMPLETE: 1}


@pytest.mark.slow
def test_many_workers_on_one_journal_never_overshoot(tmp_path, sim_cache):
    """Four processes racing for the last trials, three rounds (without the lock this
    overshot by one in about half of the runs here)."""
    cfg = load_study_config(write_study(tmp_path, study={"trials": 10},
                                        train={"seeds": [0]}))
    for k in (1, 2, 3):  # three rounds of "resume to k * 10" with 4 workers
        study = run_study(cfg, trials=10 * k, workers=4, cache_dir=sim_cache, progress=False)
        assert states(study) == {TrialState.COMPLETE: 10 * k}


def test_resuming_continues_the_study(tmp_path, sim_cache):
    cfg = load_study_config(write_study(tmp_path))
    first = run_study(cfg, trials=2, cache_dir=sim_cache, progress=False)
    before = [(t.params, t.value) for t in first.trials]
    again = run_study(cfg, trials=5, cache_dir=sim_cache, progress=False)
    after = [(t.params, t.value) for t in again.trials]
    assert len(after) == 5 and after[:2] == before
    assert states(again) == {TrialState.COMPLETE: 5}
    # the resumed process does not redraw the parameters the first one drew
    assert len({tuple(sorted(p.items())) for p, _ in after}) == 5
    # already at the total: nothing more runs
    assert len(run_study(cfg, trials=5, cache_dir=sim_cache, progress=False).trials) == 5
    assert_clean(tmp_path)


@pytest.mark.parametrize("sampler", ["random", "tpe", "nsga2", "qmc"])
def test_a_resumed_study_draws_new_parameters_and_runs_are_reproducible(tmp_path, sampler,
                                                                          monkeypatch):
    monkeypatch.setattr(Objective, "_run",
                        lambda self, trial: float(len(build_all(self.spaces, trial))))
    params = []
    for name in ("a", "b"):
        cfg = load_study_config(write_study(tmp_path, name=name, file_name=f"{name}.toml",
                                            study={"sampler": sampler}))
        run_study(cfg, trials=3, progress=False)
        study = run_study(cfg, trials=6, progress=False)
        params.append([tuple(sorted(t.params.items())) for t in study.trials])
    assert len(set(params[0])) == 6       # no redrawn parameter set after the resume
    assert params[0] == params[1]         # same config, same history: same trials


# -- killed workers -------------------------------------------------------------------------------
def _start_worker(cfg, total, cache):
    return subprocess.Popen(
        [sys.executable, "-m", "fuzzynav.tuning.worker", str(cfg.path), "--total", str(total),
         "--cache", str(cache)], cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
        env=dict(os.environ, PYTHONWARNINGS="ignore"))


def _wait_for_running(study, proc, min_complete, timeout_s=90.0):
    """A trial of ``proc`` seen RUNNING with some of its runs done (so in the middle of
    its evaluation), once ``min_complete`` trials are complete."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        assert proc.poll() is None, proc.stderr.read().decode()
        done = len(study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)))
        for t in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
            if done >= min_complete and t.user_attrs.get("pid") == proc.pid \
                    and t.intermediate_values:
                return t.number
        time.sleep(0.02)
    raise AssertionError("the worker never started a trial")


def test_a_worker_killed_mid_trial_loses_nothing_and_its_trial_is_retried(tmp_path, sim_cache):
    scn = load_scenario(LONG)
    seeds = [0, 1, 2, 3, 4, 5]
    for sd in seeds:
        simulate(scn, sd, sim_cache)  # the worker finds the logs cached
    cfg = load_study_config(write_study(
        tmp_path, train={"scenarios": [str(LONG)], "seeds": seeds},
        study={"stale_after_s": 5.0}))
    total = 4
    open_study(cfg, create=True)
    watcher = optuna.load_study(study_name=cfg.name,
                                storage=JournalStorage(JournalFileBackend(str(journal(cfg)))))
    for attempt in range(3):  # the kill must land mid-trial; a trial lasts about a second
        proc = _start_worker(cfg, total, sim_cache)
        number = _wait_for_running(watcher, proc, min_complete=1)
        done_before = {t.number: (t.params, t.value) for t in
                       watcher.get_trials(states=(TrialState.COMPLETE,))}
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        killed = watcher.get_trials(deepcopy=False)[number]
        if killed.state == TrialState.RUNNING:
            break
    else:
        pytest.fail("three kills in a row landed between trials")
    assert proc.returncode == -signal.SIGKILL
    # Optuna itself never fails it: still RUNNING, and no completed trial was lost
    assert {t.number: (t.params, t.value) for t in
            watcher.get_trials(states=(TrialState.COMPLETE,))} == done_before
    # the next worker reaps it (its process is gone), retries its parameters, and stops
    # at the total
    run_worker(cfg, total, cache_dir=sim_cache)
    trials = watcher.get_trials(deepcopy=False)
    assert trials[number].state == TrialState.FAIL
    retries = [t for t in trials if t.user_attrs.get("retry_of") == number]
    assert len(retries) == 1
    assert retries[0].state == TrialState.COMPLETE and retries[0].params == killed.params
    assert retries[0].user_attrs["retries"] == 1
    assert len([t for t in trials if t.state == TrialState.COMPLETE]) == total
    assert not [t for t in trials if t.state in (TrialState.RUNNING, TrialState.WAITING)]
    for n, (params, value) in done_before.items():
        assert (trials[n].params, trials[n].value) == (params, value)
    assert_clean(tmp_path)


# -- opening -------------------------------------------------------------------------------------
def test_opening_a_study_that_does_not_exist(tmp_path):
    cfg = load_study_config(write_study(tmp_path))
    with pytest.raises(FuzzynavError, match="no study named 'tiny'.*run it first"):
        open_study(cfg)
    assert not journal(cfg).exists()  # nothing created on the way
    other = load_study_config(write_study(tmp_path, name="other"))
    open_study(other, create=True)
    with pytest.raises(FuzzynavError, match="no study named 'tiny'"):
        open_study(cfg, storage_url=other.storage_url)


def test_an_unreachable_database_is_one_clear_error(tmp_path):
    cfg = load_study_config(write_study(tmp_path))
    url = "postgresql://me:secret@127.0.0.1:1/none"
    with pytest.raises(FuzzynavError, match=r"storage postgresql://me:\*\*\*@127.0.0.1:1/none: "
                                            "cannot open it") as err:
        open_study(cfg, storage_url=url, create=True)
    assert "secret" not in str(err.value)


def test_a_bare_path_as_storage_says_how_to_write_a_journal(tmp_path):
    cfg = load_study_config(write_study(tmp_path))
    bare = str(tmp_path / "study.journal")
    with pytest.raises(FuzzynavError, match=f"storage {bare}: not a storage URL; for a "
                                            f"journal file write journal:{bare}"):
        open_study(cfg, storage_url=bare, create=True)
    assert not (tmp_path / "study.journal").exists()


@pytest.mark.parametrize("where, message", [
    ("dir", "is a directory; name a journal file"),
    ("/proc/fuzzynav-no/journal.log", "cannot open the journal file"),
    ("/proc/fuzzynav-journal.log", "cannot open the journal file"),
])
def test_a_journal_that_cannot_be_a_file_is_one_clear_error(tmp_path, where, message):
    cfg = load_study_config(write_study(tmp_path))
    path = str(tmp_path) if where == "dir" else where
    with pytest.raises(FuzzynavError, match=message) as err:
        open_study(cfg, storage_url=f"journal:{path}", create=True)
    assert f"storage journal:{path}" in str(err.value)


def test_the_slot_lock_is_the_journal_itself(tmp_path):
    """flock on the journal: exclusive between processes, released by a kill, no file."""
    path = tmp_path / "s.journal"
    path.write_bytes(b"")
    slots = TrialSlots(f"journal:{path}", "s")
    slots.acquire()
    probe = ("import fcntl, sys\nf = open(sys.argv[1], 'ab')\n"
             "try:\n    fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)\nexcept OSError:\n"
             "    sys.exit(3)\n")
    assert subprocess.run([sys.executable, "-c", probe, str(path)]).returncode == 3
    slots.release()
    assert subprocess.run([sys.executable, "-c", probe, str(path)]).returncode == 0
    holder = subprocess.Popen([sys.executable, "-c", "import fcntl, sys, time\n"
                               "f = open(sys.argv[1], 'ab')\nfcntl.flock(f, fcntl.LOCK_EX)\n"
                               "print('held', flush=True)\ntime.sleep(60)\n", str(path)],
                              stdout=subprocess.PIPE)
    assert holder.stdout.readline().strip() == b"held"
    holder.kill()
    holder.wait()
    slots.acquire()  # would block forever if the kill had left the lock held
    slots.release()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.journal"]
