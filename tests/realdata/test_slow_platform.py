"""``--data rtklib:DIR?options``: a walking-speed recording, refused by the car defaults,
starts and navigates with a lower speed threshold or the heading from the GNSS track.

The walk (``tests.realdata.rtklib_files.WALK_SEGMENTS``: 20 s rest, 1.4 m/s, two 90-degree turns
and a stop) is written by the simulator in the RTKLIB formats with an identity mounting, so
the body's forward axis is known and its true heading at the start is 30 degrees.  Bounds:

* with GNSS the horizontal RMS must beat the noisy fixes it is fed (2 m per axis: 2.83 m);
* the heading: from the course of exact velocities, within 1 degree (only the gyro
  propagation of an ideal IMU stands between them); from 15-m chords of fixes with 2 m
  noise per axis, about 0.19 rad per chord, averaged over the ~60 chords of a 30-s window
  that overlap in pairs: within 5 degrees;
* after a 20-s outage an ideal IMU drifts by what the filter had not settled: a 5-degree
  heading error at 1.4 m/s (2.4 m) plus a 0.1 m/s velocity error (2 m): < 10 m.
"""
import contextlib
import io
import json

import pytest

from fuzzynav.cli import main
from tests.realdata.rtklib_files import DRIVE_HEADING_DEG, WALK_SEGMENTS, write_drive

RAW_FIXES_H_RMS_M = 2.0 * 2.0**0.5
PROTOCOL = ("--first-outage", "40", "--outage-duration", "20", "--json")


def _run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(argv))
    return code, out.getvalue(), err.getvalue()


def write_walk(d, forward: float = 1.0):
    """The simulated walk in ``d``, its IMU's x and y axes times ``forward`` (-1: reversed)."""
    write_drive(d, segments=WALK_SEGMENTS)
    (d / "mounting.toml").write_text(f"imu_to_body = [[{forward}, 0.0, 0.0], [0.0, {forward}, "
                                     "0.0], [0.0, 0.0, 1.0]]\n")
    return d


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    return write_walk(tmp_path_factory.mktemp("walk"))


def test_car_defaults_refuse_a_walk_and_name_the_option(walk):
    code, out, err = _run("run", "--data", f"rtklib:{walk}", *PROTOCOL)
    assert code == 2 and out == ""
    assert "2 m/s" in err and "min_speed" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("query, method, tol_deg", [("min_speed=0.5", "course", 1.0),
                                                    ("heading=track&baseline=15", "track", 5.0)])
def test_a_walk_starts_and_navigates(walk, query, method, tol_deg):
    code, out, err = _run("run", "--data", f"rtklib:{walk}?{query}", *PROTOCOL)
    assert code == 0, err
    doc = json.loads(out)
    start = doc["start"]
    assert start["heading_method"] == method
    assert abs(start["time_s"] - 20.0) <= 0.5          # the walk starts at 20 s
    assert abs((start["heading_deg"] - DRIVE_HEADING_DEG + 180.0) % 360.0 - 180.0) < tol_deg
    assert doc["status"] == {"GNSS throughout": ["ok"], "with outages": ["ok"]}
    assert doc["feeds"]["GNSS throughout"]["rms_pos_h_m"]["mean"] < RAW_FIXES_H_RMS_M
    done = [o for o in doc["outages"] if o["complete"]]
    assert len(done) == 1 and done[0]["drift_h_m"]["with outages"][0] < 10.0


@pytest.mark.parametrize("query, named", [("speed=1", "speed"), ("min_speed=abc", "min_speed"),
                                          ("lever_arm=1,2", "lever_arm"), ("window=-3", "window"),
                                          ("heading=north", "heading"), ("min_speed", "min_speed")])
def test_bad_options_name_the_option(walk, query, named):
    code, out, err = _run("run", "--data", f"rtklib:{walk}?{query}", *PROTOCOL)
    assert code == 2 and out == ""
    assert f"option {named}:" in err and len(err.strip().splitlines()) == 1


def test_spelled_out_defaults_give_the_drive_its_previous_start(rtklib_drive):
    """The car defaults, written as options, change nothing on the real drive; its start is
    the documented one (docs/validation.md: rest to 20.3 s, course heading 354.8 deg)."""
    short = ("--span", "0,130", "--first-outage", "40", "--mounting", "rtklib-drive", "--json")
    docs = []
    for query in ("", "?min_speed=2&rest_speed=0.2&min_rest=2&window=30&heading=auto"):
        code, out, err = _run("run", "--data", f"rtklib:{rtklib_drive}{query}", *short)
        assert code == 0, err
        docs.append(json.loads(out))
    plain, spelled = docs
    assert abs(plain["start"]["time_s"] - 20.3) < 0.6
    assert abs(plain["start"]["heading_deg"] - 354.8) < 0.5
    for feed, metrics in plain["feeds"].items():
        for name in ("rms_pos_h_m", "rms_vel_mps"):
            assert spelled["feeds"][feed][name]["mean"] == pytest.approx(
                metrics[name]["mean"], rel=1e-9)
