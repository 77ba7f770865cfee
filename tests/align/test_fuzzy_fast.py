"""Fuzzy R-scaling (paper 002's three rules) and the fast azimuth estimate."""
import dataclasses

import numpy as np
import pytest

from fuzzynav import units
from fuzzynav.align import alignment_run as R
from fuzzynav.errors import FuzzynavError
from fuzzynav.align.fine import DEFAULT_RULES, r_policy
from fuzzynav.align.alignment_states import UP
from fuzzynav.align.scenario import load_alignment_scenario
from fuzzynav.filters.adaptation.epoch import EpochPolicy
from fuzzynav.filters.adaptation.r_scaling import FuzzyRScaling
from fuzzynav.filters.catalog import find_rule_file
from fuzzynav.fuzzy import load_fis
from fuzzynav.sim.imu import ImuSpec


def _rules(window):
    fis = load_fis(find_rule_file(DEFAULT_RULES))
    return dataclasses.replace(fis, binding={**fis.binding, "window": window})


def _factor_at(ror, window=4):
    """The factor t when the measured innovations are exactly ``ror`` times ``D``
    (``H P- H^T = 0``, ``R0 = I``: ``D = R``)."""
    pol = EpochPolicy(r_policy(_rules(window)), ("vel", "vel"))
    r = np.sqrt(ror) * np.array([1.0, 1.0])      # r r^T has trace 2 ror = ror tr D
    for _ in range(window - 1):
        assert pol.step(r, np.zeros((2, 2)), np.eye(2)).diag["t"] == 1.0  # window filling
    step = pol.step(r, np.zeros((2, 2)), np.eye(2))
    return step.diag["t"], step.diag["ror"]


def test_a_consistent_filter_keeps_R_and_a_mismatched_one_moves_it_the_right_way():
    t1, ror = _factor_at(1.0)
    assert abs(ror - 1.0) < 1e-12
    assert abs(t1 - 1.0) < 1e-9                 # the rule file's equal1 is centred on 1
    t_hi, _ = _factor_at(2.5)
    t_lo, _ = _factor_at(0.2)
    assert t_hi > 1.1 and t_lo < 0.9


def test_the_scale_of_R_stays_within_its_bounds():
    fis = _rules(2)
    pol = EpochPolicy(FuzzyRScaling(fis, scale_bounds=(1e-2, 3.0), full_window=True),
                      ("vel", "vel"))
    for _ in range(50):
        step = pol.step(np.array([10.0, 10.0]), np.zeros((2, 2)), np.eye(2))
    np.testing.assert_array_equal(step.r_scale, [3.0, 3.0])
    np.testing.assert_array_equal(step.R, 3.0 * np.eye(2))


def test_the_alignment_refuses_a_rule_file_reading_motion_context():
    fis = _rules(4)
    name = fis.inputs[0].name
    binding = {**fis.binding, "inputs": {name: {"statistic": "speed"}}}
    with pytest.raises(FuzzynavError, match="speed"):
        r_policy(dataclasses.replace(fis, binding=binding))


def test_fuzzy_scaling_learns_a_reference_noisier_than_R0():
    scn = load_alignment_scenario("paper002-rmismatch")
    scn = dataclasses.replace(scn, duration_s=300.0, imu=dataclasses.replace(scn.imu,
                                                                             rate_hz=10.0))
    log = R.simulate(scn, 0)
    ep = R.epochs(scn, log, 0)
    out = R.run_align_filter("align-fuzzy", scn, log, ep)
    # the reference is 4x noisier than R0 says (variance x16) outside 100..200 s
    late = out.result.r_scale[-50:]
    assert 4.0 < np.median(late) < 64.0
    assert 0.3 < np.nanmean(out.result.ror[-50:]) < 3.0


def test_fast_azimuth_beats_the_filter_early_on_noise_free_data():
    scn = dataclasses.replace(load_alignment_scenario("paper002"), imu=ImuSpec(rate_hz=10.0),
                              meas_sigma_mps=0.0, duration_s=120.0)
    log = R.simulate(scn, 0)
    ep = R.epochs(scn, log, 0)
    kf = R.run_align_filter("align-kf", scn, log, ep)
    fast = R.run_align_filter("align-kf-fast", scn, log, ep)
    k = 60                                       # 10 s after the first fit window
    assert abs(kf.error[k, UP]) > 30 * units.ARCMIN
    assert abs(fast.error[k, UP]) < 2 * units.ARCMIN
    # level estimates are the filter's own, untouched
    np.testing.assert_allclose(fast.phi_hat[:, :UP], kf.phi_hat[:, :UP])


def test_fast_azimuth_falls_back_to_the_filter_on_noisy_data():
    scn = dataclasses.replace(load_alignment_scenario("paper002"), duration_s=120.0)
    log = R.simulate(scn, 1)
    ep = R.epochs(scn, log, 1)
    kf = R.run_align_filter("align-kf", scn, log, ep)
    fast = R.run_align_filter("align-kf-fast", scn, log, ep)
    # 0.05 m/s reference noise: the 20-s fit's sigma exceeds the filter's, so it is not used
    np.testing.assert_allclose(fast.phi_hat, kf.phi_hat)
