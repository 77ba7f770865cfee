"""Pieces of the real-data path: increments, time tags, mounting, alignment, degradation."""
import math

import numpy as np
import pytest
from scipy import stats

from fuzzynav.errors import InputFileError
from fuzzynav.nav import attitude
from fuzzynav.realdata import coarse_align, degrade
from fuzzynav.sim.imu import ImuData
from fuzzynav.realdata.loaders import increments, sync, timetag
from fuzzynav.realdata.loaders.mounting import Mounting, passive_rpy_matrix
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import scenario_from_dict
from fuzzynav.sim.sensors import SensorData
from tests.realdata.rtklib_files import tag_bytes

ALPHA = 1e-6


# -- increments ---------------------------------------------------------------------------------
def test_integrate_rates_is_exact_for_piecewise_linear_rates():
    t = np.array([0.0, 0.01, 0.02, 0.035, 0.05])
    w = np.column_stack([3.0 + 2.0 * t, np.array([0.0, 1.0, -1.0, 2.0, 0.5])])
    bounds = np.array([0.0, 0.005, 0.017, 0.05])
    got = increments.integrate_rates(t, w, bounds)
    # column 0 is linear in t: exact antiderivative 3t + t^2
    F = 3.0 * bounds + bounds**2
    np.testing.assert_allclose(got[:, 0], np.diff(F), rtol=1e-12)
    # column 1 piecewise linear: integrate a fine linear interpolation by brute force
    fine = np.linspace(0.0, 0.05, 500001)
    y = np.interp(fine, t, w[:, 1])
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(fine))])
    np.testing.assert_allclose(got[:, 1], np.diff(np.interp(bounds, fine, cum)), atol=1e-10)
    # on the sample instants themselves: the trapezoid rule
    np.testing.assert_allclose(increments.integrate_rates(t, w, t)[:, 1],
                               0.5 * (w[1:, 1] + w[:-1, 1]) * np.diff(t), rtol=1e-12)


def test_regular_sample_times_removes_jitter_and_counts_dropouts():
    rng = np.random.default_rng(1)
    n = np.arange(5000)
    n = np.delete(n, [100, 2000, 2001])                 # three dropped samples
    true = 1234.5 + 9.9995 * n
    ticks = np.floor(true + rng.uniform(0, 1.0, n.size))
    clock = increments.regular_sample_times(ticks)
    assert clock.regular and clock.n_missing == 3
    assert clock.period_ms == pytest.approx(9.9995, abs=1e-5)
    assert np.max(np.abs(clock.time_ms - true + np.mean(clock.time_ms - true))) < 0.05
    assert clock.max_gap_ms == pytest.approx(3 * 9.9995, abs=1e-3)


def test_grid_bounds_are_whole_multiples():
    b = increments.grid_bounds(0.8731, 1.0, 100.0)
    assert b[0] == pytest.approx(0.88) and b[-1] == pytest.approx(1.0) and b.size == 13


# -- time tags ------------------------------------------------------------------------------------
def test_timetag_parse(tmp_path):
    p = tmp_path / "x.tag"
    p.write_bytes(tag_bytes([(131, 37), (146, 99), (162, 180)]) + b"\x00\x01\x02")
    tag = timetag.read_timetag(p)
    assert (tag.start_int_s, tag.start_frac_s, tag.tick_f) == (1752003261, 0.854, 7)
    assert tag.tick_ms.tolist() == [131, 146, 162] and tag.fpos.tolist() == [37, 99, 180]
    assert timetag.arrival_ticks(tag, np.array([10, 37, 38, 180, 181])).tolist() == \
        [131, 131, 146, 162, -1]


@pytest.mark.parametrize("raw, where", [
    (b"TIMETAG", "header"),
    (tag_bytes([(1, 10)]).replace(b"TIMETAG", b"TIMEBAG"), "header"),
    (tag_bytes([(5, 10), (4, 20)]), "record 1"),
    (tag_bytes([(5, 10), (6, 2)]), "record 1"),
    (tag_bytes([(5, 10)], start=(1, 1.5)), "header.fractional_seconds"),
])
def test_bad_timetags(tmp_path, raw, where):
    p = tmp_path / "bad.tag"
    p.write_bytes(raw)
    with pytest.raises(InputFileError) as exc:
        timetag.read_timetag(p)
    assert exc.value.where == where and exc.value.path == str(p)


# -- mounting ---------------------------------------------------------------------------------------
def test_passive_rpy_matches_groves_matrix():
    r, p, y = np.deg2rad([10.0, -20.0, 30.0])
    cr, sr, cp, sp, cy, sy = map(float, (np.cos(r), np.sin(r), np.cos(p), np.sin(p),
                                         np.cos(y), np.sin(y)))
    # Groves (2013), eq. 2.22: C = [[cp cy, cp sy, -sp], ...]
    groves = np.array([[cp * cy, cp * sy, -sp],
                       [-cr * sy + sr * sp * cy, cr * cy + sr * sp * sy, sr * cp],
                       [sr * sy + cr * sp * cy, -sr * cy + cr * sp * sy, cr * cp]])
    np.testing.assert_allclose(passive_rpy_matrix([r, p, y]), groves, atol=1e-15)


def test_mounting_of_an_upside_down_backwards_imu():
    m = Mounting.from_frd_rpy([180.0, 0.0, 180.0])
    # IMU x points back, y right, z up: body (right, forward, up) = (y, -x, z)
    np.testing.assert_allclose(m.matrix, [[0, 1, 0], [-1, 0, 0], [0, 0, 1]], atol=1e-15)


def test_mounting_toml(tmp_path):
    p = tmp_path / "mounting.toml"
    p.write_text("imu_to_body = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]\n"
                 "gnss_lever_arm_b_m = [-0.05, 0.0, 0.0]\n")
    m = Mounting.from_toml(p)
    assert m.gnss_lever_arm_b_m == (-0.05, 0.0, 0.0)
    for text, where in [("imu_to_body = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]", "imu_to_body"),
                        ("imu_rpy_frd_deg = [1, 2]", "imu_rpy_frd_deg"),
                        ("gnss_lever_arm_b_m = [0, 0, 0]", "imu_rpy_frd_deg"),
                        ("imu_rpy_frd_deg = [0, 0, 0]\nlever = 1", "lever"),
                        ("imu_rpy_frd_deg = [0, 0, 0]\ngnss_lever_arm_b_m = [0, 1e6, 0]",
                         "gnss_lever_arm_b_m[1]")]:
        p.write_text(text)
        with pytest.raises(InputFileError) as exc:
            Mounting.from_toml(p)
        assert exc.value.where == where and exc.value.path == str(p)



def test_mounting_toml_has_the_scenario_files_limits(tmp_path):
    """Deep nesting, a huge file and a directory: one InputFileError naming the file each
    (tomllib alone would raise RecursionError, read it all, or IsADirectoryError)."""
    from fuzzynav.sim.tomltable import MAX_TOML_BYTES, MAX_TOML_DEPTH

    p = tmp_path / "mounting.toml"
    for text, what in [("x = " + "[" * 5000 + "]" * 5000, "nest"),
                       (f"a = [{'[' * (MAX_TOML_DEPTH + 2)}1{']' * (MAX_TOML_DEPTH + 2)}]",
                        "deeper than"),
                       ("# pad\n" * (MAX_TOML_BYTES // 6 + 1), "bytes")]:
        p.write_text(text)
        with pytest.raises(InputFileError, match=what) as exc:
            Mounting.from_toml(p)
        assert exc.value.path == str(p)
    d = tmp_path / "dir.toml"
    d.mkdir()
    with pytest.raises(InputFileError, match="is a directory") as exc:
        Mounting.from_toml(d)
    assert exc.value.path == str(d)

# -- coarse alignment and lag on simulated data -------------------------------------------------------
CAR = {"start": {"lat_deg": 40.0, "lon_deg": -105.0, "h_m": 1600.0},
       "imu": {"rate_hz": 100.0, "gyro_arw_dpsh": 0.3, "accel_vrw_ug_psqrthz": 80.0,
               "gyro_bias_dph": [20.0, -10.0, 30.0], "accel_bias_ug": [500.0, -800.0, 300.0]},
       "segments": [{"kind": "static", "duration_s": 20.0},
                    {"kind": "accelerate", "duration_s": 10.0, "speed_change_mps": 8.0},
                    {"kind": "turn", "duration_s": 10.0, "turn_deg": 70.0},
                    {"kind": "cruise", "duration_s": 5.0},
                    {"kind": "turn", "duration_s": 8.0, "turn_deg": -120.0},
                    {"kind": "s-turns", "duration_s": 20.0, "turn_deg": 40.0, "n_turns": 4},
                    {"kind": "accelerate", "duration_s": 10.0, "speed_change_mps": -8.0}],
       "sensors": {"gps": {"kind": "gnss", "rate_hz": 4.0, "pos_sigma_m": 0.02,
                           "vel_sigma_mps": 0.02}}}


@pytest.mark.parametrize("heading_deg", [0.0, 63.0, 200.0, 300.0])
def test_initial_state_recovers_attitude_on_simulation(heading_deg):
    doc = {**CAR, "start": {**CAR["start"], "heading_deg": heading_deg}}
    log = simulate(scenario_from_dict(doc), 3)
    g = log.sensors["gps"]
    k = None
    for forward_known in (True, False):
        s = coarse_align.initial_state(log.imu, g, forward_known=forward_known)
        k = np.searchsorted(log.truth.time_s, s.time_s)
        d = np.rad2deg(attitude.wrap_pi(s.att - log.truth.att[k]))
        # level: the accelerometer bias tilts by b/g (800 ug: 0.05 deg)
        assert np.all(np.abs(d[:2]) < 0.1)
        assert abs(d[2]) < 1.5, (s.method, d)
    assert 19.0 <= s.rest_s[1] <= 20.5
    # the rest mean carries the angle random walk: sigma = ARW / sqrt(T)
    rest = s.rest_s[1] - s.rest_s[0]
    sd = np.deg2rad(0.3 / 60.0) / math.sqrt(rest)
    np.testing.assert_allclose(s.gyro_bias_rps, np.deg2rad([20.0, -10.0, 30.0]) / 3600,
                               atol=5 * sd)


def test_course_rate_lag_finds_a_known_shift():
    doc = {**CAR, "segments": CAR["segments"] * 1}
    log = simulate(scenario_from_dict(doc), 4)
    shifted = ImuData(time_s=log.imu.time_s + 0.13, dtheta_b=log.imu.dtheta_b,
                      dv_b=log.imu.dv_b)
    lag = sync.course_rate_lag(shifted, log.sensors["gps"], up_b=[0, 0, 1], min_speed_mps=2.0)
    assert lag == pytest.approx(-0.13, abs=0.01)


def test_velocity_lag_of_a_delayed_velocity():
    t = np.arange(0, 60, 0.25)
    e = 50 * np.sin(t / 5.0)
    n = 30 * np.cos(t / 7.0)
    z = np.column_stack([np.deg2rad(40) + n / 6.37e6, np.deg2rad(-105) + e / (6.39e6 * 0.766),
                         np.full_like(t, 1600.0), 10 * np.cos((t - 0.2) / 5.0),
                         -30 / 7 * np.sin((t - 0.2) / 7.0), np.zeros_like(t)])
    g = SensorData(kind="gnss", time_s=t, z=z, sigma=np.ones_like(z))
    assert sync.velocity_lag(g) == pytest.approx(0.2, abs=0.02)


# -- degradation ------------------------------------------------------------------------------------
def fixes(n=20000):
    t = np.arange(n) * 0.25
    z = np.column_stack([np.full(n, np.deg2rad(40.0)), np.full(n, np.deg2rad(-105.0)),
                         np.full(n, 1600.0), np.zeros((n, 3))])
    sigma = np.tile([0.01, 0.01, 0.02, 0.05, 0.05, 0.05], (n, 1))
    return SensorData(kind="gnss", time_s=t, z=z, sigma=sigma,
                      meta={"q": np.ones(n), "lever_arm_b": np.zeros(3)})


def test_add_white_noise_statistics_and_claimed_sigma():
    f = fixes()
    d = degrade.add_white_noise(f, 2.0, np.random.default_rng(5), sigma_vel_mps=0.3)
    assert np.array_equal(f.z[:, 2], np.full(20000, 1600.0))      # input untouched
    n = d.meta["added_pos_enu_m"]
    lo, hi = stats.chi2.ppf([ALPHA / 2, 1 - ALPHA / 2], n.shape[0]) / n.shape[0]
    for axis in range(3):
        assert lo * 4.0 <= np.mean(n[:, axis] ** 2) <= hi * 4.0
    np.testing.assert_allclose(d.z[:, 2] - 1600.0, n[:, 2], atol=1e-9)
    np.testing.assert_allclose(d.z[:, 0] - f.z[:, 0], n[:, 1] / 6.3695e6, rtol=2e-3)
    np.testing.assert_allclose(d.sigma[0], np.hypot(f.sigma[0], [2, 2, 2, .3, .3, .3]))
    assert degrade.add_white_noise(f, 2.0, np.random.default_rng(5), claim="keep").sigma[0, 0] \
        == 0.01


def test_outages_every_180_s():
    f = fixes(4000)                      # 1000 s at 4 Hz
    d = degrade.with_outages(f, period_s=180.0, duration_s=60.0)
    w = d.meta["outage_windows"]
    assert w.tolist() == [[180.0, 240.0], [360.0, 420.0], [540.0, 600.0], [720.0, 780.0],
                          [900.0, 960.0]]
    assert d.time_s.size == 4000 - 5 * 240 and d.meta["q"].size == d.time_s.size
    gaps = np.diff(d.time_s)
    assert np.sum(gaps > 1.0) == 5 and math.isclose(gaps.max(), 60.25)
    assert d.meta["lever_arm_b"].shape == (3,)


def test_data_lines_found_on_the_bytes_are_those_line_by_line():
    """The block-at-once shortcut (no ``#`` and no line starting with whitespace: every line
    is data) keeps the lines the line-by-line definition keeps: ending with a newline, not
    blank by ``bytes.strip``, not the file's first; random blocks of data, blanks of every
    ASCII whitespace, comments and cut last lines."""
    import random

    from fuzzynav.realdata.loaders.imu_csv import _data_lines

    def by_line(lines, first):
        return [j for j, x in enumerate(lines) if first + j >= 1 and x.endswith(b"\n")
                and x.strip() and not x.lstrip().startswith(b"#")]

    rnd = random.Random(7)
    parts = [b"1,2,3", b"", b" ", b"\t", b"\r", b"x", b"\x0b", b"\x0c", b"  7 ", b"#"]
    for _ in range(5000):
        lines = [b"".join(rnd.choices(parts, k=rnd.randint(0, 3))) + rnd.choice([b"\n", b"\r\n"])
                 for _ in range(rnd.randint(1, 6))]
        if rnd.random() < 0.5:
            lines[-1] = lines[-1].rstrip(b"\n") or b"z"
        for first in (0, 3):
            assert list(_data_lines(lines, first, b"".join(lines))) == by_line(lines, first)
