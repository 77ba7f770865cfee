"""The alignment filters against theory: steady-state limits, unobservable states, NEES."""
import dataclasses

import numpy as np
import pytest
from scipy import stats

from fuzzynav import units
from fuzzynav.align import alignment_run as R
from fuzzynav.align.alignment_states import LAYOUT_10, NORTH
from fuzzynav.align.scenario import load_alignment_scenario
from fuzzynav.nav import earth
from fuzzynav.sim.imu import ImuSpec

PAPER = load_alignment_scenario("paper002")


def _scenario(**kw):
    return dataclasses.replace(PAPER, **kw)


def _run(scn, name="align-kf", seed=0):
    log = R.simulate(scn, seed)
    ep = R.epochs(scn, log, seed)
    return log, ep, R.run_align_filter(name, scn, log, ep)


def true_state(layout, log, ep) -> np.ndarray:
    """The true error state ``(K+1, n)`` of the open-loop solution (simulations only)."""
    step = (log.imu.time_s.size - 1) // (ep.time_s.size - 1)
    n_ep = ep.time_s.size
    truth = {"vel": ep.vel_err, "att": R.true_misalignment(log, ep),
             "accel_bias": log.imu.accel_bias_mps2[::step][:n_ep],
             "gyro_bias": log.imu.gyro_bias_rps[::step][:n_ep]}
    out = np.zeros((n_ep, layout.n))
    for name, size in layout.blocks:
        out[:, layout[name]] = truth[name][:, :size]
    return out


def nees(run, truth) -> np.ndarray:
    """Normalised estimation error squared at every epoch, (K+1,)."""
    e = truth - run.result.x
    return np.einsum("ki,ki->k", e, np.linalg.solve(run.result.P, e[..., None])[..., 0])


def _limits(log, lat):
    """Textbook steady-state alignment errors from the ENU-resolved biases."""
    C = log.C_bn[-1]
    nab = C @ log.imu.accel_bias_mps2[0]
    eps = C @ log.imu.gyro_bias_rps[0]
    g = earth.gravity(lat, 0.0)
    w_n = earth.omega_ie_n(lat)[NORTH]
    return np.array([-nab[1] / g, nab[0] / g, -eps[0] / w_n + np.tan(lat) * nab[0] / g])


@pytest.mark.parametrize("name, heading, gyro, accel", [
    ("align-kf", 0.0, (0.02, -0.03, 0.01), (0.0, 0.0, 0.0)),
    ("align-kf", 30.0, (0.02, -0.03, 0.01), (100.0, -80.0, 50.0)),
    ("align-kf12", 30.0, (0.02, -0.03, 0.01), (100.0, -80.0, 50.0)),
])
def test_steady_state_errors_reach_the_analytic_limits(name, heading, gyro, accel):
    # noise-free, small initial misalignment (the open-loop solution's second-order terms,
    # g phi^2 / 2, would act as an extra accelerometer bias), long enough to settle
    scn = _scenario(imu=ImuSpec(rate_hz=10.0, gyro_bias_dph=gyro, accel_bias_ug=accel),
                    meas_sigma_mps=0.0, att_deg=(0.0, 0.0, heading),
                    misalign_deg=(0.01, 0.01, 0.01), duration_s=1500.0)
    log, ep, out = _run(scn, name)
    expected = _limits(log, ep.lat_rad)
    assert np.max(np.abs(expected)) > 0.3 * units.ARCMIN       # the limits are not zero
    # tolerance 0.15 arcmin: the filter gives the unobservable biases ~1-2 % of each
    # unobservable combination (prior ratio) and has not fully settled after 1500 s
    np.testing.assert_allclose(out.error[-1], expected, atol=0.15 * units.ARCMIN)


def test_unobservable_states_keep_their_prior_variance():
    # base facing north, level: body x, y = east, north; theory: nabla_E, nabla_N, eps_E
    # are unobservable, eps_N is not (the velocity sees it through phi_N)
    log, ep, out = _run(_scenario(duration_s=400.0))
    P = out.result.P
    ratio = np.diagonal(P[-1]) / np.diagonal(P[0])
    lay = LAYOUT_10
    unobservable = [lay.index("accel_bias", 0), lay.index("accel_bias", 1),
                    lay.index("gyro_bias", 0)]
    # the filter hands them only the prior-ratio share of each combination (< 2 %)
    assert np.all(ratio[unobservable] > 0.97)
    assert ratio[lay.index("gyro_bias", 1)] < 0.5
    assert np.all(ratio[lay.att] < 0.1)


def test_nees_is_consistent_over_monte_carlo_seeds():
    # truth drawn from the filter's own prior: misalignment N(0, 0.1 deg) (the linear
    # regime), turn-on biases N(0, prior), white noises as Q and R say
    noise = dataclasses.replace(PAPER.noise, att_sigma_rad=0.1 * units.DEG)
    imu = ImuSpec(rate_hz=10.0, gyro_bias_sigma_dph=0.02, gyro_arw_dpsh=0.01 / 60.0,
                  accel_bias_sigma_ug=100.0, accel_vrw_ug_psqrthz=50.0)
    seeds = range(8)
    total = 0.0
    for seed in seeds:
        mis = 0.1 * np.random.default_rng(100 + seed).standard_normal(3)
        scn = _scenario(imu=imu, noise=noise, misalign_deg=tuple(mis), duration_s=200.0)
        log, ep, out = _run(scn, seed=seed)
        total += nees(out, true_state(LAYOUT_10, log, ep))[-1]
    dof = LAYOUT_10.n * len(seeds)
    # two-sided 99.8 % interval of a chi-square sum with n * seeds degrees of freedom
    assert stats.chi2.ppf(0.001, dof) < total < stats.chi2.ppf(0.999, dof)


def test_the_12_state_form_agrees_with_the_10_state_one_on_the_paper_case():
    log, ep, kf = _run(_scenario(duration_s=300.0))
    kf12 = R.run_align_filter("align-kf12", PAPER, log, ep)
    # the vertical channel adds nothing to the horizontal misalignment on a base at rest
    np.testing.assert_allclose(kf12.phi_hat[-1], kf.phi_hat[-1], atol=1.0 * units.ARCMIN)
