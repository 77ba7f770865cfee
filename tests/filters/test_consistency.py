"""The EKF is statistically consistent when its noise model is the truth (NEES, NIS)."""
import numpy as np
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
