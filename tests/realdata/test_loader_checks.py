"""The recording checks at their thresholds (:mod:`fuzzynav.realdata.loaders.checks`)."""
from types import SimpleNamespace

import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.sim.imu import ImuData
from fuzzynav.realdata.loaders import checks, sync
from fuzzynav.sim.sensors import SensorData
from tests.realdata.rtklib_files import drive_samples

P = "rec/imu_1.csv"


def expect(ok, match, check, *args):
    """Run ``check(*args)``: it must pass if ``ok``, else refuse with ``match`` in the text."""
    if ok:
        return check(*args)
    with pytest.raises(InputFileError, match=match):
        check(*args)


def _ticks(rate_hz, n=500, gap_s=0.0):
    t = 1000.0 + np.arange(n) * 1000.0 / rate_hz
    t[n // 2:] += gap_s * 1000.0
    return t


@pytest.mark.parametrize("rate_hz, ok", [(1.0, True), (100.0, True), (2000.0, True),
                                         (0.9, False), (2100.0, False)])
def test_sample_rate_range(rate_hz, ok):
    rate = expect(ok, "column tick", checks.imu_ticks, P, _ticks(rate_hz), np.arange(500) + 2)
    assert not ok or rate == pytest.approx(rate_hz)


def test_gap_limit_names_the_line():
    lines = np.arange(500) + 2
    checks.imu_ticks(P, _ticks(100.0, gap_s=0.98), lines)          # 0.99 s between samples
    with pytest.raises(InputFileError) as exc:
        checks.imu_ticks(P, _ticks(100.0, gap_s=1.0), lines)       # 1.01 s
    assert exc.value.where == f"line {lines[250]}, column tick"


def _at_rest(f_g=1.0, w_dps=0.2, n=3000):
    rng = np.random.default_rng(0)
    acc = np.array([0.1, 0.2, np.sqrt(1.0 - 0.05)]) * f_g + 0.003 * rng.standard_normal((n, 3))
    gyro = np.array([w_dps, 0.0, 0.0]) + 0.1 * rng.standard_normal((n, 3))
    return acc, gyro, np.arange(n) + 2


@pytest.mark.parametrize("f_g, ok", [(0.91, True), (1.09, True), (0.89, False), (1.11, False)])
def test_gravity_band(f_g, ok):
    expect(ok, "gravity_band", checks.imu_physics, P, *_at_rest(f_g), 100.0)


def test_swapped_columns_and_units_are_named():
    acc, gyro, lines = _at_rest()
    with pytest.raises(InputFileError, match="swapped"):
        checks.imu_physics(P, gyro, acc, lines, 100.0)
    with pytest.raises(InputFileError, match="m/s\\^2"):
        checks.imu_physics(P, acc * 9.80665, gyro, lines, 100.0)


@pytest.mark.parametrize("w_dps, ok", [(5.5, True), (6.0, False)])      # limit 5.73 deg/s
def test_gyro_at_rest(w_dps, ok):
    expect(ok, "gyro_rest_max_rps", checks.imu_physics, P, *_at_rest(w_dps=w_dps), 100.0)


def test_full_scale_names_the_first_line_beyond_it():
    acc, gyro, lines = _at_rest()
    gyro[2000] = [0.0, 0.0, np.degrees(36.0)]
    with pytest.raises(InputFileError) as exc:
        checks.imu_physics(P, acc, gyro, lines, 100.0)
    assert exc.value.where == f"line {lines[2000]}, columns gyro x,y,z"


TAG = SimpleNamespace(fpos=np.array([100, 400_000]), tick_ms=np.array([130, 60_300]),
                      duration_s=60.3)


@pytest.mark.parametrize("method, rate, samples_s, ok", [
    ("tag-fit", 1.0099, 60.0, True), ("tag-fit", 0.9899, 60.0, False),
    ("endpoints", 60.3 / 59.9, 59.9, True),          # 0.4 s of stretch
    ("endpoints", 60.3 / 59.7, 59.7, False),         # 0.6 s
])
def test_clock_rate_and_stretch(method, rate, samples_s, ok):
    expect(ok, "clock_rate_tolerance|max_stretch_s", checks.clock_rate, P, "rec/imu_1.csv.tag",
           TAG, method, rate, 396_000, 6_000, samples_s)


@pytest.mark.parametrize("n_fixed, span_s, ok", [(10, 51.0, True), (9, 51.0, False),
                                                 (204, 49.0, False)])
def test_gnss_overlap(n_fixed, span_s, ok):
    """Fixed epochs (the first n-1 and the last) over ``span_s`` of a 100-s IMU span."""
    t = 1e9 + np.linspace(0.0, span_s, 204)
    q = np.ones(204)
    q[n_fixed - 1:-1] = 2
    expect(ok, "column (Q|GPST)", checks.gnss_overlap, "g.pos", t, q, (1e9, 1e9 + 100.0))


def test_gyro_course_gain_of_a_drive_and_of_gyros_in_the_wrong_unit():
    traj, _, _ = drive_samples()
    sel = slice(0, None, 25)
    fixes = SensorData("gnss", traj.time_s[sel], np.column_stack([traj.lla[sel],
                                                                  traj.vel_n[sel]]),
                       np.ones((traj.time_s[sel].size, 6)))
    imu = ImuData(time_s=traj.time_s, dtheta_b=traj.dtheta_b, dv_b=traj.dv_b)
    # ideal gyros turn as the course does (chords on arcs: a few % at 4 Hz and 9 deg/s)
    assert sync.gyro_course_gain(imu, fixes) == pytest.approx(1.0, abs=0.05)
    rad_as_deg = ImuData(time_s=traj.time_s, dtheta_b=traj.dtheta_b * np.pi / 180,
                         dv_b=traj.dv_b)
    assert sync.gyro_course_gain(rad_as_deg, fixes) == pytest.approx(180 / np.pi, rel=0.05)
    with pytest.raises(InputFileError, match="rad/s"):
        checks.gyro_scale(P, rad_as_deg, fixes)
    # a car that does not turn cannot tell
    still = ImuData(time_s=traj.time_s[:1500], dtheta_b=traj.dtheta_b[:1499],
                    dv_b=traj.dv_b[:1499])
    assert sync.gyro_course_gain(still, fixes) is None
