"""A journal whose last record was cut (disk full, killed writer) is repaired on open: every
complete record is kept, the cut one dropped and named, the original kept as ``.bak``."""
from __future__ import annotations

import errno
import json
import os
import shutil
import socket
import time
from pathlib import Path

import optuna
import pytest
from optuna.trial import TrialState

from fuzzynav.cli import main
from fuzzynav.errors import FuzzynavError
from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.journal import salvage, tail_ok
from fuzzynav.tuning.study_run import run_study
from fuzzynav.tuning.space import build_all
from fuzzynav.tuning.optuna_study import Objective, open_study
from tests.tuning.studies import write_study

optuna.logging.set_verbosity(optuna.logging.ERROR)


def record(i: int) -> bytes:
    return json.dumps({"op_code": 4, "worker_id": "w", "trial_id": i}).encode() + b"\n"


def test_salvage_keeps_complete_records_and_drops_cut_ones():
    a, b, c = record(0), record(1), record(2)
    kept, n, nbytes = salvage(a + b + c[:-7])  # the last record cut 7 bytes short
    assert (kept, n, nbytes) == (a + b, 1, len(c) - 7)
    # a record appended onto the cut one (the next write after the cut) is kept
    kept, n, nbytes = salvage(a + c[:-7] + b + record(3))
    assert (kept, n, nbytes) == (a + b + record(3), 1, len(c) - 7)
    assert salvage(a + b) == (a + b, 0, 0)


def test_tail_check(tmp_path):
    p = tmp_path / "j"
    for data, ok in ((b"", True), (record(0) + record(1), True),
                     (record(0) + record(1)[:-1], False),      # newline missing
                     (record(0) + record(1)[:-9] + b"\n", False)):  # cut, then a newline
        p.write_bytes(data)
        assert tail_ok(p) is ok, data


def _dead_pid() -> int:
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def _fake_run(pid):
    """A trial that takes no time and looks written by process ``pid`` (gone by now)."""
    def run(self, trial):
        build_all(self.spaces, trial)  # draws the parameters
        for k, v in (("host", socket.gethostname()), ("pid", pid), ("heartbeat", time.time()),
                     ("n_runs", len(self.cfg.train))):
            trial.set_user_attr(k, v)
        return float(trial.number + 1)
    return run


def test_a_cut_last_record_is_dropped_and_the_study_finishes(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(Objective, "_run", _fake_run(_dead_pid()))
    cfg = load_study_config(write_study(tmp_path, study={"trials": 3}))
    run_study(cfg, progress=False)
    path = Path(cfg.storage_url[len("journal:"):])
    original = path.read_bytes()
    last = original[:-1].rsplit(b"\n", 1)[1]
    cut = original[:-(len(last) // 2)]  # the disk filled up halfway through the last record
    path.write_bytes(cut)

    code = main(["study", "report", str(cfg.path), "--no-eval", "--out", str(tmp_path / "r")])
    err = capsys.readouterr().err
    assert code == 0, err
    line = [s for s in err.splitlines() if "warning" in s]
    assert len(line) == 1 and str(path) in line[0]
    assert f"dropped 1 incomplete record(s) ({len(last) - len(last) // 2 + 1} bytes" in line[0]
    assert Path(f"{path}.bak").read_bytes() == cut  # the original, as found
    assert path.read_bytes() == original[:-(len(last) + 1)]  # every complete record kept

    # the last trial lost its COMPLETE record: it shows as RUNNING of a dead worker, is
    # retried, and the study reaches its total
    study = run_study(cfg, progress=False)
    trials = study.get_trials(deepcopy=False)
    assert len([t for t in trials if t.state == TrialState.COMPLETE]) == 3
    assert trials[2].state == TrialState.FAIL and trials[3].user_attrs["retry_of"] == 2
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []


def test_a_record_appended_after_the_cut_one_is_kept(tmp_path, monkeypatch, capsys):
    """Without the repair the next append would glue a record onto the cut one, and Optuna
    would refuse the journal from then on."""
    monkeypatch.setattr(Objective, "_run", _fake_run(_dead_pid()))
    cfg = load_study_config(write_study(tmp_path, study={"trials": 2}))
    run_study(cfg, progress=False)
    path = Path(cfg.storage_url[len("journal:"):])
    data = path.read_bytes()
    last = data[:-1].rsplit(b"\n", 1)[1] + b"\n"
    head = data[:-len(last)]
    # the last record cut, then written again whole right after it, on the same line
    path.write_bytes(head + last[:len(last) // 2] + last)
    study = open_study(cfg)
    assert "dropped 1 incomplete record(s)" in capsys.readouterr().err
    assert len(study.get_trials(states=(TrialState.COMPLETE,))) == 2
    assert path.read_bytes() == data
    assert os.path.exists(f"{path}.bak")


def _enospc():
    return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def _copy_half(src, dst):
    """shutil.copyfile on a disk that fills up halfway through the copy."""
    data = Path(src).read_bytes()
    with open(dst, "wb") as fh:
        fh.write(data[:len(data) // 2])
    raise _enospc()


def _write_half(self, data):
    """Path.write_bytes on a disk that fills up halfway through."""
    with open(self, "wb") as fh:
        fh.write(data[:len(data) // 2])
    raise _enospc()


@pytest.mark.parametrize("failing", ["backup", "journal"])
def test_a_repair_on_a_full_disk_changes_nothing(tmp_path, monkeypatch, capsys, failing):
    monkeypatch.setattr(Objective, "_run", _fake_run(_dead_pid()))
    cfg = load_study_config(write_study(tmp_path, study={"trials": 2}))
    run_study(cfg, progress=False)
    path = Path(cfg.storage_url[len("journal:"):])
    cut = path.read_bytes()[:-20]
    path.write_bytes(cut)
    before = sorted(p.name for p in path.parent.iterdir())
    if failing == "backup":  # the disk fills up while the original is copied
        monkeypatch.setattr(shutil, "copyfile", _copy_half)
    else:  # the backup fits, the repaired journal does not
        monkeypatch.setattr(Path, "write_bytes", _write_half)

    code = main(["study", "report", str(cfg.path), "--no-eval", "--out", str(tmp_path / "r")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and str(path) in err[0] and "cannot be repaired" in err[0]
    assert os.strerror(errno.ENOSPC) in err[0]
    assert path.read_bytes() == cut  # the journal as found
    # no backup (partial or whole) and no temporary file: the next repair starts afresh
    assert sorted(p.name for p in path.parent.iterdir()) == before


def test_a_line_written_by_something_else_is_named_so(tmp_path, monkeypatch, capsys):
    """Not every damaged line is a cut-off write: a line that is not even the start of a
    record is reported as foreign (the repair still keeps every complete record)."""
    monkeypatch.setattr(Objective, "_run", _fake_run(_dead_pid()))
    cfg = load_study_config(write_study(tmp_path, study={"trials": 2}))
    run_study(cfg, progress=False)
    path = Path(cfg.storage_url[len("journal:"):])
    lines = path.read_bytes().splitlines(keepends=True)
    path.write_bytes(b"".join(lines[:2] + [b"garbage{{\n"] + lines[2:]))
    study = open_study(cfg)
    err = capsys.readouterr().err
    assert "dropped 1 incomplete record(s)" in err and "not journal records at all" in err
    assert "cut off by a full disk" not in err
    assert len(study.get_trials(states=(TrialState.COMPLETE,))) == 2


@pytest.mark.parametrize("content", [b"\x00\x01\x02", b"hello, not a journal\n"])
def test_a_file_that_is_no_journal_is_refused_not_emptied(tmp_path, content):
    """It was 'repaired' to nothing and the study silently started again from scratch."""
    cfg = load_study_config(write_study(tmp_path, study={"trials": 2}))
    path = Path(cfg.storage_url[len("journal:"):])
    path.write_bytes(content)
    with pytest.raises(FuzzynavError, match="not an Optuna journal"):
        open_study(cfg)
    assert path.read_bytes() == content and not list(tmp_path.glob("*.bak"))
