"""DVL simulation: the error-free velocity, the contaminated mixture, dropouts, TOML errors."""
import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.nav import attitude
from fuzzynav.sim.sensors.dvl import Spec
from fuzzynav.sim.trajectory import Segment, generate

START = np.array([np.deg2rad(30.5), np.deg2rad(114.4), 20.0])


@pytest.fixture(scope="module")
def truth():
    segs = [Segment("accelerate", 10, speed_change_mps=2.0), Segment("turn", 40, turn_deg=180),
            Segment("cruise", 400)]
    return generate(START, segs, 50.0, 0.0, 0.0)


def test_error_free_velocity_is_the_body_velocity(truth):
    spec = Spec(rate_hz=1.0, sigma_mps=1e-9)
    d = spec.simulate(truth, np.random.default_rng(0))
    idx = np.round(d.time_s * truth.imu_rate_hz).astype(int)
    C_bn = attitude.quat_to_dcm(truth.q_bn[idx])
    v_b = np.stack([C.T @ v for C, v in zip(C_bn, truth.vel_n[idx])])
    np.testing.assert_allclose(d.z, v_b, atol=1e-6)
    # a boat going straight: forward speed, no sideslip (body RFU: y forward)
    assert np.allclose(d.z[-5:, 1], 2.0, atol=1e-6) and np.allclose(d.z[-5:, 0], 0.0, atol=1e-6)


def test_scale_factor_misalignment_and_lever_arm(truth):
    spec = Spec(rate_hz=1.0, sigma_mps=1e-9, scale_factor=0.003,
                misalignment_deg=(0.0, 0.0, 1.0), lever_arm_b_m=(0.0, 2.0, 0.0))
    d = spec.simulate(truth, np.random.default_rng(0))
    straight = d.time_s > 60
    # (1 + k) times the forward speed; a small yaw misalignment mu (first order, as the
    # model's I - [mu x]) leaks mu * v into x
    np.testing.assert_allclose(d.z[straight, 1], 2.0 * 1.003, rtol=1e-6)
    np.testing.assert_allclose(d.z[straight, 0], 2.0 * 1.003 * np.deg2rad(1.0), rtol=1e-5)
    turning = (d.time_s >= 10) & (d.time_s <= 50)
    # turning right, a point 2 m ahead of the IMU swings right (+x) at 2 m x yaw rate:
    # over the whole 180-deg turn that integrates to 2 m x pi
    spec0 = Spec(rate_hz=1.0, sigma_mps=1e-9, scale_factor=0.003,
                 misalignment_deg=(0.0, 0.0, 1.0))
    d0 = spec0.simulate(truth, np.random.default_rng(0))
    lateral = (d.z[turning, 0] - d0.z[turning, 0]) / 1.003
    assert np.all(lateral > -1e-9)
    np.testing.assert_allclose(lateral.sum() * 1.0, 2.0 * np.pi, rtol=0.03)


def test_contaminated_mixture_and_dropouts(truth):
    clean = Spec(rate_hz=2.0, sigma_mps=1e-12).simulate(truth, np.random.default_rng(1)).z
    spec = Spec(rate_hz=2.0, sigma_mps=0.01, contamination=0.3, contamination_factor=100.0)
    d = spec.simulate(truth, np.random.default_rng(1))
    e = d.z - clean
    mask = d.meta["contaminated"]
    assert 0.2 < mask.mean() < 0.4
    np.testing.assert_allclose(np.std(e[~mask]), 0.01, rtol=0.15)
    np.testing.assert_allclose(np.std(e[mask]), 0.1, rtol=0.2)
    np.testing.assert_allclose(d.meta["true_sigma"][0], 0.01 * np.sqrt(0.7 + 0.3 * 100))
    spec = Spec(rate_hz=2.0, dropouts=((100.0, 160.0),), dropout_rate=0.05,
                dropout_duration_s=5.0)
    d = spec.simulate(truth, np.random.default_rng(2))
    assert not np.any((d.time_s >= 100.0) & (d.time_s < 160.0))
    assert d.time_s.size < 0.8 * 2 * truth.time_s[-1]


@pytest.mark.parametrize("key,value,where", [("contamination", 1.5, "contamination"),
                                             ("sigma_mps", 0.0, "sigma_mps"),
                                             ("misalignment_deg", [1, 2], "misalignment_deg"),
                                             ("bottom_lock", True, "bottom_lock")])
def test_bad_tables_name_the_key(key, value, where):
    with pytest.raises(InputFileError, match=where):
        Spec.from_dict({"kind": "dvl", key: value}, "sensors.dvl")
