"""The EKF is statistically consistent when its noise model is the truth (NEES, NIS)."""
import numpy as np
import pytest
from scipy.stats import chi2

from fuzzynav.filters.runner import run_filter
from tests.filters.simple_data import CONFIG, run_inputs, state_errors, trajectory

RUNS = 16


def test_nees_and_nis_are_consistent():
    tr = trajectory(1)
    nees, nis, dof_nis = [], [], []
    for seed in range(RUNS):
        imu, gnss, init, bg, ba = run_inputs(tr, seed)
        res = run_filter(imu, {"gnss": gnss}, init, CONFIG)
        assert res.ok
        err = state_errors(res, tr, bg, ba)[::20]   # every 2 s: weakly correlated samples
        nees.append(((err / res.sigma[::20]) ** 2))
        ev = res.events["gnss"]
        nis.append(ev.nis[ev.accepted])
    nees = np.array(nees)                           # runs x epochs x 15
    # per state, averaged over runs and epochs: 1 for a consistent filter
    per_state = nees.mean(axis=(0, 1))
    assert np.all(per_state > 0.6) and np.all(per_state < 1.5), per_state
    # the run-averaged NEES of the 15 states at each epoch, within 99.9 % chi-square bounds
    # widened for time correlation (a filter with a wrong sign fails by orders of magnitude)
    total = nees.sum(axis=2).mean(axis=0)
    lo, hi = chi2.ppf([0.0005, 0.9995], 15 * RUNS) / RUNS
    frac_inside = np.mean((total > lo * 0.8) & (total < hi * 1.2))
    assert frac_inside > 0.9, frac_inside
    nis = np.concatenate(nis)
    lo, hi = chi2.ppf([0.001, 0.999], 6 * nis.size) / nis.size
    assert lo * 0.95 < nis.mean() < hi * 1.05, nis.mean()


def test_propagation_interval_does_not_change_the_solution():
    tr = trajectory(1)
    imu, gnss, init, bg, ba = run_inputs(tr, 3)
    a = run_filter(imu, {"gnss": gnss}, init, CONFIG.with_(max_prop_dt_s=1.0))
    b = run_filter(imu, {"gnss": gnss}, init, CONFIG.with_(max_prop_dt_s=0.01))
    ea, eb = state_errors(a, tr, bg, ba), state_errors(b, tr, bg, ba)
    rms_a, rms_b = np.sqrt((ea ** 2).mean(0)), np.sqrt((eb ** 2).mean(0))
    np.testing.assert_allclose(rms_a[:9], rms_b[:9], rtol=0.01)


def test_paper000_system_with_compass_is_consistent(sim_cache):
    """GPS + imaging polarization + the scenario's tactical IMU (Gauss-Markov biases that the
    15-state filter models as random walks): per-state NEES near 1, NIS near each dof."""
    from fuzzynav.experiment import run_on_log
    from fuzzynav.metrics import _enu_difference
    from fuzzynav.nav import attitude
    from fuzzynav.sim.sensor_log import simulate
    from fuzzynav.sim.scenario import load_scenario

    scn = load_scenario("paper000-nominal")
    nees, nis = [], {"gps": [], "pol": []}
    for seed in range(6):
        log = simulate(scn, seed, sim_cache)
        res = run_on_log(log, "ekf").result
        tr = log.truth
        k = np.searchsorted(tr.time_s, res.time_s - 1e-9)
        phi = attitude.attitude_error(attitude.quat_to_dcm(res.q_bn),
                                      attitude.quat_to_dcm(tr.q_bn[k]))
        err = np.hstack([phi, res.vel_n - tr.vel_n[k], _enu_difference(res.lla, tr.lla[k])])
        nees.append(((err / res.sigma[:, :9]) ** 2)[::20])
        for name, ev in res.events.items():
            nis[name].append(ev.nis[ev.accepted])
    per_state = np.array(nees).mean(axis=(0, 1))
    assert np.all(per_state > 0.6) and np.all(per_state < 1.6), per_state
    assert 5.4 < np.concatenate(nis["gps"]).mean() < 6.6       # 6 rows per GPS epoch
    nis_pol = np.concatenate(nis["pol"]).mean()
    assert nis_pol > 1.8 and nis_pol < 2.2                     # pitch + heading rows


def test_oracle_equals_ekf_without_mismatch(sim_cache):
    from fuzzynav.experiment import monte_carlo

    df = monte_carlo("paper000-nominal", ["ekf", "ekf-true"], [0], cache_dir=sim_cache)
    a, b = df[df["filter"] == "ekf"].iloc[0], df[df["filter"] == "ekf-true"].iloc[0]
    # two configurations: R from the claimed sigma and R from the simulator's true-sigma
    # formula, equal here up to rounding; an ulp in R moves an RMS over a whole run by orders
    # of magnitude less than 1e-12 (relative), a wrong R moves it by percent
    for key in ("rms_pos_m", "rms_vel_mps", "rms_att_deg"):
        assert a[key] == pytest.approx(b[key], rel=1e-12, abs=0.0)
