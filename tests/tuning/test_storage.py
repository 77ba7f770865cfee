"""Journal storage and workers: exact totals with parallel workers, resuming, killed workers
(SIGKILL mid-trial), the reaper and its races, missing studies."""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
import types
from pathlib import Path

import optuna
import pytest
from optuna.storages.journal import JournalFileBackend, JournalStorage
from optuna.trial import TrialState

from fuzzynav.errors import FuzzynavError
from fuzzynav.sim.log import simulate
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.tuning import study as study_mod
from fuzzynav.tuning.config import load_study_config
from fuzzynav.tuning.run import run_study
from fuzzynav.tuning.slots import TrialSlots
from fuzzynav.tuning.space import build_all
from fuzzynav.tuning.study import (MAX_FAILS_IN_ROW, Objective, open_study, reap_orphans,
                                   reap_stale, run_worker)
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
