"""Command-line values, unwritable outputs and diverged runs: one line, the right exit code.

Exit codes: 2 for bad input (a value, a file, an output place), 3 for a filter run that
diverged (non-finite metrics).  Full disks and read-only places are simulated by making
the write itself raise ``OSError`` (the tests run as root, which ``chmod`` does not stop).
"""
import errno
import json
import os
import sys
from dataclasses import replace
from pathlib import Path

import matplotlib.figure
import numpy as np
import pytest

import fuzzynav.experiment
import fuzzynav.runpath
import fuzzynav.sim.sensor_log
from fuzzynav.cli import main

ROOT = Path(__file__).resolve().parents[2]
TINY = ROOT / "tests" / "tuning" / "data" / "tiny.toml"
QUICKSTART = ROOT / "studies" / "quickstart.toml"


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _one_line(err):
    return err.count("\n") == 1 and err.startswith("fuzzynav: error: ") and "Traceback" not in err


@pytest.mark.parametrize("argv, fragment", [
    (["run", TINY, "--seed", "-1"], "--seed must be >= 0"),
    (["compare", TINY, "--filters", "ekf,,fakf"], "an empty filter name"),
    (["compare", TINY, "--filters", "ekf,fakf,"], "an empty filter name"),
    (["run", TINY, "--mc", "-2"], "--mc must be >= 1"),
    (["compare", TINY, "--filters", "ekf,fakf", "--mc", "0"], "--mc must be >= 1"),
    (["run", TINY, "--t-start", "-1"], "--t-start must be a finite number"),
    (["run", TINY, "--t-start", "nan"], "--t-start must be a finite number"),
    (["run", TINY, "--t-start", "60"], "at or after the end of the run (60 s)"),
    (["study", "run", QUICKSTART, "--trials", "0"], "--trials must be >= 1"),
    (["study", "run", QUICKSTART, "--trials", "-5"], "--trials must be >= 1"),
    (["study", "run", QUICKSTART, "--workers", "0"], "--workers must be >= 1"),
    (["study", "run", QUICKSTART, "--workers", "100000"], "--workers must be <= "),
])
def test_meaningless_option_values_are_refused_before_any_work(capsys, tmp_path, argv,
                                                               fragment):
    code, out, err = _run(capsys, *argv, "--cache", tmp_path)
    assert code == 2 and _one_line(err) and fragment in err
    assert not any(tmp_path.iterdir()) and out == ""
    assert not list(QUICKSTART.parent.glob("quickstart.journal*"))


def test_a_directory_where_a_file_is_expected(capsys, tmp_path):
    code, _, err = _run(capsys, "run", tmp_path, "--cache", tmp_path)
    assert code == 2 and _one_line(err) and "is a directory, not a scenario file" in err
    code, _, err = _run(capsys, "study", "run", tmp_path)
    assert code == 2 and _one_line(err) and "is a directory, not a study file" in err
    (tmp_path / "rules.json").mkdir()
    study = tmp_path / "s.toml"
    text = QUICKSTART.read_text().replace('"../rules/paper002_ror_gnss.json"', '"rules.json"')
    study.write_text(text)
    code, _, err = _run(capsys, "study", "run", study)
    assert code == 2 and _one_line(err) and "controllers[0].template" in err
    assert "is a directory" in err


def test_a_file_name_too_long_for_the_system(capsys, tmp_path):
    code, _, err = _run(capsys, "run", tmp_path / ("x" * 300 + ".toml"), "--cache", tmp_path)
    assert code == 2 and _one_line(err) and "File name too long" in err


def test_a_long_scenario_name_gives_a_short_cache_file_name(tmp_path):
    from fuzzynav.sim.sensor_log import cache_path
    from fuzzynav.sim.scenario import load_scenario

    scn = load_scenario(TINY)
    long_a = replace(scn, name="a" * 100)
    long_b = replace(scn, name="a" * 99 + "b")
    pa, pb = cache_path(tmp_path, long_a, 0), cache_path(tmp_path, long_b, 0)
    assert len(pa.name) < 100 and pa != pb  # cut names keep a hash of the whole
    assert cache_path(tmp_path, replace(scn, name="../../x"), 0).parent == tmp_path


# -- outputs -------------------------------------------------------------------------------
def _raise(code):
    def fail(*args, **kwargs):
        raise OSError(code, os.strerror(code))
    return fail


@pytest.mark.parametrize("target, code", [("np.savez", errno.ENOSPC),
                                          ("tempfile.mkstemp", errno.EROFS)])
def test_cache_on_a_full_or_read_only_disk(capsys, tmp_path, monkeypatch, target, code):
    from fuzzynav.sim.sensor_log import cache_path
    from fuzzynav.sim.scenario import load_scenario

    old = cache_path(tmp_path, load_scenario(TINY), 0)
    old.write_bytes(b"an old damaged cache file")  # not trusted, so it is rewritten
    module, name = target.split(".")
    import tempfile

    # the cache is written by fuzzynav.fileio.write_npz: numpy's and tempfile's functions
    monkeypatch.setattr({"np": np, "tempfile": tempfile}[module], name, _raise(code))
    code_, _, err = _run(capsys, "run", TINY, "--cache", tmp_path)
    assert code_ == 2 and _one_line(err)
    assert str(old) in err and "simulation cache" in err and os.strerror(code) in err
    assert old.read_bytes() == b"an old damaged cache file"
    assert sorted(p.name for p in tmp_path.iterdir()) == [old.name]  # no temporary file


def test_cache_directory_that_is_a_file(capsys, tmp_path):
    blocker = tmp_path / "cache"
    blocker.write_text("not a directory")
    code, _, err = _run(capsys, "run", TINY, "--cache", blocker)
    assert code == 2 and _one_line(err) and "cannot write the simulation cache" in err


def test_plot_on_a_full_disk_keeps_the_old_figure(capsys, tmp_path, monkeypatch, sim_cache):
    out = tmp_path / "plots"
    out.mkdir()
    old = out / "tiny_errors.png"
    old.write_bytes(b"old figure")
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", _raise(errno.ENOSPC))
    code, _, err = _run(capsys, "run", TINY, "--cache", sim_cache, "--plot", out)
    assert code == 2 and _one_line(err) and "No space left on device" in err
    assert str(old) in err and old.read_bytes() == b"old figure"
    assert sorted(p.name for p in out.iterdir()) == ["tiny_errors.png"]


def test_plot_directory_that_is_a_file(capsys, tmp_path, sim_cache):
    blocker = tmp_path / "plots"
    blocker.write_text("a file")
    code, _, err = _run(capsys, "run", TINY, "--cache", sim_cache, "--plot", blocker)
    assert code == 2 and _one_line(err) and "cannot write the figure" in err
    assert blocker.read_text() == "a file"


class _FullStdout:
    def write(self, text):
        raise OSError(errno.ENOSPC, "No space left on device")

    def flush(self):
        pass


def test_json_to_a_full_disk(capsys, monkeypatch, sim_cache):
    capsys.readouterr()
    monkeypatch.setattr(sys, "stdout", _FullStdout())
    code = main(["run", str(TINY), "--json", "--cache", str(sim_cache)])
    err = capsys.readouterr().err
    assert code == 2 and _one_line(err) and "stdout" in err and "No space left" in err


# -- diverged runs ---------------------------------------------------------------------------
def _diverging(run_filter):
    """``run_filter`` whose solution turns to NaN half-way (a filter blowing up)."""
    def run(*args, **kwargs):
        res = run_filter(*args, **kwargs)
        lla = res.lla.copy()
        lla[lla.shape[0] // 2:] = np.nan
        return replace(res, lla=lla)
    return run


@pytest.mark.parametrize("json_flag", [[], ["--json"]])
def test_a_diverged_run_exits_3_without_a_table(capsys, monkeypatch, sim_cache, json_flag):
    monkeypatch.setattr(fuzzynav.runpath, "run_filter",
                        _diverging(fuzzynav.runpath.run_filter))
    code, out, err = _run(capsys, "run", TINY, "--filter", "ekf", "--seed", "4",
                          "--cache", sim_cache, *json_flag)
    assert code == 3 and _one_line(err) and out == ""
    assert "filter ekf diverged on scenario tiny seed 4" in err and "= nan" in err


def test_the_sane_run_still_works_and_prints_finite_json(capsys, sim_cache):
    code, out, err = _run(capsys, "run", TINY, "--filter", "ekf", "--json", "--cache", sim_cache)
    assert code == 0, err
    doc = json.loads(out)
    assert np.isfinite(doc["filters"]["ekf"]["rms_pos_m"]["mean"])


@pytest.mark.parametrize("command", [["run", TINY], ["compare", TINY, "--filters", "ekf,fakf"]])
@pytest.mark.parametrize("where", ["/proc/fuzzynav-plots", "a-file", "/sys/x"])
def test_a_plot_directory_that_cannot_be_written_is_refused_before_the_run(
        capsys, tmp_path, monkeypatch, command, where):
    """It was found only after the whole run, its table already printed."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a-file").write_text("kept")
    ran = []
    monkeypatch.setattr(fuzzynav.experiment, "monte_carlo",
                        lambda *a, **k: ran.append(1) or pytest.fail("ran"))
    code, out, err = _run(capsys, *command, "--mc", "1", "--plot", where, "--cache", "cache")
    assert code == 2 and _one_line(err) and "figure directory (--plot)" in err, err
    assert out == "" and not ran and (tmp_path / "a-file").read_text() == "kept"


def test_an_output_dir_that_is_a_file_is_refused_before_the_run(capsys, tmp_path):
    target = tmp_path / "chunks"
    target.write_text("kept")
    code, out, err = _run(capsys, "run", TINY, "--output-rate", "1", "--output-dir", target,
                          "--cache", tmp_path / "cache")
    assert code == 2 and _one_line(err) and "it is a file, not a directory" in err, err
    assert out == "" and target.read_text() == "kept"
