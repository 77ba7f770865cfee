"""Runner features: chi-square gating, the 18-state Gauss-Markov model, outputs, errors."""
import math
from dataclasses import replace

import numpy as np
import pytest

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters.error_model import ErrorModel
from fuzzynav.filters.runner import run_filter
from tests.filters.simple_data import CONFIG, run_inputs, state_errors, trajectory


@pytest.fixture(scope="module")
def data():
    tr = trajectory(1)
    return (tr,) + run_inputs(tr, 11)


def test_gate_rejects_an_outlier_and_only_it(data):
    tr, imu, gnss, init, bg, ba = data
    z = gnss.z.copy()
    z[200, 2] += 80.0  # an 80-m height outlier
    bad = replace(gnss, z=z)
    plain = run_filter(imu, {"gnss": bad}, init, CONFIG)
    gated = run_filter(imu, {"gnss": bad}, init, CONFIG.with_(gate_probability=0.9999))
    flags = gated.events["gnss"].flag
    assert flags[200] == 2 and np.sum(flags == 2) <= 3
    assert plain.events["gnss"].flag[200] == 1
    k = np.searchsorted(gated.time_s, gnss.time_s[200] + 0.5)
    up_plain = abs(state_errors(plain, tr, bg, ba)[k, 8])
    up_gated = abs(state_errors(gated, tr, bg, ba)[k, 8])
    assert up_plain > 1.5 and up_gated < 0.5 * up_plain  # the outlier pulled only the ungated one


def test_eighteen_state_model_with_gauss_markov_blocks(data):
    tr, imu, gnss, init, bg, ba = data
    model = ErrorModel(gyro_tau_s=(math.inf, 600.0), accel_tau_s=(1200.0,))
    cfg = CONFIG.with_(model=model, gyro_sigma_dph=(20.0, 5.0), accel_sigma_ug=(500.0,),
                       gyro_rw_dph_psh=(0.0, 0.0), accel_rw_ug_psqrts=(0.0,))
    res = run_filter(imu, {"gnss": gnss}, init, cfg)
    assert res.ok and res.sensor_states.shape[1] == 9 and res.sigma.shape[1] == 18
    assert len(res.state_labels) == 18
    # the total gyro bias is the sum of its two blocks and still finds the true bias
    np.testing.assert_allclose(res.gyro_bias[-1], bg, atol=np.sqrt(cfg.P0()[9, 9]) * 0.5)


def test_outputs_follow_the_requested_rate(data):
    tr, imu, gnss, init, bg, ba = data
    res = run_filter(imu, {"gnss": gnss}, init, CONFIG.with_(out_rate_hz=2.0))
    assert np.allclose(np.diff(res.time_s), 0.5)
    assert res.time_s[0] == tr.time_s[0]


def test_bad_imu_arrays_are_one_clear_error(data):
    tr, imu, gnss, init, bg, ba = data
    from types import SimpleNamespace

    short = SimpleNamespace(time_s=imu.time_s[:-2], dtheta_b=imu.dtheta_b, dv_b=imu.dv_b)
    with pytest.raises(FuzzynavError, match="IMU arrays disagree"):
        run_filter(short, {"gnss": gnss}, init, CONFIG)
