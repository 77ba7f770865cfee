"""IMU error model: units, white noise, biases, scale factor, misalignment, streams."""
import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats

from fuzzynav.errors import InputFileError
from fuzzynav.sim.imu import ImuSpec

ALPHA = 1e-6
DEG = math.pi / 180.0


def chi2_ok(sample_var, true_var, dof):
    lo, hi = stats.chi2.ppf([ALPHA / 2, 1 - ALPHA / 2], dof) / dof
    return lo * true_var <= sample_var <= hi * true_var


def ideal(n, rate_hz=100.0, rng=None, scale=0.0):
    """Ideal increments: zero, or random ones of size ``scale`` (an IMU at rest / moving)."""
    t = np.arange(n + 1) / rate_hz
    if rng is None:
        z = np.zeros((n, 3))
        return SimpleNamespace(time_s=t, dtheta_b=z, dv_b=z.copy())
    return SimpleNamespace(time_s=t, dtheta_b=scale * rng.standard_normal((n, 3)),
                           dv_b=scale * rng.standard_normal((n, 3)))


def test_datasheet_units_convert_to_si():
    noise = ImuSpec(gyro_arw_dpsh=0.1, accel_vrw_ug_psqrthz=50.0, gyro_bias_dph=(1, 2, 3),
                    gyro_rrw_dph_psh=1.0, accel_rrw_ug_psh=60.0, gyro_bi_sigma_dph=0.3,
                    accel_bias_ug=(100, 0, 0), gyro_sf_ppm=(10, 0, 0)).noise_si()
    # by hand: deg/sqrt(h) = (pi/180) rad / sqrt(3600 s)
    assert noise.arw_rad_psqrts == pytest.approx(0.1 * DEG / 60.0, rel=1e-15)
    assert noise.vrw_mps_psqrts == pytest.approx(50e-6 * 9.80665, rel=1e-15)
    assert noise.gyro.bias[2] == pytest.approx(3 * DEG / 3600.0, rel=1e-15)
    assert noise.gyro.rrw == pytest.approx(DEG / 3600.0 / 60.0, rel=1e-15)
    assert noise.accel.rrw == pytest.approx(1e-6 * 9.80665, rel=1e-15)
    assert noise.gyro.gm_sigma == pytest.approx(0.3 * DEG / 3600.0, rel=1e-15)
    assert noise.accel.bias[0] == pytest.approx(100e-6 * 9.80665, rel=1e-15)
    assert noise.gyro.matrix[0, 0] == pytest.approx(1.00001, rel=1e-15)


@pytest.mark.parametrize("rate_hz", [50.0, 100.0, 200.0])
def test_white_noise_variance_is_density_squared_times_dt(rate_hz):
    n = 60000
    spec = ImuSpec(rate_hz=rate_hz, gyro_arw_dpsh=0.2, accel_vrw_ug_psqrthz=80.0)
    out = spec.corrupt(ideal(n, rate_hz), np.random.default_rng(5))
    dt = 1.0 / rate_hz
    si = spec.noise_si()
    for inc, dens in ((out.dtheta_b, si.arw_rad_psqrts), (out.dv_b, si.vrw_mps_psqrts)):
        for axis in range(3):
            assert chi2_ok(np.mean(inc[:, axis] ** 2), dens**2 * dt, n)
        # white: neighbouring increments uncorrelated (|r| < 5/sqrt(n))
        r = np.corrcoef(inc[:-1, 0], inc[1:, 0])[0, 1]
        assert abs(r) < 5.0 / math.sqrt(n)


def test_fixed_bias_gives_bias_times_dt_in_every_increment():
    spec = ImuSpec(gyro_bias_dph=(1.0, -2.0, 3.0), accel_bias_ug=(100.0, 0.0, -50.0))
    out = spec.corrupt(ideal(1000), np.random.default_rng(0))
    np.testing.assert_allclose(out.dtheta_b, np.tile(np.array([1, -2, 3]) * DEG / 3600 * 0.01,
                                                     (1000, 1)), rtol=1e-12)
    np.testing.assert_allclose(out.dv_b[:, 2], -50e-6 * 9.80665 * 0.01, rtol=1e-12)
    np.testing.assert_allclose(out.gyro_bias_rps[0], np.array([1, -2, 3]) * DEG / 3600)


def test_turn_on_bias_spread_and_its_truth():
    spec = ImuSpec(gyro_bias_sigma_dph=5.0, accel_bias_sigma_ug=200.0)
    ons = []
    for seed in range(3000):
        out = spec.corrupt(ideal(4), np.random.default_rng(seed))
        on = out.meta["gyro_turn_on_rps"]
        np.testing.assert_allclose(out.dtheta_b, np.tile(on * 0.01, (4, 1)), rtol=1e-12)
        ons.append(np.concatenate([on, out.meta["accel_turn_on_mps2"]]))
    ons = np.array(ons)
    for axis in range(3):
        assert chi2_ok(np.mean(ons[:, axis] ** 2), (5.0 * DEG / 3600) ** 2, len(ons))
        assert chi2_ok(np.mean(ons[:, 3 + axis] ** 2), (200e-6 * 9.80665) ** 2, len(ons))


def test_scale_factor_and_misalignment_act_as_the_matrix_says():
    mis = ((0.0, 0.1, -0.2), (0.05, 0.0, 0.3), (-0.1, 0.2, 0.0))
    spec = ImuSpec(gyro_sf_ppm=(100.0, -200.0, 300.0), gyro_misalign_deg=mis,
                   accel_sf_ppm=(1000.0, 0.0, 0.0), accel_misalign_deg=mis)
    rng = np.random.default_rng(6)
    src = ideal(500, rng=rng, scale=0.01)
    out = spec.corrupt(src, rng)
    m = np.array(mis) * DEG
    gyro_m = np.eye(3) + np.diag([100e-6, -200e-6, 300e-6]) + m
    accel_m = np.eye(3) + np.diag([1000e-6, 0.0, 0.0]) + m
    np.testing.assert_allclose(out.dtheta_b, src.dtheta_b @ gyro_m.T, rtol=1e-13, atol=1e-18)
    np.testing.assert_allclose(out.dv_b, src.dv_b @ accel_m.T, rtol=1e-13, atol=1e-18)
    # a pure rotation about x shows up on y and z through M[1,0], M[2,0]
    x_only = SimpleNamespace(time_s=np.arange(2) / 100.0, dtheta_b=np.array([[1e-3, 0, 0]]),
                             dv_b=np.zeros((1, 3)))
    y = spec.corrupt(x_only, rng).dtheta_b[0]
    np.testing.assert_allclose(y / 1e-3, [1 + 100e-6, 0.05 * DEG, -0.1 * DEG], rtol=1e-12)


def test_bias_instability_increments_and_truth_series_agree():
    sigma_dph, tau, n = 10.0, 5.0, 200000
    spec = ImuSpec(gyro_bi_sigma_dph=sigma_dph, gyro_bi_tau_s=tau)
    out = spec.corrupt(ideal(n), np.random.default_rng(7))
    s = sigma_dph * DEG / 3600
    dt = 0.01
    # stationary variance of the bias series (effective dof: n * dt / (2 tau) independent)
    dof = n * dt / (2 * tau)
    assert chi2_ok(np.mean(out.gyro_bias_rps[:, 0] ** 2), s**2, dof)
    # the increments integrate the same bias as the truth series: their running sums agree
    # to the trapezoid error of each step, q^2 dt^3 / 12 per step
    cum_inc = np.cumsum(out.dtheta_b[:, 1])
    b = out.gyro_bias_rps[:, 1]
    cum_trap = np.cumsum(0.5 * (b[:-1] + b[1:]) * dt)
    q2 = 2 * s**2 / tau
    assert np.max(np.abs(cum_inc - cum_trap)) < 6 * np.sqrt(n * q2 * dt**3 / 12)
    # lag-tau autocorrelation of the truth series is 1/e
    lag = int(tau / dt)
    b0 = out.gyro_bias_rps[:, 2]
    rho = np.sum(b0[:-lag] * b0[lag:]) / np.sum(b0[:-lag] ** 2)
    assert abs(rho - np.exp(-1)) < 0.2  # one series of 400 tau: a coarse check


def test_rate_random_walk_grows_as_sqrt_t():
    spec = ImuSpec(gyro_rrw_dph_psh=100.0)
    finals = np.array([spec.corrupt(ideal(100), np.random.default_rng(s)).gyro_bias_rps[-1]
                       for s in range(2000)])
    k = 100 * DEG / 3600 / 60
    assert chi2_ok(np.mean(finals**2), k**2 * 1.0, finals.size)


def test_each_error_term_has_its_own_random_stream():
    base = ImuSpec(gyro_arw_dpsh=0.1, accel_vrw_ug_psqrthz=50.0)
    more = ImuSpec(gyro_arw_dpsh=0.1, accel_vrw_ug_psqrthz=50.0, gyro_bias_sigma_dph=3.0,
                   accel_bi_sigma_ug=30.0, accel_bi_tau_s=100.0)
    a = base.corrupt(ideal(1000), np.random.default_rng(9))
    b = more.corrupt(ideal(1000), np.random.default_rng(9))
    # gyro: only the turn-on bias differs; accelerometer: only the Gauss-Markov integral
    np.testing.assert_allclose(b.dtheta_b - a.dtheta_b,
                               np.tile(b.meta["gyro_turn_on_rps"] * 0.01, (1000, 1)),
                               rtol=1e-9, atol=1e-20)
    diff = b.dv_b - a.dv_b
    assert np.std(diff) < 0.05 * 50e-6 * 9.80665 * 0.1  # far below the white noise


@pytest.mark.parametrize("table, where, what", [
    ({"gyro_arw": 0.1}, "imu.gyro_arw", "unknown key"),
    ({"gyro_arw_dpsh": "low"}, "imu.gyro_arw_dpsh", "must be a number"),
    ({"gyro_arw_dpsh": -1.0}, "imu.gyro_arw_dpsh", "must lie in"),
    ({"gyro_bi_tau_s": 0.0}, "imu.gyro_bi_tau_s", "must lie in"),
    ({"gyro_bias_dph": [1.0, 2.0]}, "imu.gyro_bias_dph", "array of 3"),
    ({"accel_misalign_deg": [[1, 0, 0], [0, 0, 0], [0, 0, 0]]}, "imu.accel_misalign_deg",
     "diagonal"),
    ({"rate_hz": 0}, "imu.rate_hz", "must lie in"),
])
def test_bad_imu_tables_name_the_key(table, where, what):
    with pytest.raises(InputFileError) as exc:
        ImuSpec.from_dict(table)
    assert exc.value.where == where and what in exc.value.what


def test_imu_table_round_trip():
    spec = ImuSpec(rate_hz=200.0, gyro_bias_dph=(1, 2, 3), accel_misalign_deg=(
        (0, 0.1, 0), (0, 0, 0), (0.2, 0, 0)), accel_bias_sigma_ug=3.0)
    assert ImuSpec.from_dict(spec.to_dict()) == spec
