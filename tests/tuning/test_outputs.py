"""``study export --out`` and ``study report`` into a full disk or a read-only directory: one
line, exit code 2, the files already there unchanged, no temporary file left.

Both faults are simulated (the tests run as root, whom a read-only mode does not stop): a
full disk by ``os.replace`` / ``os.fsync`` failing with ENOSPC, a read-only directory by the
creation of the temporary file failing with EROFS.  A failure part-way (the second file
written, or a rename while the finished files are moved into place) is simulated by making
one chosen ``os.replace`` fail.
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
    assert err.startswith(f"fuzzynav: error: {path}") and ": cannot write " in err, err
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


def fail_replace(monkeypatch, when, nth=2) -> list:
    """Make the ``nth`` ``os.replace`` for which ``when(source, target)`` holds fail (ENOSPC);
    returns the targets of the ones that went through before it."""
    real, done = os.replace, []

    def replace(src, dst, **kw):
        if when(str(src), str(dst)):
            if len(done) == nth - 1:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            done.append(str(dst))
        return real(src, dst, **kw)
    monkeypatch.setattr(os, "replace", replace)
    return done


def into_staging(src, dst) -> bool:
    return ".staged-" in dst


def old_files(directory, *names) -> dict:
    """``directory`` holding files the new outputs do not resemble."""
    directory.mkdir(parents=True)
    for name in names:
        (directory / name).write_text(f"an older {name}\n")
    return snapshot(directory)


def test_report_failing_at_its_second_file_publishes_none(done, tmp_path, capsys,
                                                          monkeypatch):
    """trials.csv is written first; the figure after it fails: trials.csv must not be
    published either (the old one, differing from the new, stays)."""
    cfg, cache = done
    out = tmp_path / "report"
    before = old_files(out, "trials.csv", "report.md", "notes.txt")
    staged = fail_replace(monkeypatch, into_staging)
    msg = one_error_line(capsys, ["study", "report", cfg.path, "--no-eval", "--out", out,
                                  "--cache", cache], out)
    assert len(staged) == 1 and "(nothing was changed)" in msg
    assert snapshot(out) == before


def test_export_failing_at_its_second_write_publishes_none(done, tmp_path, capsys,
                                                           monkeypatch):
    """The rule file is written twice (then with its ``expected`` block); the second
    write fails: the old file stays and nothing else is left."""
    cfg, cache = done
    out = tmp_path / "rules" / "tuned.json"
    before = old_files(out.parent, "tuned.json")
    staged = fail_replace(monkeypatch, into_staging)
    msg = one_error_line(capsys, ["study", "export", cfg.path, "--out", out, "--cache", cache],
                         out)
    assert len(staged) == 1 and "(nothing was changed)" in msg
    assert snapshot(out.parent) == before


def test_report_failing_while_publishing_lists_what_it_wrote(done, tmp_path, capsys,
                                                             monkeypatch):
    cfg, cache = done
    out = tmp_path / "report"
    before = old_files(out, "trials.csv", "report.md")
    published = fail_replace(monkeypatch, lambda src, dst: ".staged-" in src
                             and os.path.dirname(dst) == str(out))
    msg = one_error_line(capsys, ["study", "report", cfg.path, "--no-eval", "--out", out,
                                  "--cache", cache], out)
    assert len(published) == 1 and published[0].startswith(str(out))
    assert msg.endswith(f"(files written before it: {published[0]})"), msg
    assert "nothing was changed" not in msg
    after = snapshot(out)
    assert after[os.path.basename(published[0])] != before.get(os.path.basename(published[0]))
    assert after["report.md"] == before["report.md"]  # the index moves last: not reached
    assert not [n for n in after if n.startswith(".")]  # the staging directory is gone
