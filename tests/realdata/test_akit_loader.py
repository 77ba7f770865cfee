"""The A-KIT loader on synthetic files with a known truth, damaged files, and the real data."""
from pathlib import Path

import numpy as np
import pytest

from fuzzynav.errors import DataMissingError, InputFileError
from fuzzynav.nav import attitude
from fuzzynav.realdata.loaders.akit_recording import (MAX_TRAJECTORY, body_velocity, load_trajectory,
                                       parse_trajectories, read_table, reference_on_imu_clock)
from tests.conftest import datasets_dir
from tests.realdata.akit_files import auv_trajectory, varied_auv_trajectory, write_akit

AKIT = datasets_dir() / "akit"


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    d = tmp_path_factory.mktemp("akit")
    tr = auv_trajectory()
    idx = write_akit(d, tr, n=1, lag=1)
    return d, tr, idx


def test_frames_and_lag_are_recovered(synthetic):
    d, tr, idx = synthetic
    rec = load_trajectory(d, 1)
    assert abs(rec.clock.offset_s - 1.0) < 0.005 and abs(rec.clock.rate - 1.0) < 1e-4
    # increments back in body RFU (trapezoid of the sampled rates: first order)
    np.testing.assert_allclose(rec.imu.dv_b[5000], tr.dv_b[5000], atol=2e-4)
    np.testing.assert_allclose(rec.imu.dtheta_b[5000], tr.dtheta_b[5000], atol=2e-6)
    # reference on the IMU clock, ENU, attitude RFU -> ENU
    k = np.searchsorted(tr.time_s, rec.reference.time_s[10:100] - 1e-9)
    np.testing.assert_allclose(rec.reference.vel_n[10:100], tr.vel_n[k], atol=0.03)
    np.testing.assert_allclose(rec.reference.lla[10:100, :2], tr.lla[k, :2], atol=1e-7)
    ang = [np.linalg.norm(attitude.dcm_to_rotvec(a @ b.T)) for a, b in
           zip(attitude.quat_to_dcm(rec.reference.q_bn[10:100]), attitude.quat_to_dcm(tr.q_bn[k]))]
    assert max(ang) < np.deg2rad(0.5)
    # DVL in body RFU: forward speed on y
    np.testing.assert_allclose(np.median(rec.dvl.z[:, 1]), 2.0, atol=0.05)
    assert abs(rec.reference_offset_b[1]) < 0.1  # the synthetic DVL is at the reference


@pytest.mark.parametrize("lag,rate", [(0.37, 1.0), (-0.435, 1.0), (-0.46, 1.0025)])
def test_clock_map_is_recovered(tmp_path, lag, rate):
    """Offsets either side of zero, between IMU samples, and a reference clock 0.25 % slow
    (the real files' stamps) are recovered from the gyros: 5 ms, 1e-4 in rate."""
    tr = auv_trajectory()
    write_akit(tmp_path, tr, n=1, lag=lag, rate=rate)
    rec = load_trajectory(tmp_path, 1)
    assert abs(rec.clock.offset_s - lag) < 0.005
    assert abs(rec.clock.rate - rate) < 1e-4
    # the loaded reference is the truth at the IMU times it carries
    k = np.searchsorted(tr.time_s, rec.reference.time_s[5:100] - 1e-9)
    ang = [np.linalg.norm(attitude.dcm_to_rotvec(a @ b.T)) for a, b in
           zip(attitude.quat_to_dcm(rec.reference.q_bn[5:100]), attitude.quat_to_dcm(tr.q_bn[k]))]
    assert max(ang) < np.deg2rad(0.2)  # 1-Hz epochs interpolated: 0.16 deg in the turns


def test_clock_map_round_trip_and_closed_form():
    """``label = rate * t_imu + offset_s``: a stamp maps back to the IMU time it was made
    at (a rate applied the wrong way round would be 0.6 s off after 120 s at 0.25 %)."""
    from fuzzynav.realdata.loaders.akit_timing import ClockMap

    clock = ClockMap(offset_s=-0.46, rate=1.0025, dvl_offset_s=0.3)
    t = np.array([0.0, 1.5, 60.0, 120.0])
    np.testing.assert_allclose(clock.to_label(t), 1.0025 * t - 0.46, rtol=0, atol=1e-12)
    np.testing.assert_allclose(clock.to_imu(clock.to_label(t)), t, rtol=0, atol=1e-12)
    # a DVL stamp carries the extra offset: label = rate t + offset + dvl_offset
    np.testing.assert_allclose(clock.to_imu(1.0025 * t - 0.46 + 0.3, 0.3), t, atol=1e-12)


def test_loaded_clock_maps_file_stamps_to_their_true_times(tmp_path):
    """On a synthetic recording whose reference clock runs 0.25 % fast of the IMU's, the
    measured map takes each GT file stamp to the truth time it holds, within the map's
    accuracy (5 ms offset, 1e-4 rate over 120 s)."""
    lag, rate = -0.46, 1.0025
    tr = auv_trajectory()
    idx = write_akit(tmp_path, tr, n=1, lag=lag, rate=rate)
    rec = load_trajectory(tmp_path, 1)
    stamps = tr.time_s[idx]  # the GT rows' stamps as written
    np.testing.assert_allclose(rec.clock.to_imu(stamps), (stamps - lag) / rate, atol=0.03)


def test_a_reference_that_never_lines_up_with_the_gyros_is_refused(tmp_path):
    """Stamps 2.6 s off: beyond the +-2 s search, so no clock map is measured; the loader
    names the file and column instead of loading a reference seconds off the IMU."""
    write_akit(tmp_path, auv_trajectory(), n=1, lag=2.6)
    with pytest.raises(InputFileError, match=r"GT_trajectory1.csv.*Time.*line up"):
        load_trajectory(tmp_path, 1)


def test_reference_point_is_fitted_against_the_reference_at_the_dvl_times(tmp_path):
    """Reference 1.85 m ahead of the IMU, its 1-Hz samples half a second off the DVL's
    (the worst case for pairing a DVL row with the next reference epoch: it lands a whole
    second away), speed changing 1.5-2.5 m/s in turns.  The DVL's timing is recovered
    (the synthetic DVL is on the IMU clock: -lag), the lever arm within 0.03 m (what the
    1-Hz reference's linear interpolation leaves: 0.017 m; the next epoch gave 0.06 m) and
    the DVL agrees with the interpolated reference's forward velocity to 0.01 m/s (exact
    DVL; the next epoch gave 0.054 m/s)."""
    write_akit(tmp_path, varied_auv_trajectory(), n=1, lag=0.5, lever_y=1.85)
    rec = load_trajectory(tmp_path, 1)
    assert abs(rec.clock.dvl_offset_s + 0.5) < 0.02
    assert abs(rec.reference_offset_b[1] - 1.85) < 0.03
    gt = read_table(tmp_path / "corrected" / "GT_trajectory1.csv", "GT")
    fwd = rec.dvl.z[:, 1] - body_velocity(reference_on_imu_clock(gt, rec.clock,
                                                                 rec.dvl.time_s))[:, 1]
    assert np.sqrt(np.mean(fwd ** 2)) < 0.01


@pytest.mark.parametrize("text,expected", [("3", [3]), ("1-3", [1, 2, 3]), ("2,5-6", [2, 5, 6])])
def test_trajectory_lists(text, expected):
    assert parse_trajectories(text) == expected


@pytest.mark.parametrize("text", ["x", "3-1", "1-", "", "0", "0-8", "1-999999999999",
                                  "2,10000", "9" * 5000])
def test_bad_trajectory_lists(text):
    """A range to 10^12 was a MemoryError traceback; a 5000-digit number is quoted briefly."""
    with pytest.raises(InputFileError, match="trajectory") as exc:
        parse_trajectories(text)
    assert len(str(exc.value)) < 400


def test_the_highest_trajectory_number_is_accepted():
    assert parse_trajectories(f"{MAX_TRAJECTORY - 1}-{MAX_TRAJECTORY}") == [MAX_TRAJECTORY - 1,
                                                                          MAX_TRAJECTORY]


def _damaged(tmp_path, synthetic, rel, edit):
    d, _, _ = synthetic
    out = tmp_path / "akit"
    for f in d.rglob("*.csv"):
        dst = out / f.relative_to(d)
        dst.parent.mkdir(parents=True, exist_ok=True)
        dst.write_text(f.read_text())
    p = out / rel
    p.write_text(edit(p.read_text()))
    return out


@pytest.mark.parametrize("rel,edit,where", [
    ("IMU_trajectory1.csv", lambda s: s[: s.index("\n", len(s) // 2) + 9], "line"),  # cut
    ("corrected/DVL_trajectory1.csv", lambda s: s.replace(",", ";", 30), "line 2"),
    ("corrected/GT_trajectory1.csv", lambda s: "\n".join(s.splitlines()[:30]), "Time"),
    ("IMU_trajectory1.csv", lambda s: s.replace("-9.", "-1.9"), "ACC X,Y,Z"),          # no g
    ("corrected/DVL_trajectory1.csv", lambda s: s.replace("\n1.0,", "\nnan,", 1), "line"),
])
def test_damaged_files_give_one_clear_error(tmp_path, synthetic, rel, edit, where):
    d = _damaged(tmp_path, synthetic, rel, edit)
    with pytest.raises(InputFileError, match=where) as exc:
        load_trajectory(d, 1)
    assert Path(rel).name in str(exc.value)


def test_missing_file(tmp_path):
    with pytest.raises(DataMissingError, match="IMU_trajectory4.csv"):
        load_trajectory(tmp_path, 4)


@pytest.mark.skipif(not (AKIT / "IMU_trajectory3.csv").is_file(),
                    reason=f"real recording not found: {AKIT} (set FUZZYNAV_DATA)")
def test_real_trajectory_3_ends_within_one_percent_of_distance():
    """A DVL-aided navigation-grade INS: dead reckoning with the reference attitude ends
    within 0.1-0.9 % of the distance (shared notes); the filter must do about as well."""
    from fuzzynav.realdata.akit import run_trajectory

    rec = load_trajectory(AKIT, 3)
    res, m = run_trajectory(rec, "ekf")
    assert res.ok
    assert m["end_pos_h_pct"] < 1.0
    assert 600.0 < m["distance_m"] < 800.0
