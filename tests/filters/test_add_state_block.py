"""The worked example of docs/architecture.md, "Adding a state block", as a test.

A block that nothing drives and no measurement sees must leave the filter as it was: its
estimate stays zero, its variance follows its own closed form, and the navigation solution
equals the one without it.
"""
import math

import numpy as np
import pytest

from fuzzynav.filters.error_model import ErrorModel, fill_F
from fuzzynav.filters.layout import COUPLE_NONE, register_block
from fuzzynav.filters.runner import run_filter
from fuzzynav.nav import attitude, strapdown
from fuzzynav.nav.state_layout import Q_SLICE
from tests.filters.simple_data import CONFIG, run_inputs, trajectory

# a sensor module would do this at import: a 1-state odometer scale factor
register_block("test_odo_scale", 1, COUPLE_NONE)

MODEL = ErrorModel(extra=(("mag_bias", math.inf), ("test_odo_scale", 100.0)))
ODO_SIGMA, ODO_TAU = 0.01, 100.0
CFG = CONFIG.with_(model=MODEL, extra_noise_si=((1e-6, 0.0),
                                                (ODO_SIGMA, 2 * ODO_SIGMA**2 / ODO_TAU)))


@pytest.fixture(scope="module")
def runs():
    tr = trajectory(1)
    imu, gnss, init, _, _ = run_inputs(tr, 5)
    return (run_filter(imu, {"gnss": gnss}, init, CONFIG),
            run_filter(imu, {"gnss": gnss}, init, CFG))


def test_the_layout_and_the_noise_grow_by_the_new_blocks():
    lay = MODEL.layout
    assert lay.n == 19 and lay.mag_bias == slice(15, 18) and lay["test_odo_scale"] == slice(18, 19)
    assert CFG.P0().shape == (19, 19) and CFG.q_diag().shape == (19,)
    assert lay.labels()[15:] == ("mag_bias_x", "mag_bias_y", "mag_bias_z", "test_odo_scale")


def test_F_of_an_uncoupled_block_is_its_own_decay_only():
    nav = strapdown.make_nav(np.array([0.7, 0.3, 100.0]), np.array([10.0, 2.0, 0.1]),
                             attitude.euler_to_quat(np.radians([2.0, -1.0, 30.0])))
    C, f = attitude.quat_to_dcm(nav[Q_SLICE]), np.array([0.2, 0.1, 9.8])
    F15, F = np.zeros((15, 15)), np.zeros((19, 19))
    fill_F(F15, nav, C, f, *ErrorModel().block_arrays())
    fill_F(F, nav, C, f, *MODEL.block_arrays())
    lay = MODEL.layout
    np.testing.assert_allclose(F[:15, :15], F15, rtol=1e-15, atol=0)
    odo = lay["test_odo_scale"].start
    expected = np.zeros((4, 19))
    expected[3, odo] = -1.0 / ODO_TAU
    np.testing.assert_allclose(F[15:], expected, rtol=1e-15, atol=0)
    np.testing.assert_allclose(F[:, 15:][:15], 0.0, atol=0)


def test_an_unobserved_block_stays_zero_and_leaves_the_solution_alone(runs):
    base, ext = runs
    assert base.ok and ext.ok
    lay = MODEL.layout
    np.testing.assert_allclose(ext.sensor_states[:, lay.sensor_slice("mag_bias")], 0.0, atol=1e-15)
    np.testing.assert_allclose(ext.sensor_states[:, lay.sensor_slice("test_odo_scale")], 0.0,
                               atol=1e-15)
    # zero-noise random constant: its sigma never changes; a Gauss-Markov block started at its
    # steady-state sigma stays there (dP/dt = -2P/tau + 2 sigma^2/tau = 0)
    np.testing.assert_allclose(ext.state_sigma("mag_bias"), 1e-6, rtol=1e-12)
    np.testing.assert_allclose(ext.state_sigma("test_odo_scale"), ODO_SIGMA, rtol=1e-3)
    np.testing.assert_allclose(ext.lla[:, :2], base.lla[:, :2], rtol=0, atol=1e-13)
    np.testing.assert_allclose(ext.lla[:, 2], base.lla[:, 2], rtol=0, atol=1e-6)
    np.testing.assert_allclose(ext.sigma[:, :15], base.sigma, rtol=1e-9)
