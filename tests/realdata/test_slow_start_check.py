"""The start's second and third headings: an IMU whose forward axis points backward (the
walk of ``test_slow_platform`` read with a mounting that reverses body x and y: a phone
carried back to front) starts with ``heading=track`` and ``min_speed=0.5`` turned by 180 deg
to the specific-force heading (the true 210 deg), and says so; an IMU turned by 90 deg, which
no direction of travel explains, is refused with both headings; the unreversed walk passes
(``test_slow_platform``); an explicit ``heading=DEG`` is not second-guessed.

Bounds: the turned heading is the course or track heading plus 180 deg, so it keeps their
bounds of ``test_slow_platform`` (1 deg for the course, 5 deg for 15-m chords).
"""
import json
import math

import pytest

from fuzzynav.realdata.start_check import check_headings
from fuzzynav.errors import InputFileError
from fuzzynav.realdata.start_check import resolve_direction
from tests.realdata.rtklib_files import DRIVE_HEADING_DEG, WALK_SEGMENTS, write_drive
from tests.realdata.test_slow_platform import PROTOCOL, RAW_FIXES_H_RMS_M, _run, write_walk


@pytest.fixture(scope="module")
def reversed_walk(tmp_path_factory):
    return write_walk(tmp_path_factory.mktemp("reversed_walk"), forward=-1.0)


@pytest.fixture(scope="module")
def turned_walk(tmp_path_factory):
    d = tmp_path_factory.mktemp("turned_walk")
    write_drive(d, segments=WALK_SEGMENTS)
    (d / "mounting.toml").write_text("imu_to_body = [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], "
                                     "[0.0, 0.0, 1.0]]\n")
    return d


@pytest.mark.parametrize("query, method, tol_deg", [("heading=track&baseline=15", "track", 5.0),
                                                    ("min_speed=0.5", "course", 1.0)])
def test_a_reversed_imu_is_turned_by_180_and_navigates(reversed_walk, query, method, tol_deg):
    code, out, err = _run("run", "--data", f"rtklib:{reversed_walk}?{query}", *PROTOCOL)
    assert code == 0, err
    doc = json.loads(out)
    start = doc["start"]
    assert start["heading_method"] == method
    assert start["heading_check"].startswith("turned 180 deg")
    true_deg = DRIVE_HEADING_DEG + 180.0
    assert abs((start["heading_deg"] - true_deg + 180.0) % 360.0 - 180.0) < tol_deg
    assert "turned 180 deg" in err and len(err.strip().splitlines()) == 1
    assert doc["feeds"]["GNSS throughout"]["rms_pos_h_m"]["mean"] < RAW_FIXES_H_RMS_M


@pytest.mark.parametrize("query", ["heading=track&baseline=15", "min_speed=0.5"])
def test_an_imu_turned_by_90_is_refused_with_both_headings(turned_walk, query):
    code, out, err = _run("run", "--data", f"rtklib:{turned_walk}?{query}", *PROTOCOL)
    assert code == 2 and out == "", err
    line = err.strip()
    assert len(line.splitlines()) == 1
    assert "disagree" in line and "specific-force" in line and "heading=DEG" in line


def test_the_unreversed_walk_says_its_heading_agrees(tmp_path):
    code, out, err = _run("run", "--data", f"rtklib:{write_walk(tmp_path)}?min_speed=0.5",
                          *PROTOCOL)
    assert code == 0, err
    check = json.loads(out)["start"]["heading_check"]
    assert check.startswith("agrees with specific-force") and "agrees with track" in check


def test_resolve_direction():
    two, pi = math.radians(2), math.pi
    assert resolve_direction(("track", 0.1, two), ("specific-force", 0.15, two))[0] == 0.1
    h, why = resolve_direction(("track", 0.1, two), ("specific-force", 0.1 + pi, two))
    assert h == pytest.approx(0.1 + pi) and why.startswith("turned")
    h, why = resolve_direction(("track", 0.1, two), ("specific-force", 2.0, math.radians(40)))
    assert h == 0.1 and why.startswith("direction not checked")
    with pytest.raises(InputFileError, match="disagree by 90"):
        resolve_direction(("track", 0.0, two), ("specific-force", pi / 2, two))


def test_check_headings_threshold():
    check_headings(("track", 0.0, math.radians(2)), ("specific-force", math.radians(15), 0.0))
    with pytest.raises(InputFileError, match="disagree"):
        check_headings(("track", 0.0, math.radians(2)), ("specific-force", math.pi, 0.0))
