"""Magnetometer measurement model: residual sign and Jacobians against finite differences."""
import numpy as np
import pytest

from fuzzynav.filters.measurements import default_rows, get
from fuzzynav.nav import attitude, strapdown
from fuzzynav.sim.sensors import SensorData
from tests.filters.test_measurements import ATT, LLA, VEL, _call, _numeric_H

FIELD_N = np.array([-2.9e-6, 29.1e-6, -45.8e-6])  # ENU [T], about the paper-001 place


def _data(heading, m_b, sig_h=np.deg2rad(0.5), sig_b=100e-9):
    z = np.array([[heading, *m_b]])
    sigma = np.array([[sig_h, sig_b, sig_b, sig_b]])
    return SensorData("magnetometer", np.zeros(1), z, sigma, {"field_n_t": FIELD_N})


@pytest.mark.parametrize("att", [ATT, np.array([0.0, 0.0, 3.0]), np.array([-0.3, 0.25, 5.5])])
def test_heading_residual_and_jacobian(att):
    model = get("magnetometer")
    nav = strapdown.make_nav(LLA, VEL, attitude.euler_to_quat(att))
    measured = att[2] - 0.02
    d = _data(measured, np.full(3, np.nan))
    par = model.pack(d, {})
    m, z, H, R, chan = _call(model, nav, default_rows(d)[0], par)
    assert m == 1 and model.channels[chan[0]] == "heading"
    # INS minus sensor, wrapped: the INS heading is the truth here
    assert z[0] == pytest.approx(0.02, abs=1e-12)
    assert R[0] == pytest.approx(np.deg2rad(0.5) ** 2, rel=1e-12)
    Hn = _numeric_H(model, nav, default_rows(d)[0], par, 1, [1e-6] * 9)
    np.testing.assert_allclose(H[:, :9], Hn, atol=1e-7)


def test_vector_residual_zero_at_truth_and_jacobian():
    model = get("magnetometer")
    nav = strapdown.make_nav(LLA, VEL, attitude.euler_to_quat(ATT))
    C = attitude.quat_to_dcm(nav[0:4])
    hard = np.array([1e-6, -2e-6, 0.5e-6])
    d = _data(0.0, C.T @ FIELD_N + hard)
    par = model.pack(d, {"mode": "vector", "hard_iron_t": hard})
    m, z, H, R, chan = _call(model, nav, default_rows(d)[0], par)
    assert m == 3 and set(model.channels[c] for c in chan) == {"field"}
    np.testing.assert_allclose(z, 0.0, atol=1e-15)  # 1e-10 of the field: rounding only
    Hn = _numeric_H(model, nav, default_rows(d)[0], par, 3, [1e-6] * 9)
    np.testing.assert_allclose(H[:, :9], Hn, atol=1e-11)  # field ~5e-5 T: 1e-6 relative
    assert np.abs(H[:, :3]).max() > 1e-5  # the attitude columns carry the field


def test_heading_only_data_gives_no_vector_rows():
    model = get("magnetometer")
    nav = strapdown.make_nav(LLA, VEL, attitude.euler_to_quat(ATT))
    d = _data(1.0, np.full(3, np.nan))
    par = model.pack(d, {"mode": "vector"})
    assert _call(model, nav, default_rows(d)[0], par)[0] == 0
