"""``--data`` and the recording options: one clear line and exit code 2 (no data needed)."""
import contextlib
import io

import pytest

from fuzzynav.cli import main


def _run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(argv))
    return code, out.getvalue(), err.getvalue()


def test_unknown_kind_lists_the_known_ones(tmp_path):
    code, _, err = _run("run", "--data", f"akit9:{tmp_path}")
    assert code == 2 and "unknown data source kind 'akit9'" in err and "rtklib" in err


def test_missing_directory_is_named(tmp_path):
    missing = tmp_path / "nowhere"
    code, _, err = _run("run", "--data", f"rtklib:{missing}")
    assert code == 2 and str(missing) in err and "not found" in err


def test_spec_without_a_directory(tmp_path):
    for spec in ("rtklib", "rtklib:", f":{tmp_path}"):
        code, _, err = _run("run", "--data", spec)
        assert code == 2 and "KIND:DIR" in err


def test_missing_files_are_named(tmp_path):
    code, _, err = _run("run", "--data", f"rtklib:{tmp_path}")
    assert code == 2 and "imu_*.csv" in err and str(tmp_path) in err
    (tmp_path / "imu_7.csv").write_text("")
    code, _, err = _run("run", "--data", f"rtklib:{tmp_path}")
    assert code == 2 and "imu_7.csv.tag" in err


@pytest.mark.parametrize("argv, words", [
    (("--span", "10"), "--span"),
    (("--span", "20,10"), "--span"),
    (("--mounting", "no-such-mounting"), "rtklib-drive"),
    (("--noise", "-1"), "--noise must lie in [0, 1000], got -1.0"),
    (("--outage-period", "30"), "--outage-period (30.0) must exceed --outage-duration (60.0)"),
])
def test_bad_options(tmp_path, argv, words):
    code, _, err = _run("run", "--data", f"rtklib:{tmp_path}", *argv)
    assert code == 2 and words in err and err.count("\n") == 1


def test_bad_velocity_mode_is_an_argparse_error(tmp_path):
    with pytest.raises(SystemExit) as exc, contextlib.redirect_stderr(io.StringIO()):
        main(["run", "--data", f"rtklib:{tmp_path}", "--gnss-velocity", "late"])
    assert exc.value.code == 2


def test_scenarios_lists_the_recording_kinds():
    code, out, _ = _run("scenarios")
    assert code == 0 and "rtklib" in out and "--data KIND:DIR" in out


def test_recording_options_are_refused_for_a_scenario():
    code, _, err = _run("run", "paper000", "--noise", "3", "--span", "0,10")
    assert code == 2 and "--noise, --span: do not apply to simulated scenarios" in err
    assert "the recording options need --data" in err


@pytest.mark.parametrize("extra, flags", [
    (["--noise", "5"], "--noise: does not apply"),
    (["--nhc", "0.1", "--outage-period", "30"], "--outage-period, --nhc: do not apply"),
    (["--mc", "3"], "--mc: does not apply"),
    (["--t-start", "100"], "--t-start: does not apply"),
    (["--outage-duration", "0", "--first-outage", "10", "--vel-noise", "0.1"],
     "do not apply"),
    (["--span", "0,10", "--imu-delay", "0.01"], "--imu-delay, --span: do not apply"),
    (["--mounting", "rtklib-drive"], "--mounting: does not apply"),
])
def test_options_an_akit_run_would_ignore_are_refused_by_name(tmp_path, extra, flags):
    """They used to give output identical to a plain A-KIT run; refused before any file is
    read (the directory need not hold a recording)."""
    (tmp_path / "akit").mkdir()
    code, out, err = _run("run", "--data", f"akit:{tmp_path / 'akit'}:1", "--filter", "ekf",
                          *extra)
    assert code == 2 and out == "" and flags in err and "akit recordings" in err, err


def test_t_start_beyond_a_recording_is_refused_not_diverged(rtklib_drive, tmp_path):
    code, out, err = _run("run", "--data", f"rtklib:{rtklib_drive}", "--filter", "ekf",
                          "--t-start", "1e6", "--cache", str(tmp_path))
    assert code == 2 and out == "" and "--t-start 1e+06 s: the recording runs" in err, err
    assert "diverged" not in err


@pytest.mark.parametrize("as_json", [False, True])
def test_an_akit_run_with_non_finite_metrics_prints_nothing_and_exits_3(monkeypatch, as_json):
    """A-KIT runs skipped the finite-metrics check: a table with only "distance travelled"
    (JSON ``rms_pos_h_m: null``) and exit 0."""
    import math

    
    import fuzzynav.realdata.akit as akit
    import fuzzynav.realdata.cli as rcli
    from fuzzynav.runpath import RunOutcome

    class _Rec:
        trajectory = 3
        imu = type("I", (), {"span_s": (0.0, 400.0), "rate_hz": 200.0})()

    monkeypatch.setattr(rcli, "load_recording", lambda spec, args, streamed=False: [_Rec()])
    monkeypatch.setattr(rcli, "refuse_unused_options", lambda spec, args: None)
    metrics = {"rms_pos_h_m": math.nan, "rms_vel_h_mps": 0.1, "distance_m": 600.0,
               "completed": 1.0}
    out = RunOutcome("ekf", "akit trajectory 3", 0, None, metrics,
                                      ("rms_pos_h_m",))
    monkeypatch.setattr(akit, "run_outcomes", lambda recs, name, options: [out])
    code, out, err = _run("run", "--data", "akit:x:3", "--filter", "ekf",
                          *(["--json"] if as_json else []))
    assert code == 3 and out == "" and "diverged" in err and "rms_pos_h_m" in err, err


@pytest.mark.parametrize("extra, phrase", [
    (["--noise", "inf"], "--noise must lie in [0, 1000], got inf"),
    (["--noise", "1e300"], "--noise must lie in [0, 1000]"),
    (["--velocity-lag", "nan"], "--velocity-lag must lie in [-10, 10], got nan"),
    (["--vel-noise", "inf"], "--vel-noise must lie in [0, 100]"),
    (["--first-outage", "-5"], "--first-outage must lie in"),
])
def test_a_bad_protocol_value_is_refused_naming_the_option(tmp_path, extra, phrase):
    """Checked before the recording is read (the directory need hold nothing); the message
    names the option given, not the settings field behind it."""
    code, out, err = _run("run", "--data", f"rtklib:{tmp_path}", "--filter", "ekf", *extra)
    assert code == 2 and out == "" and phrase in err, err
    assert "Traceback" not in err and "_m " not in err


@pytest.mark.parametrize("value", ["nan", "inf", "-20"])
def test_an_imu_delay_that_is_not_a_delay_is_refused_before_reading(tmp_path, value):
    # nan and inf raised ValueError / OverflowError deep in the loader (exit 1, a traceback)
    code, out, err = _run("run", "--data", f"rtklib:{tmp_path}", "--filter", "ekf",
                          "--imu-delay", value)
    assert code == 2 and out == "" and "--imu-delay" in err and "Traceback" not in err, err


@pytest.mark.parametrize("argv, phrase", [
    (["--data", ""], "--data is empty"),
    (["--data", "  "], "--data is empty"),
    (["--data", "nosuchdataset"], "unknown dataset 'nosuchdataset'; known: akit, rtklib-drive"),
    (["--data", "rtklib:DIR", "--span", "nan,5"], "--span: START and END must be finite"),
])
def test_an_empty_or_misspelt_data_spec_says_so(argv, phrase, tmp_path):
    argv = [a.replace("DIR", str(tmp_path)) for a in argv]
    code, out, err = _run("run", *argv, "--filter", "ekf")
    assert code == 2 and out == "" and phrase in err and err.count("\n") == 1, err
