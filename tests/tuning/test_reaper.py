"""The reaper: RUNNING trials whose worker is gone are failed and retried, once, and only
those (split from test_storage.py, which keeps totals, resuming, killed workers, opening)."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
import types
from pathlib import Path

import optuna
import pytest
from optuna.storages.journal import JournalFileBackend, JournalStorage
from optuna.trial import TrialState

from fuzzynav.errors import FuzzynavError
from fuzzynav.tuning import optuna_study as study_mod
from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.optuna_study import (MAX_FAILS_IN_ROW, Objective, open_study, reap_orphans,
                                   reap_stale, run_worker)
from tests.tuning.studies import write_study

optuna.logging.set_verbosity(optuna.logging.ERROR)
LONG = Path(__file__).resolve().parent / "data" / "long.toml"


from tests.tuning.test_storage import dead_pid, journal, states


# -- the reaper ---------------------------------------------------------------------------------
@pytest.fixture
def bare(tmp_path):
    """A study on a journal file and a second handle on it (as another worker would have)."""
    path = str(tmp_path / "r.journal")
    a = optuna.create_study(study_name="r", storage=JournalStorage(JournalFileBackend(path)))
    b = optuna.load_study(study_name="r", storage=JournalStorage(JournalFileBackend(path)))
    return a, b


def _running(study, beat_in_s=0.0, **attrs):
    """A RUNNING trial with the given user attributes and a heartbeat ``beat_in_s`` from now
    (set after the trial started, as a worker does; None: no heartbeat)."""
    t = study.ask()
    t.suggest_float("x", 0.0, 1.0)
    for k, v in attrs.items():
        t.set_user_attr(k, v)
    if beat_in_s is not None:
        t.set_user_attr("heartbeat", time.time() + beat_in_s)
    return t.number


def test_two_reapers_of_the_same_trial_retry_it_once(bare, monkeypatch):
    a, b = bare
    n = _running(a, host=socket.gethostname(), pid=dead_pid())
    stale_view = b.get_trials(deepcopy=False, states=(TrialState.RUNNING,))
    assert [t.number for t in stale_view] == [n]
    assert reap_stale(a, 300.0) == 1
    # b read the trial list before a's FAIL landed: it must not retry the trial again
    monkeypatch.setattr(b, "get_trials", lambda *args, **kw: stale_view)
    assert reap_stale(b, 300.0) == 0
    monkeypatch.undo()
    assert [t.state for t in b.trials] == [TrialState.FAIL, TrialState.WAITING]
    assert b.trials[1].user_attrs == {"retry_of": n, "retries": 1}


def test_tell_fail_from_another_process_works_on_a_journal(bare):
    a, _ = bare
    n = _running(a)
    path = a._storage._backend._file_path
    code = ("import optuna\nfrom optuna.storages.journal import JournalFileBackend, "
            "JournalStorage\nfrom optuna.trial import TrialState\n"
            f"s = optuna.load_study(study_name='r', storage=JournalStorage("
            f"JournalFileBackend({path!r})))\ns.tell({n}, state=TrialState.FAIL)\n")
    subprocess.run([sys.executable, "-c", code], check=True)
    assert a.trials[n].state == TrialState.FAIL


def test_who_gets_reaped(bare, monkeypatch):
    a, _ = bare
    here = socket.gethostname()
    alive = _running(a, host=here, pid=os.getpid())
    dead = _running(a, host=here, pid=dead_pid())
    far = _running(a, host="elsewhere", pid=1)
    far_recent = _running(a, beat_in_s=90.0, host="elsewhere", pid=1)
    silent = _running(a, beat_in_s=None)  # killed before it recorded anything
    # attributes older than the trial's start were inherited from the trial it retries
    # (Optuna's RDB retry callback copies them): its own start time judges it
    inherited = _running(a, beat_in_s=-3600.0, host=here, pid=dead_pid())

    def state():
        return {t.number: t.state.name for t in a.trials if t.number <= inherited}

    assert reap_stale(a, 50.0) == 1
    assert state() == {alive: "RUNNING", dead: "FAIL", far: "RUNNING", far_recent: "RUNNING",
                       silent: "RUNNING", inherited: "RUNNING"}
    later = time.time() + 100.0  # 100 s on, nothing having been heard from anyone
    monkeypatch.setattr(study_mod.time, "time", lambda: later)
    assert reap_stale(a, 50.0) == 3
    assert state() == {alive: "RUNNING",     # its process runs: a long trial, not a dead one
                       dead: "FAIL", far: "FAIL", far_recent: "RUNNING", silent: "FAIL",
                       inherited: "FAIL"}
    retried = sorted(t.user_attrs["retry_of"] for t in a.trials if t.state == TrialState.WAITING)
    assert retried == [dead, far, silent, inherited]


_KILLED_IN_THE_WINDOW = """
import os, signal, sys
import optuna
from optuna.storages.journal import JournalFileBackend, JournalStorage
from fuzzynav.tuning.slots import TrialSlots
path = sys.argv[1]
study = optuna.load_study(study_name="r", storage=JournalStorage(JournalFileBackend(path)))
slots = TrialSlots("journal:" + path, "r")
slots.acquire()
t = study.ask()               # the trial exists, RUNNING ...
t.suggest_float("x", 0.0, 1.0)
os.kill(os.getpid(), signal.SIGKILL)   # ... and its worker dies before naming itself
"""


def test_a_worker_killed_before_naming_itself_is_reaped_at_once(bare):
    """The slot lock is held from before a trial is created until it names its owner, so
    an ownerless RUNNING trial seen under the lock is an orphan: reaped now, not after
    ``stale_after_s`` (300 s here)."""
    a, _ = bare
    path = a._storage._backend._file_path
    proc = subprocess.run([sys.executable, "-c", _KILLED_IN_THE_WINDOW, path], timeout=120)
    assert proc.returncode == -signal.SIGKILL
    assert [t.state for t in a.trials] == [TrialState.RUNNING]
    assert reap_stale(a, 300.0) == 0  # without the lock it may be a worker in the window
    cfg = types.SimpleNamespace(name="r", stale_after_s=300.0)
    assert reap_orphans(a, cfg, f"journal:{path}") == 1
    assert [t.state for t in a.trials] == [TrialState.FAIL, TrialState.WAITING]
    assert a.trials[1].user_attrs["retry_of"] == 0


def test_without_a_real_lock_ownerless_trials_wait_for_stale_after(tmp_path):
    """An in-memory or SQLite storage has no slot lock: nothing is known, so nothing is
    reaped before ``stale_after_s``."""
    study = optuna.create_study(storage=f"sqlite:///{tmp_path / 's.db'}", study_name="r")
    _running(study, beat_in_s=None)
    cfg = types.SimpleNamespace(name="r", stale_after_s=300.0)
    assert reap_orphans(study, cfg, f"sqlite:///{tmp_path / 's.db'}") == 0


def test_a_trial_is_retried_at_most_twice(bare):
    a, _ = bare
    _running(a, host=socket.gethostname(), pid=dead_pid())
    for _ in range(3):
        reap_stale(a, 300.0)
        t = a.ask()  # pops the retry, if any, whose worker dies too
        t.suggest_float("x", 0.0, 1.0)
        t.set_user_attr("host", socket.gethostname())
        t.set_user_attr("pid", dead_pid())
        t.set_user_attr("heartbeat", time.time())
    trials = a.trials
    assert [t.state for t in trials] == [TrialState.FAIL] * 3 + [TrialState.RUNNING]
    assert [t.user_attrs.get("retries", 0) for t in trials[:3]] == [0, 1, 2]
    assert trials[1].params == trials[2].params == trials[0].params
    assert "retry_of" not in trials[3].user_attrs  # a fresh trial: the retries are spent


def test_a_worker_whose_trial_was_reaped_elsewhere_carries_on(tmp_path, sim_cache, monkeypatch):
    """Another host judged this worker's trial stale and failed it while it ran."""
    cfg = load_study_config(write_study(tmp_path))
    open_study(cfg, create=True)
    other = optuna.load_study(study_name=cfg.name,
                              storage=JournalStorage(JournalFileBackend(str(journal(cfg)))))
    run = Objective._run
    reaped = []

    def run_but_reaped_first(self, trial):
        if not reaped:
            reaped.append(trial.number)
            other.tell(trial.number, state=TrialState.FAIL)
        return run(self, trial)

    monkeypatch.setattr(Objective, "_run", run_but_reaped_first)
    assert run_worker(cfg, 3, cache_dir=sim_cache) == 4
    assert [t.state for t in other.trials] == [TrialState.FAIL] + [TrialState.COMPLETE] * 3


def test_a_worker_gives_up_after_repeated_failures(tmp_path, sim_cache, monkeypatch):
    cfg = load_study_config(write_study(tmp_path))
    open_study(cfg, create=True)

    def broken(self, trial):
        raise ValueError("every candidate breaks")

    monkeypatch.setattr(Objective, "_run", broken)
    with pytest.raises(FuzzynavError, match=f"{MAX_FAILS_IN_ROW} trials in a row failed.*"
                                            "every candidate breaks"):
        run_worker(cfg, 50, cache_dir=sim_cache)
    study = open_study(cfg)
    assert states(study) == {TrialState.FAIL: MAX_FAILS_IN_ROW}


