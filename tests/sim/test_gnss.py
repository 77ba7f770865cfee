"""GNSS simulation: noise statistics, outliers, outages, noise windows and lever arm."""
import math

import numpy as np
import pymap3d
import pytest
from scipy import stats

from fuzzynav.errors import InputFileError
from fuzzynav.nav import attitude
from fuzzynav.sim.sensors import spec_class
from fuzzynav.sim.sensors.gnss import NoiseWindow, Spec, in_windows, outage_windows
from fuzzynav.sim.trajectory import Segment, Trajectory, generate

ALPHA = 1e-6
START = np.array([np.deg2rad(38.0178), np.deg2rad(112.4447), 825.0])


def chi2_ok(sample_var, true_var, dof):
    lo, hi = stats.chi2.ppf([ALPHA / 2, 1 - ALPHA / 2], dof) / dof
    return lo * true_var <= sample_var <= hi * true_var


@pytest.fixture(scope="module")
def static_truth():
    return generate(START, [Segment("static", 2000.0)], 10.0)


def enu_error(data, truth):
    """Measured minus true position in ENU metres, by pymap3d (independent of our earth)."""
    idx = np.searchsorted(truth.time_s, data.time_s)
    lat0, lon0, h0 = truth.lla[idx].T
    e, n, u = pymap3d.geodetic2enu(np.rad2deg(data.z[:, 0]), np.rad2deg(data.z[:, 1]),
                                   data.z[:, 2], np.rad2deg(lat0), np.rad2deg(lon0), h0)
    return np.column_stack([e, n, u])


def test_registered_as_gnss():
    assert spec_class("gnss") is Spec


def test_white_noise_per_axis_and_claimed_sigma(static_truth):
    spec = Spec(rate_hz=10.0, pos_sigma_m=(1.0, 2.0, 3.0), vel_sigma_mps=(0.1, 0.2, 0.3))
    data = spec.simulate(static_truth, np.random.default_rng(1))
    m = data.time_s.size
    assert m == 20001
    err = enu_error(data, static_truth)
    # metres-sized errors are applied to first order in lat/lon: the earth's curvature
    # leaves |e|^2 / R ~ 1e-5 m between the two
    np.testing.assert_allclose(err, data.meta["err_pos_enu_m"], atol=1e-4)
    for axis, (sp, sv) in enumerate(zip((1.0, 2.0, 3.0), (0.1, 0.2, 0.3))):
        assert chi2_ok(np.mean(err[:, axis] ** 2), sp**2, m)
        assert chi2_ok(np.mean(data.z[:, 3 + axis] ** 2), sv**2, m)  # truth velocity is 0
    np.testing.assert_array_equal(data.sigma[0], [1.0, 2.0, 3.0, 0.1, 0.2, 0.3])
    assert abs(np.corrcoef(err[:-1, 0], err[1:, 0])[0, 1]) < 5 / math.sqrt(m)


def test_gauss_markov_error_autocorrelation(static_truth):
    spec = Spec(rate_hz=10.0, pos_sigma_m=0.0, vel_sigma_mps=0.0, gm_pos_sigma_m=(2, 2, 2),
                gm_tau_s=5.0)
    err = spec.simulate(static_truth, np.random.default_rng(2)).meta["err_pos_enu_m"]
    lag = 50  # tau at 10 Hz
    rho = np.sum(err[:-lag] * err[lag:]) / np.sum(err[:-lag] ** 2)
    # 3 axes x 2000 s / 5 s: about 1200 correlation times; Bartlett sd ~ 0.03
    assert abs(rho - math.exp(-1)) < 0.12
    assert chi2_ok(np.mean(err**2), 4.0, err.size * 0.1 / (2 * 5.0))
    # claimed sigma defaults to the total white + GM
    assert spec.claimed_sigma()[0] == pytest.approx(2.0)


def test_outliers_rate_and_size(static_truth):
    spec = Spec(rate_hz=10.0, pos_sigma_m=0.0, vel_sigma_mps=0.0, outlier_rate=0.05,
                outlier_pos_m=30.0, outlier_vel_mps=3.0)
    data = spec.simulate(static_truth, np.random.default_rng(3))
    mask = data.meta["outlier_mask"]
    lo, hi = stats.binom.ppf([ALPHA / 2, 1 - ALPHA / 2], mask.size, 0.05)
    assert lo <= mask.sum() <= hi
    norm = np.linalg.norm(data.meta["err_pos_enu_m"], axis=1)
    np.testing.assert_allclose(norm[mask], 30.0, rtol=1e-12)
    assert np.all(norm[~mask] == 0.0)
    np.testing.assert_allclose(np.linalg.norm(data.z[mask, 3:], axis=1), 3.0, rtol=1e-9)
    # directions are uniform on the sphere: the mean of the unit vectors is near zero
    unit = data.meta["err_pos_enu_m"][mask] / 30.0
    assert np.all(np.abs(unit.mean(0)) < 5 / math.sqrt(mask.sum() * 3))


def test_periodic_and_explicit_outages(static_truth):
    spec = Spec(rate_hz=1.0, outage_period_s=180.0, outage_duration_s=60.0,
                outages=((10.0, 20.0),))
    data = spec.simulate(static_truth, np.random.default_rng(4))
    w = data.meta["outage_windows"]
    assert w.tolist()[:3] == [[10.0, 20.0], [180.0, 240.0], [360.0, 420.0]]
    assert not np.any(in_windows(data.time_s, w))
    # 2001 epochs minus 10 (explicit), 10 full windows of 60 (180 ... 1800) and the 21
    # epochs 1980 ... 2000 of the last window, cut by the end of the run
    assert data.time_s.size == 2001 - 10 - 60 * 10 - 21
    assert {20.0, 179.0, 240.0}.issubset(set(data.time_s.tolist()))
    assert data.meta["err_pos_enu_m"].shape[0] == data.time_s.size


def test_outage_windows_helper_first_start():
    w = outage_windows(400.0, period_s=180.0, duration_s=60.0, first_s=30.0)
    assert w.tolist() == [[30.0, 90.0], [210.0, 270.0], [390.0, 450.0]]


def test_noise_window_scales_true_noise_not_claimed_sigma(static_truth):
    win = NoiseWindow(start_s=500.0, end_s=1500.0, scale=3.0)
    spec = Spec(rate_hz=10.0, pos_sigma_m=1.0, noise_windows=(win,))
    data = spec.simulate(static_truth, np.random.default_rng(5))
    err = data.meta["err_pos_enu_m"]
    inside = (data.time_s >= 500.0) & (data.time_s < 1500.0)
    assert chi2_ok(np.mean(err[inside] ** 2), 9.0, err[inside].size)
    assert chi2_ok(np.mean(err[~inside] ** 2), 1.0, err[~inside].size)
    assert np.all(data.sigma[:, :3] == 1.0)


def test_coloured_noise_window_is_correlated_and_confined(static_truth):
    win = NoiseWindow(start_s=1000.0, end_s=2000.0, coloured_pos_m=5.0, coloured_tau_s=10.0)
    spec = Spec(rate_hz=10.0, pos_sigma_m=0.0, vel_sigma_mps=0.0, noise_windows=(win,))
    data = spec.simulate(static_truth, np.random.default_rng(6))
    err = data.meta["err_pos_enu_m"]
    inside = data.time_s >= 1000.0
    assert np.all(err[~inside] == 0.0)
    e = err[inside]
    rho = np.sum(e[:-100] * e[100:]) / np.sum(e[:-100] ** 2)
    assert abs(rho - math.exp(-1)) < 0.2


def test_no_velocity_gives_nan_columns(static_truth):
    data = Spec(velocity=False).simulate(static_truth, np.random.default_rng(7))
    assert np.all(np.isnan(data.z[:, 3:])) and np.all(np.isnan(data.sigma[:, 3:]))
    assert np.all(np.isfinite(data.z[:, :3]))


def hand_truth(heading_deg, yaw_rate_rps, pitch_deg=0.0):
    """A two-sample truth at rest with a given attitude and body rate (not integrated)."""
    att = np.tile([np.deg2rad(pitch_deg), 0.0, np.deg2rad(heading_deg)], (2, 1))
    lla = np.tile(START, (2, 1))
    w = np.tile([0.0, 0.0, -yaw_rate_rps], (2, 1))
    z = np.zeros((1, 3))
    return Trajectory(time_s=np.array([0.0, 0.01]), lla=lla, vel_n=np.zeros((2, 3)),
                      att=att, q_bn=attitude.euler_to_quat(att), dtheta_b=z, dv_b=z,
                      omega_nb_b=w, imu_rate_hz=100.0)


def test_lever_arm_geometry_by_hand():
    # facing east, antenna 1 m forward and 0.5 m up, turning right at 0.2 rad/s
    truth = hand_truth(90.0, 0.2)
    spec = Spec(rate_hz=100.0, pos_sigma_m=0.0, vel_sigma_mps=0.0,
                lever_arm_b_m=(0.0, 1.0, 0.5))
    data = spec.simulate(truth, np.random.default_rng(0))
    enu = enu_error(data, truth)[0]
    np.testing.assert_allclose(enu, [1.0, 0.0, 0.5], atol=1e-6)
    # the nose swings south: v = omega x l = (0, 0, -0.2) x (1, 0, 0.5) = (0, -0.2, 0)
    np.testing.assert_allclose(data.z[0, 3:], [0.0, -0.2, 0.0], atol=1e-12)
    np.testing.assert_array_equal(data.meta["lever_arm_b"], [0.0, 1.0, 0.5])


def test_lever_arm_pitched_up():
    # pitched up 30 deg facing north: a forward lever arm of 2 m rises by 1 m
    truth = hand_truth(0.0, 0.0, pitch_deg=30.0)
    data = Spec(rate_hz=100.0, pos_sigma_m=0.0, lever_arm_b_m=(0.0, 2.0, 0.0)).simulate(
        truth, np.random.default_rng(0))
    np.testing.assert_allclose(enu_error(data, truth)[0], [0.0, math.sqrt(3), 1.0], atol=1e-6)


def test_adding_outliers_leaves_the_white_noise_alone(static_truth):
    a = Spec(rate_hz=1.0).simulate(static_truth, np.random.default_rng(8))
    b = Spec(rate_hz=1.0, outlier_rate=0.1, outlier_pos_m=50.0).simulate(
        static_truth, np.random.default_rng(8))
    ok = ~b.meta["outlier_mask"]
    np.testing.assert_array_equal(a.z[ok], b.z[ok])
    assert b.meta["outlier_mask"].any()


@pytest.mark.parametrize("table, where, what", [
    ({"rate": 1}, "sensors.g.rate", "unknown key"),
    ({"rate_hz": -1}, "sensors.g.rate_hz", "must lie in"),
    ({"outlier_rate": 2.0}, "sensors.g.outlier_rate", "must lie in"),
    ({"outages": [[50, 40]]}, "sensors.g.outages[0]", "start must precede end"),
    ({"outage_period_s": 180}, "sensors.g.outage_duration_s", "both"),
    ({"noise_windows": [{"start_s": 1, "end_s": 2, "scal": 3}]},
     "sensors.g.noise_windows[0].scal", "unknown key"),
    ({"velocity": "yes"}, "sensors.g.velocity", "true or false"),
])
def test_bad_gnss_tables_name_the_key(table, where, what):
    with pytest.raises(InputFileError) as exc:
        Spec.from_dict(table, "sensors.g")
    assert exc.value.where == where and what in exc.value.what


def test_gnss_table_round_trip():
    spec = Spec(rate_hz=5.0, outages=((1.0, 2.0),), outage_period_s=180, outage_duration_s=60,
                noise_windows=(NoiseWindow(3.0, 4.0, scale=2.0),), claimed_pos_sigma_m=(1, 1, 2),
                lever_arm_b_m=(0.1, 0.2, 0.3))
    d = spec.to_dict()
    assert d["kind"] == "gnss"
    assert Spec.from_dict(d, "s") == spec
