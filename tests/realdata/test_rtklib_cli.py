"""``fuzzynav run --data rtklib:DIR`` on a short stretch of the real car recording.

The first 130 s of the rtklib-drive: the opening rest (to 20.3 s), then residential streets;
one 60-s outage 40 s after the filter starts.  Skips when the recording is absent.  The bounds
are physical, not this code's own output:

* with GNSS the horizontal RMS must beat the noisy fixes it is fed (2 m per axis: 2.83 m
  horizontal) and cannot beat averaging them (2 m / sqrt(4 Hz x 100 s) = 0.1 m per axis), so
  it lies between 0.05 m and 2.83 m;
* after 60 s without GNSS a MEMS IMU has drifted more than a navigation-grade one (0.65 m
  RMS in the KF-GINS evaluation): > 1 m; and less than 1 km — a constant acceleration error
  of 0.55 m/s^2 (a 3-degree tilt or 56 mg) for the whole minute, beyond a GNSS-calibrated
  consumer part; a gravity or frame mistake drifts kilometres.
"""
import contextlib
import io
import json

import pytest

from fuzzynav.cli import main

SHORT = ("--span", "0,130", "--first-outage", "40", "--mounting", "rtklib-drive")
RAW_FIXES_H_RMS_M = 2.0 * 2.0**0.5


def _run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(argv))
    return code, out.getvalue(), err.getvalue()


def _json(drive, filter_name, *extra):
    code, out, err = _run("run", "--data", f"rtklib:{drive}", "--filter", filter_name,
                          *SHORT, "--json", *extra)
    assert code == 0, err
    return json.loads(out)


@pytest.fixture(scope="module")
def ekf(rtklib_drive):
    return _json(rtklib_drive, "ekf")


def _mean(doc, feed, key):
    return doc["feeds"][feed][key]["mean"]


@pytest.mark.parametrize("name", ["ekf", "sage-husa", "vb", "fakf"])
def test_short_stretch_is_physically_sensible(rtklib_drive, ekf, name):
    doc = ekf if name == "ekf" else _json(rtklib_drive, name)
    assert doc["status"] == {"GNSS throughout": ["ok"], "with outages": ["ok"]}
    # the rest ends at 20.3 s (docs/data.md §5); one complete outage 40 s later
    assert abs(doc["start"]["time_s"] - 20.3) < 0.6
    complete = [o for o in doc["outages"] if o["complete"]]
    assert len(complete) == 1
    assert complete[0]["start_s"] == pytest.approx(doc["start"]["time_s"] + 40.0)
    assert 0.05 < _mean(doc, "GNSS throughout", "rms_pos_h_m") < RAW_FIXES_H_RMS_M
    assert _mean(doc, "with outages", "rms_pos_h_aided_m") < RAW_FIXES_H_RMS_M
    drift = complete[0]["drift_h_m"]["with outages"][0]
    aided = complete[0]["drift_h_m"]["GNSS throughout"][0]
    assert drift > 1.0 and drift < 1000.0
    # at the same instant, with GNSS, the error is of the aided size
    assert aided < RAW_FIXES_H_RMS_M and drift > 10.0 * aided


def test_seeds_change_the_noise_not_the_protocol(rtklib_drive, ekf):
    two = _json(rtklib_drive, "ekf", "--seed", "5", "--mc", "2")
    assert two["seeds"] == [5, 6]
    vals = two["feeds"]["GNSS throughout"]["rms_pos_h_m"]["values"]
    assert len(vals) == 2 and vals[0] != vals[1]
    assert two["outages"][0]["start_s"] == ekf["outages"][0]["start_s"]


def test_table_and_figures(rtklib_drive, tmp_path):
    code, out, err = _run("run", "--data", f"rtklib:{rtklib_drive}", *SHORT,
                          "--plot", str(tmp_path))
    assert code == 0, err
    assert "horizontal position RMS (m)" in out and "error at end of outage 1" in out
    for suffix in ("horizontal_error", "trajectory"):
        png = tmp_path / f"rtklib-drive_ekf_{suffix}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_json_with_figures_is_one_json_document(rtklib_drive, tmp_path):
    code, out, err = _run("run", "--data", f"rtklib:{rtklib_drive}", *SHORT, "--json",
                          "--plot", str(tmp_path))
    assert code == 0, err
    assert json.loads(out)["feeds"] and "wrote" not in out
    assert err.count(f"wrote {tmp_path}") == 2    # the notices of both figures, on stderr


def test_rule_files_bind_to_the_gnss_sensor(rtklib_drive):
    doc = _json(rtklib_drive, "fakf", "--rules", "paper002_ror_gnss.json")
    assert doc["status"]["with outages"] == ["ok"]
    code, _, err = _run("run", "--data", f"rtklib:{rtklib_drive}", *SHORT, "--filter", "fakf",
                        "--rules", "paper000_attitude.json")
    assert code == 2 and "heading" in err and "sensors: gnss" in err


def test_a_stretch_without_motion_names_the_recording(rtklib_drive):
    # the car drives off at 35.5 s: 25 s of data give no heading
    code, _, err = _run("run", "--data", f"rtklib:{rtklib_drive}", "--span", "0,25")
    assert code == 2 and str(rtklib_drive) in err and "initialisation" in err


def test_vehicle_constraints_bound_the_outage_drift(rtklib_drive, ekf):
    """Zero lateral/vertical body velocity removes the tilt-driven growth: the drift after the
    60-s outage must fall well below the unconstrained one and stay within tens of metres."""
    doc = _json(rtklib_drive, "ekf", "--nhc", "0.3")
    free = [o for o in ekf["outages"] if o["complete"]][0]["drift_h_m"]["with outages"][0]
    held = [o for o in doc["outages"] if o["complete"]][0]["drift_h_m"]["with outages"][0]
    assert held < 0.5 * free and held < 60.0  # 25 m vs 75 m here, 40 s after a cold start
    assert _mean(doc, "GNSS throughout", "rms_pos_h_m") < RAW_FIXES_H_RMS_M
