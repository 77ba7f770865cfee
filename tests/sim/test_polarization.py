"""Polarization sensor simulation: measurement content, noise statistics, dropouts, TOML."""
import datetime as dt

import numpy as np
import pytest
from scipy import stats

from fuzzynav.errors import InputFileError
from fuzzynav.nav.attitude import euler_to_dcm, euler_to_quat
from fuzzynav.nav import polarization_solver as ps
from fuzzynav.sim import skylight as sk
from fuzzynav.sim import sun
from fuzzynav.sim.sensors import SensorData, spec_class
from fuzzynav.sim.sensors.polarization import Spec
from fuzzynav.sim.trajectory import Trajectory

# paper 000's start point, a June morning (sun ~20-60 deg high over the run)
LAT, LON = np.radians(38.0178), np.radians(112.4447)
START = dt.datetime(2023, 6, 10, 1, 0, tzinfo=dt.timezone.utc)


def _trajectory(att, rate_hz=100.0, lat=LAT, lon=LON):
    """Truth with the given attitudes (N+1, 3); the position stays put (the sensor only
    needs attitude, place and time)."""
    n = att.shape[0]
    zeros = np.zeros((n, 3))
    lla = np.tile([lat, lon, 825.0], (n, 1))
    return Trajectory(time_s=np.arange(n) / rate_hz, lla=lla, vel_n=zeros, att=att,
                      q_bn=euler_to_quat(att), dtheta_b=zeros[1:], dv_b=zeros[1:],
                      omega_nb_b=zeros, imu_rate_hz=rate_hz)


def _wobbly(duration_s, rate_hz=100.0, tilt_deg=15.0, seed=0):
    t = np.arange(int(duration_s * rate_hz) + 1) / rate_hz
    rng = np.random.default_rng(seed)
    w = rng.uniform(0.01, 0.1, 3)
    att = np.stack([np.radians(tilt_deg) * np.sin(w[0] * t),
                    np.radians(tilt_deg) * np.sin(w[1] * t + 1.0),
                    (w[2] * t) % (2 * np.pi)], -1)
    return _trajectory(att, rate_hz)


def _model_aop(truth, data):
    """Noise-free zenith AoP of the data epochs, from truth and the sun columns."""
    idx = np.round(data.time_s * truth.imu_rate_hz).astype(int)
    C = euler_to_dcm(truth.att[idx])
    return np.array([ps.zenith_aop(C[i], data.z[i, 1:4]) for i in range(len(idx))])


def test_registered_and_simulates_point_measurements():
    assert spec_class("polarization") is Spec
    truth = _wobbly(60.0)
    data = Spec(noise_deg=0.0, claimed_sigma_deg=0.3).simulate(
        truth, np.random.default_rng(1), START)
    assert isinstance(data, SensorData) and data.kind == "polarization"
    assert data.z.shape == (601, 4) and data.meta["sensor_type"] == 0
    np.testing.assert_allclose(np.diff(data.time_s), 0.1)
    np.testing.assert_allclose(data.sigma[:, 0], np.radians(0.3))
    np.testing.assert_array_equal(data.sigma[:, 1:], 0.0)
    # sun columns: the ephemeris at the epoch
    jd = sun.julian_day(START) + data.time_s / 86400.0
    np.testing.assert_allclose(data.z[:, 1:4], sun.sun_vector_n(jd, LAT, LON), atol=1e-14)
    # noise-free AoPs equal the solver's model, and the solver gives back the heading
    np.testing.assert_allclose(sk.fold_half_pi(data.z[:, 0] - _model_aop(truth, data)), 0.0,
                               atol=1e-12)
    idx = np.round(data.time_s * 100).astype(int)
    for i in range(0, 601, 37):
        p, r, h = truth.att[idx[i]]
        h_est, _ = ps.heading_from_zenith_aop(data.z[i, 0], data.z[i, 1:4], p, r, h + 1.0)
        assert abs((h_est - h + np.pi) % (2 * np.pi) - np.pi) < 1e-9


def _errors(spec, seed=2, duration_s=200.0):
    truth = _wobbly(duration_s)
    data = spec.simulate(truth, np.random.default_rng(seed), START)
    err = sk.fold_half_pi(data.z[:, 0] - _model_aop(truth, data))
    np.testing.assert_allclose(err, data.meta["err_aop_rad"][:, 0], atol=1e-12)
    return np.degrees(err)


def test_gaussian_noise_std_within_chi_square_bounds():
    err = _errors(Spec(noise_deg=0.3, rate_hz=20.0))
    n = err.size
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], n - 1)
    s2 = err.var(ddof=1)
    assert (n - 1) * s2 / hi < 0.3**2 < (n - 1) * s2 / lo
    assert abs(err.mean()) < 4 * 0.3 / np.sqrt(n)
    assert stats.kstest(err / 0.3, "norm").pvalue > 1e-3


def test_heavy_tailed_errors_follow_their_distributions():
    err = _errors(Spec(noise_deg=0.3, rate_hz=20.0, student_t_dof=3.0))
    assert stats.kstest(err / 0.3, stats.t(3.0).cdf).pvalue > 1e-3
    p, k = 0.05, 10.0
    err = _errors(Spec(noise_deg=0.3, rate_hz=20.0, outlier_rate=p, outlier_scale=k), seed=3)

    def mixture_cdf(x):  # N(0,1) plus, w.p. p, an extra N(0, k^2)
        return (1 - p) * stats.norm.cdf(x) + p * stats.norm.cdf(x / np.hypot(1.0, k))

    assert stats.kstest(err / 0.3, mixture_cdf).pvalue > 1e-3
    # tails a Gaussian would not have: P(|e| > 4 sigma) = 6e-5 vs 0.035 for the mixture
    assert np.sum(np.abs(err) > 4 * 0.3) > 70


def test_misalignment_about_the_boresight_biases_level_heading_one_for_one():
    truth = _trajectory(np.tile([0.0, 0.0, 1.0], (1001, 1)))
    data = Spec(noise_deg=0.0, claimed_sigma_deg=0.3, misalignment_deg=(0.0, 0.0, 0.5)).simulate(
        truth, np.random.default_rng(0), START)
    h = np.array([ps.heading_from_zenith_aop(z[0], z[1:4], 0.0, 0.0, 1.0)[0] for z in data.z])
    # sensor turned +0.5 deg about its boresight reads 0.5 deg less: heading 0.5 deg low
    np.testing.assert_allclose(np.degrees(h - 1.0), -0.5, atol=1e-9)


def test_cloud_windows_and_random_clouds_remove_epochs():
    truth = _wobbly(600.0, rate_hz=10.0)
    data = Spec(rate_hz=10.0, dop_min=0.0,
                cloud_windows=((100.0, 160.0), (400.0, 401.5))).simulate(
        truth, np.random.default_rng(0), START)
    t = data.time_s
    assert not np.any((t >= 100.0) & (t < 160.0)) and not np.any((t >= 400.0) & (t < 401.5))
    assert t.size == 6001 - 600 - 15
    # random spells: long-run cloudy fraction cloudy / (clear + cloudy)
    spec = Spec(rate_hz=10.0, dop_min=0.0, cloud_mean_clear_s=20.0, cloud_mean_cloudy_s=10.0)
    frac = [1.0 - spec.simulate(truth, np.random.default_rng(s), START).time_s.size / 6001
            for s in range(8)]
    assert abs(np.mean(frac) - 1.0 / 3.0) < 0.06
    windows = spec.simulate(truth, np.random.default_rng(3), START).meta["cloud_windows"]
    assert np.mean(np.diff(windows, axis=1)) == pytest.approx(10.0, rel=0.35)


def test_dop_threshold_and_night_remove_epochs():
    # Tropic of Cancer near the June solstice: the sun passes within ~0.5 deg of the zenith
    lat = np.radians(23.44)
    noon = dt.datetime(2023, 6, 21, 12, 0, tzinfo=dt.timezone.utc) - dt.timedelta(hours=7.5)
    truth = _trajectory(np.zeros((36001, 3)), rate_hz=10.0, lat=lat, lon=np.radians(112.5))
    start = noon - dt.timedelta(minutes=30)
    data = Spec(rate_hz=1.0, dop_min=0.2).simulate(truth, np.random.default_rng(0), start)
    # independent DoP at the zenith from the sun's elevation
    every = np.arange(0, 3601)
    jd = sun.julian_day(start) + every / 86400.0
    el = sun.sun_position(jd, lat, np.radians(112.5)).elevation_rad
    dop = 0.75 * np.cos(el) ** 2 / (1 + np.sin(el) ** 2)
    kept = np.isin(every, np.round(data.time_s).astype(int))
    assert kept.sum() < every.size  # a gap around noon
    np.testing.assert_array_equal(kept, dop >= 0.2)
    # a night-time start: nothing at all
    night = Spec(rate_hz=1.0).simulate(truth, np.random.default_rng(0),
                                       noon + dt.timedelta(hours=12))
    assert night.time_s.size == 0 and night.z.shape == (0, 4)


def test_imaging_sensor_columns_nan_views_and_solution():
    spec = Spec(sensor_type="imaging", noise_deg=0.0, claimed_sigma_deg=0.3,
                ring_zenith_deg=60.0, dop_min=0.3)
    views = spec.views_c()
    assert views.shape == (7, 3)
    truth = _wobbly(100.0, tilt_deg=10.0)
    data = spec.simulate(truth, np.random.default_rng(0), START)
    assert data.z.shape[1] == 7 + 3 and data.meta["sensor_type"] == 1
    np.testing.assert_allclose(data.meta["views_b"], views)
    aops = data.z[:, :7]
    # views with a low DoP are NaN, and their DoP was indeed below the threshold
    low = data.meta["dop"] < 0.3
    np.testing.assert_array_equal(np.isnan(aops), low)
    assert low.any() and (~low).sum(1).min() >= 2
    idx = np.round(data.time_s * 100).astype(int)
    for i in range(0, len(idx), 53):
        p, r, h = truth.att[idx[i]]
        est_p, est_h, _, _ = ps.imaging_pitch_heading(aops[i], views, data.z[i, 7:], r, p, h,
                                                      0.02, 0.5, np.radians(0.3))
        assert abs(est_p - p) < 1e-9 and abs((est_h - h + np.pi) % (2 * np.pi) - np.pi) < 1e-9


def test_same_seed_same_data():
    spec = Spec(student_t_dof=4.0, outlier_rate=0.01, cloud_mean_clear_s=30.0,
                cloud_mean_cloudy_s=5.0)
    truth = _wobbly(120.0)
    a = spec.simulate(truth, np.random.default_rng(7), START)
    b = spec.simulate(truth, np.random.default_rng(7), START)
    np.testing.assert_array_equal(a.z, b.z)
    np.testing.assert_array_equal(a.time_s, b.time_s)


def test_from_dict_round_trip_and_defaults():
    d = {"kind": "polarization", "type": "imaging", "rate_hz": 5, "noise_deg": 0.5,
         "student_t_dof": 4, "cloud_windows": [[10, 20]], "misalignment_deg": [0, 0, 0.2],
         "ring_views": 4, "zenith_view": False}
    spec = Spec.from_dict(d, "sensors.pol")
    assert spec.sensor_type == "imaging" and spec.cloud_windows == ((10.0, 20.0),)
    assert spec.claimed_sigma_rad() == pytest.approx(np.radians(0.5))
    assert Spec.from_dict(spec.to_dict(), "x") == spec
    assert Spec.from_dict({}, "x") == Spec()


@pytest.mark.parametrize("table, key", [
    ({"nose_deg": 0.3}, "sensors.pol.nose_deg"),
    ({"noise_deg": "0.3"}, "sensors.pol.noise_deg"),
    ({"noise_deg": -1}, "sensors.pol.noise_deg"),
    ({"type": "camera"}, "sensors.pol.type"),
    ({"student_t_dof": 1.5}, "sensors.pol.student_t_dof"),
    ({"dop_min": 0.8, "dop_max": 0.7}, "sensors.pol.dop_min"),
    ({"cloud_mean_clear_s": 10}, "sensors.pol.cloud_mean_cloudy_s"),
    ({"cloud_windows": [[20, 10]]}, "sensors.pol.cloud_windows[0]"),
    ({"misalignment_deg": [0, 0]}, "sensors.pol.misalignment_deg"),
    ({"type": "imaging", "ring_views": 1, "zenith_view": False}, "sensors.pol.ring_views"),
    ({"ring_zenith_deg": 85}, "sensors.pol.ring_zenith_deg"),
    ({"noise_deg": 0}, "sensors.pol.claimed_sigma_deg"),
    ({"kind": "gnss"}, "sensors.pol.kind"),
])
def test_from_dict_errors_name_the_key(table, key):
    with pytest.raises(InputFileError) as exc:
        Spec.from_dict(table, "sensors.pol")
    assert exc.value.where == key
    assert str(exc.value).startswith(key + ":")


def test_simulate_needs_a_start_time():
    with pytest.raises(InputFileError, match="start_utc"):
        Spec().simulate(_wobbly(1.0), np.random.default_rng(0), None)


def test_paper000_scenario_with_a_polarization_sensor(tmp_path):
    # through the scenario loader and the .npz cache: the sensor table, start_utc and meta
    from fuzzynav.sim.sensor_log import simulate
    from fuzzynav.sim.scenario import load_scenario, scenario_from_dict

    d = load_scenario("paper000").to_dict()
    d["sensors"]["pol"] = {"kind": "polarization", "rate_hz": 10.0, "noise_deg": 0.3}
    scenario = scenario_from_dict(d)
    log = simulate(scenario, seed=1, cache_dir=tmp_path)
    again = simulate(scenario, seed=1, cache_dir=tmp_path)
    pol = log.sensors["pol"]
    np.testing.assert_array_equal(again.sensors["pol"].z, pol.z)
    assert again.sensors["pol"].meta["sensor_type"] == 0
    truth = log.truth
    idx = np.round(pol.time_s * truth.imu_rate_hz).astype(int)
    err = []
    for i, k in enumerate(idx):
        p, r, h = truth.att[k]
        h_pol, _ = ps.heading_from_zenith_aop(pol.z[i, 0], pol.z[i, 1:4], p, r, h + 0.5)
        err.append((h_pol - h + np.pi) % (2 * np.pi) - np.pi)
    err = np.degrees(err)
    # level most of the time and a 45-deg sun: heading error ~ AoP error (0.3 deg)
    n = err.size
    assert n > 0.95 * truth.duration_s * 10
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], n - 1)
    s2 = err.var(ddof=1)
    assert (n - 1) * s2 / hi < 0.305**2 and 0.295**2 < (n - 1) * s2 / lo
