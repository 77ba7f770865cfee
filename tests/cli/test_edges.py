"""Edges of the command line: stdout that cannot be written, huge values, ignored options.

Each case exits with one line on stderr (or, for a reader that closed the pipe, quietly)
and no traceback.  The two subprocess tests check what an in-process call cannot: that
nothing more is printed when the interpreter flushes stdout at exit.
"""
import errno
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from fuzzynav import compile_notice
from fuzzynav.cli import EXIT_BROKEN_PIPE, MAX_MESSAGE, main
from fuzzynav.cli.values import MAX_MC
from tests.cli.test_bad_values import _one_line, _run

ROOT = Path(__file__).resolve().parents[2]
TINY = ROOT / "tests" / "tuning" / "data" / "tiny.toml"
QUICKSTART = ROOT / "studies" / "quickstart.toml"
GPS = ROOT / "rules" / "paper000_gps_sins.json"
LONG = 200_000


class _FailingStdout:
    """A stdout whose every write fails with ``code`` (a full disk, a closed pipe)."""

    def __init__(self, code):
        self.code = code

    def write(self, text):
        raise OSError(self.code, os.strerror(self.code))

    def flush(self):
        pass


# -- stdout that cannot be written ----------------------------------------------------------
@pytest.mark.parametrize("argv", [["scenarios"], ["fis", "check", GPS],
                                  ["fis", "surface", GPS, "--csv"]])
def test_a_full_disk_behind_stdout_is_one_line(capsys, monkeypatch, argv):
    monkeypatch.setattr(sys, "stdout", _FailingStdout(errno.ENOSPC))
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err
    assert code == 2 and _one_line(err) and "stdout" in err and "No space left" in err


@pytest.mark.parametrize("argv", [["--help"], ["--version"], ["run", "--help"]])
def test_help_to_a_full_disk_is_one_line(capsys, monkeypatch, argv):
    """argparse prints help and exits by itself; the guard still sees the failed write."""
    monkeypatch.setattr(sys, "stdout", _FailingStdout(errno.ENOSPC))
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2 and _one_line(err) and "No space left" in err


def test_help_to_a_working_stdout_still_exits_0(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0 and "usage: fuzzynav" in capsys.readouterr().out


def test_a_closed_pipe_behind_stdout_ends_quietly(capsys, monkeypatch):
    monkeypatch.setattr(sys, "stdout", _FailingStdout(errno.EPIPE))
    code = main(["fis", "surface", str(GPS), "--csv", "--grid", "200"])
    assert code == EXIT_BROKEN_PIPE and capsys.readouterr().err == ""


_MAIN = "import sys; from fuzzynav.cli import main; sys.exit(main())"


def _cli(args, stdout):
    return subprocess.run([sys.executable, "-c", _MAIN, *map(str, args)],
                          stdout=stdout, stderr=subprocess.PIPE, text=True, timeout=120)


def test_a_closed_pipe_as_a_real_process():
    """Like ``fuzzynav fis surface --csv | head -1``, with the reader gone from the start."""
    r, w = os.pipe()
    os.close(r)  # every write to w now fails with EPIPE
    try:
        proc = _cli(["fis", "surface", GPS, "--csv", "--grid", "200"], w)
    finally:
        os.close(w)
    # nothing but, on a cold kernel cache, the one line saying it compiles
    said = [ln for ln in proc.stderr.splitlines()
            if ln not in (compile_notice.COLD_TEXT, compile_notice.PARTIAL_TEXT)]
    assert proc.returncode == EXIT_BROKEN_PIPE and said == []


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
@pytest.mark.parametrize("argv", [["scenarios"], ["--help"]])
def test_dev_full_as_a_real_process(argv):
    """The output is small enough to sit in the buffer until exit (``--help``: until
    argparse exits): still one line."""
    with open("/dev/full", "w") as full:
        proc = _cli(argv, full)
    assert proc.returncode == 2 and _one_line(proc.stderr), proc.stderr
    assert "No space left on device" in proc.stderr


# -- long values are quoted briefly ---------------------------------------------------------
def test_a_long_unknown_binding_key(capsys, tmp_path):
    doc = json.loads(GPS.read_text(encoding="utf-8"))
    doc["binding"]["k" * LONG] = 1
    path = tmp_path / "long_key.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    code, _, err = _run(capsys, "fis", "check", path)
    assert code == 2 and _one_line(err) and "unknown key 'kkk" in err
    # the binding quotes the key briefly itself: the CLI's cap is not what saves it
    assert len(err) < MAX_MESSAGE and "str of 200000 characters" in err


def test_a_long_study_name(capsys, tmp_path):
    text = QUICKSTART.read_text(encoding="utf-8").replace('name = "quickstart"',
                                                          f'name = "{"n" * LONG}!"', 1)
    path = tmp_path / "long_name.toml"
    path.write_text(text, encoding="utf-8")
    code, _, err = _run(capsys, "study", "run", path, "--cache", tmp_path, "--no-summary")
    assert code == 2 and _one_line(err) and "must be letters, digits" in err
    assert len(err) < MAX_MESSAGE and "str of 200001 characters" in err


@pytest.mark.parametrize("option", ["--filter", "--data"])
def test_a_long_command_line_value_is_bounded(capsys, tmp_path, option):
    """An unknown name is quoted briefly by its error; a long path is cut by the error's
    base class (the same cap a library caller gets)."""
    value = "x" * LONG if option == "--filter" else "rtklib:" + "d" * LONG
    argv = ["run", TINY, option, value] if option == "--filter" else ["run", option, value]
    code, _, err = _run(capsys, *argv, "--cache", tmp_path)
    assert code == 2 and _one_line(err)
    mark = "str of 200000 characters" if option == "--filter" else "characters cut)"
    assert len(err) < MAX_MESSAGE + 100 and mark in err


def test_a_message_with_newlines_stays_on_one_line(capsys, monkeypatch):
    from fuzzynav.errors import FuzzynavError

    def boom(args):
        raise FuzzynavError("first\nsecond\r\nthird")

    monkeypatch.setattr("fuzzynav.cli.nav._cmd_scenarios", boom)
    code, _, err = _run(capsys, "scenarios")
    assert code == 2 and _one_line(err) and "first second third" in err


# -- counts and seeds -----------------------------------------------------------------------
@pytest.mark.parametrize("argv, fragment", [
    (["run", TINY, "--mc", 2_000_000_000], f"--mc must be <= {MAX_MC}"),
    (["compare", TINY, "--mc", MAX_MC + 1], f"--mc must be <= {MAX_MC}"),
    (["run", "--data", "rtklib:/nonexistent", "--mc", 10**9], f"--mc must be <= {MAX_MC}"),
    (["run", TINY, "--seed", 2**63 - 1, "--mc", 2], "the last seed must be <= "),
])
def test_too_many_runs_or_too_large_a_seed(capsys, tmp_path, argv, fragment):
    code, out, err = _run(capsys, *argv, "--cache", tmp_path)
    assert code == 2 and _one_line(err) and fragment in err and out == ""
    assert not any(tmp_path.iterdir())


# -- rule files a filter would ignore, and things that are not rule files --------------------
@pytest.mark.parametrize("argv, fragment", [
    (["run", TINY, "--filter", "ekf", "--rules", GPS], "--rules: filter 'ekf' takes no rule"),
    (["run", TINY, "--filter", "ekf", "--rules", "x.json"], "--rules: filter 'ekf'"),
    (["run", TINY, "--filter", f"ekf@{GPS}"], "--filter ekf@"),
    (["compare", TINY, "--filters", "ekf@nonexist.json,fakf"],
     "--filters ekf@nonexist.json: filter 'ekf' takes no rule files"),
    (["compare", TINY, "--filters", "ekf,sage-husa", "--rules", GPS],
     "--rules: filters 'ekf', 'sage-husa' take no rule files"),
    (["compare", TINY, "--filters", "ekf,fakf@nonexist.json"],
     "nonexist.json: rule file not found"),
    (["run", TINY, "--filter", "fakf", "--rules", "nonexist.json"],
     "nonexist.json: rule file not found"),
    (["run", TINY, "--filter", "fakf", "--rules", ROOT / "rules"],
     "is a directory, not a rule file"),
    (["run", TINY, "--filter", "fakf", "--rules", os.devnull], "not a regular file"),
])
def test_rule_files_no_filter_reads_are_refused(capsys, tmp_path, argv, fragment):
    code, out, err = _run(capsys, *argv, "--cache", tmp_path)
    assert code == 2 and _one_line(err) and fragment in err and out == ""
    assert not any(tmp_path.iterdir())  # refused before anything was simulated


def test_non_finite_at_values_are_refused(capsys):
    for value in ("nan", "inf", "-inf"):
        with pytest.raises(SystemExit) as exc:
            main(["fis", "surface", str(GPS), "--at", f"dom_pos={value}"])
        assert exc.value.code == 2
        err = capsys.readouterr().err
        assert "must be a finite number" in err and "Traceback" not in err
