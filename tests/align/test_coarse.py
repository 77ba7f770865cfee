"""Coarse alignment against the simulated truth and the closed-form bias limits."""
import numpy as np
import pytest

from fuzzynav import units
from fuzzynav.nav import coarse
from fuzzynav.align.simulate import Sway, simulate_alignment
from fuzzynav.nav import attitude, earth
from fuzzynav.sim.imu import ImuSpec

LAT = np.radians(45.0)
ATT0 = np.radians([0.5, -1.0, 30.0])
SWAY = Sway(amp_deg=(2.0, 3.0, 1.0), vel_amp_mps=(0.05, 0.05, 0.02), gust_sigma_mps=0.01)


def _log(spec, sway=Sway(), seed=1, duration=120.0):
    return simulate_alignment(spec, LAT, 0.0, ATT0, duration, np.random.default_rng(seed), sway)


def _err(result, log):
    return attitude.attitude_error(result.C_bn, log.C_bn[-1])


@pytest.mark.parametrize("method", [coarse.analytic, coarse.inertial_frame])
def test_noise_free_stationary_base_is_exact(method):
    log = _log(ImuSpec(rate_hz=50.0))
    r = method(log.imu, LAT, 0.0, 0.0, 120.0, np.zeros((3, 3)))
    assert np.max(np.abs(_err(r, log))) < 1e-9


@pytest.mark.parametrize("method", [coarse.analytic, coarse.inertial_frame])
def test_biases_give_the_closed_form_errors(method):
    # level phi_N = nabla_E/g, phi_E = -nabla_N/g; azimuth phi_U = -eps_E/(w cos L)
    # + tan L nabla_E/g, with nabla, eps the biases resolved in ENU (textbook limits)
    spec = ImuSpec(rate_hz=50.0, gyro_bias_dph=(0.02, -0.03, 0.01),
                   accel_bias_ug=(100.0, -80.0, 50.0))
    log = _log(spec)
    r = method(log.imu, LAT, 0.0, 0.0, 120.0, np.zeros((3, 3)))
    C = log.C_bn[-1]
    nab = C @ log.imu.accel_bias_mps2[0]
    eps = C @ log.imu.gyro_bias_rps[0]
    g = earth.gravity(LAT, 0.0)
    expected = [-nab[1] / g, nab[0] / g,
                -eps[0] / (earth.OMEGA_IE * np.cos(LAT)) + np.tan(LAT) * nab[0] / g]
    # tolerance: second-order terms and the earth-rate turn over the window, << 1 arcmin
    np.testing.assert_allclose(_err(r, log), expected, atol=0.05 * units.ARCMIN)


def test_inertial_frame_survives_sway_where_analytic_fails():
    log = _log(ImuSpec(rate_hz=100.0), SWAY)
    cov = np.zeros((3, 3))
    e_an = _err(coarse.analytic(log.imu, LAT, 0.0, 0.0, 120.0, cov), log)
    r = coarse.inertial_frame(log.imu, LAT, 0.0, 0.0, 120.0, cov)
    e_i0 = _err(r, log)
    assert np.max(np.abs(e_an)) > 20 * units.ARCMIN      # sway breaks the mean-value method
    # gusts wander the base by decimetres (a random walk): a few arcmin of azimuth
    assert np.max(np.abs(e_i0)) < 10 * units.ARCMIN
    # the misfit term of the returned azimuth sigma covers the error it reports
    assert abs(e_i0[2]) < 3 * r.sigma_phi[2]


def test_noisy_imu_errors_stay_within_the_stated_uncertainty():
    # paper 002's IMU with turn-on biases drawn per seed: normalised errors ~ N(0, 1)
    spec = ImuSpec(rate_hz=20.0, gyro_bias_sigma_dph=0.02, gyro_arw_dpsh=0.01 / 60.0,
                   accel_bias_sigma_ug=100.0, accel_vrw_ug_psqrthz=50.0)
    noise = spec.noise_si()
    cov = coarse.uncertainty(LAT, 60.0, noise.gyro.bias_sigma, noise.accel.bias_sigma,
                             noise.gyro.white, noise.accel.white)
    z = []
    for seed in range(12):
        log = _log(spec, seed=seed, duration=60.0)
        r = coarse.analytic(log.imu, LAT, 0.0, 0.0, 60.0, cov)
        z.append(_err(r, log) / r.sigma_phi)
    z = np.array(z)
    # 36 unit normals: the mean square lies in [0.4, 1.9] with probability > 0.999
    assert 0.4 < np.mean(z**2) < 1.9


def _numpy_chain(dtheta):
    """``C_b0_b`` by numpy quaternion products (the former numpy coarse alignment's chain,
    kept as the reference of the compiled :func:`coarse.body_chain`)."""
    q = np.empty((dtheta.shape[0] + 1, 4))
    q[0] = (1.0, 0.0, 0.0, 0.0)
    dq = attitude.rotvec_to_quat(dtheta)
    for k in range(dtheta.shape[0]):
        q[k + 1] = attitude.quat_normalize(attitude.quat_multiply(q[k], dq[k]))
    return attitude.quat_to_dcm(q)


def test_body_chain_of_a_constant_rate_is_the_rotation_by_its_angle():
    # increments about one fixed axis commute: after k of them C_b0_b = exp([k dtheta x])
    dtheta = np.tile([2e-3, -1e-3, 3e-3], (500, 1))
    C = attitude.quat_to_dcm(coarse.body_chain(dtheta))
    k = np.array([0, 1, 250, 500])
    np.testing.assert_allclose(C[k], attitude.rotvec_to_dcm(k[:, None] * dtheta[0]),
                               rtol=0, atol=1e-12)


def test_body_chain_matches_the_numpy_quaternion_products():
    dtheta = np.random.default_rng(3).normal(0.0, 5e-3, (2000, 3))
    got = attitude.quat_to_dcm(coarse.body_chain(dtheta))
    # the same products in another rounding order: 1e-15 apart after 2000 steps
    np.testing.assert_allclose(got, _numpy_chain(dtheta), rtol=0, atol=1e-13)
