"""``study export --out`` and ``study report`` into a full disk or a read-only directory: one
line, exit code 2, the files already there unchanged, no temporary file left.

Both faults are simulated (the tests run as root, whom a read-only mode does not stop): a
full disk by ``os.replace`` / ``os.fsync`` failing with ENOSPC, a read-only directory by the
creation of the temporary file failing with EROFS.
"""
from __future__ import annotations

import errno
import os
import tempfile

import pytest

from fuzzynav.cli import main
from tests.tuning.studies import finished_study

FAULTS = [(os, "replace", errno.ENOSPC), (os, "fsync", errno.ENOSPC),
          (tempfile, "mkstemp", errno.EROFS), (tempfile, "mkdtemp", errno.EROFS)]


@pytest.fixture(scope="module")
def done(tmp_path_factory, sim_cache):
    d = tmp_path_factory.mktemp("outputs-study")
    cfg, _ = finished_study(d, sim_cache, trials=3)
    return cfg, sim_cache


def snapshot(directory) -> dict:
    return {p.name: p.read_bytes() for p in sorted(directory.iterdir())}


def fail_with(monkeypatch, module, name, err):
    def fail(*args, **kwargs):
        raise OSError(err, os.strerror(err))
    monkeypatch.setattr(module, name, fail)


def one_error_line(capsys, argv, path) -> str:
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "Traceback" not in err, err
    assert err.startswith(f"fuzzynav: error: {path}") and "cannot write it" in err, err
    return err


@pytest.mark.parametrize("module,name,err", [FAULTS[0], FAULTS[3]],
                         ids=["full-disk", "read-only"])
def test_export_into_a_full_disk_or_a_read_only_dir(done, tmp_path, capsys, monkeypatch,
                                                    module, name, err):
    cfg, cache = done
    out = tmp_path / "rules" / "tuned.json"
    argv = ["study", "export", cfg.path, "--out", out, "--cache", cache]
    assert main([str(a) for a in argv]) == 0
    before = snapshot(out.parent)
    fail_with(monkeypatch, module, name, err)
    msg = one_error_line(capsys, argv, out.parent if name == "mkdtemp" else out)
    assert os.strerror(err) in msg
    assert snapshot(out.parent) == before  # the old file intact, nothing else left


@pytest.mark.parametrize("module,name,err", FAULTS[:3], ids=["rename", "fsync", "read-only"])
def test_report_into_a_full_disk_or_a_read_only_dir(done, tmp_path, capsys, monkeypatch,
                                                    module, name, err):
    cfg, cache = done
    out = tmp_path / "report"
    argv = ["study", "report", cfg.path, "--no-eval", "--out", out, "--cache", cache]
    assert main([str(a) for a in argv]) == 0
    capsys.readouterr()
    before = snapshot(out)
    assert "report.md" in before and "trials.csv" in before
    fail_with(monkeypatch, module, name, err)
    msg = one_error_line(capsys, argv, out)
    assert os.strerror(err) in msg
    assert snapshot(out) == before
