"""The DVL measurement model: Jacobians against finite differences of the model itself,
taken through the loop's own closed-loop feedback (so the sign conventions of the core and of
the sensor states are checked together), and a filter run in both error models."""
import math

import numpy as np
import pytest

from fuzzynav.filters.feedback import feedback
from fuzzynav.filters.layout import N_CORE
from fuzzynav.filters.measurements import dvl
from fuzzynav.filters.sensor_states import with_sensor_states
from fuzzynav.filters.named import FilterSetup
from fuzzynav.filters.config import FilterConfig
from fuzzynav.nav import attitude
from fuzzynav.nav.state_layout import PREV_SIZE
from fuzzynav.nav.strapdown import init_prev, make_nav, quat_to_dcm_into
from fuzzynav.sim.sensors import SensorData


def _stream(n=3):
    t = np.arange(n, dtype=float)
    return SensorData("dvl", t, np.zeros((n, 3)), np.full((n, 3), 0.02),
                      {"lever_arm_b": np.array([0.3, 1.8, -0.4])})


def _setup(lever_state=True):
    opts = {"dvl_lever_arm_sigma_m": 0.5} if lever_state else {}
    return with_sensor_states(FilterSetup(FilterConfig()), {"dvl": _stream()}, opts)


def _residual(nav, xs, row, par, w):
    C = np.zeros((3, 3))
    quat_to_dcm_into(nav, C)
    aux = np.concatenate([w, [0.1, 0.2, 9.8], xs])
    n = N_CORE + xs.size
    z, H, R, chan = np.zeros(3), np.zeros((3, n)), np.zeros(3), np.zeros(3, np.int64)
    m = dvl.dvl_kernel(nav, C, aux, row, par, 0.0, z, H, R, chan)
    return m, z, H


def _after_feedback(nav, xs, x):
    nav, xs = nav.copy(), xs.copy()
    prev = np.zeros(PREV_SIZE)
    init_prev(nav, prev)
    feedback(nav, prev, xs, x)
    return nav, xs


def test_layout_gets_the_dvl_blocks_and_the_model_their_starts():
    setup = _setup()
    lay = setup.config.model.layout
    starts = setup.sensor_options["dvl"]["state_start"]
    assert starts == {b: lay.start(b) for b in ("dvl_scale", "dvl_misalignment", "lever_arm")}
    assert lay.n == 15 + 1 + 3 + 3
    off = with_sensor_states(FilterSetup(FilterConfig()), {"dvl": _stream()},
                            {"sensor_states": False})
    assert off.config.model.layout.n == 15


@pytest.mark.parametrize("seed", [0, 1])
def test_jacobian_matches_finite_differences_through_the_feedback(seed):
    rng = np.random.default_rng(seed)
    setup = _setup()
    n = setup.config.model.layout.n
    q = attitude.euler_to_quat(np.array([rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3),
                                         rng.uniform(-3, 3)]))
    nav = make_nav(np.array([0.57, 0.61, -20.0]), rng.normal(0, 1.5, 3), q)
    xs = np.zeros(n - N_CORE)
    xs[-7:] = np.r_[0.003, rng.normal(0, 0.01, 3), 0.3, 1.8, -0.4]  # k, mu, lever
    row = np.r_[rng.normal(0, 1, 3), 0.02, 0.02, 0.02]
    par = dvl.pack(_stream(), setup.sensor_options["dvl"])
    w = rng.normal(0, 0.1, 3)
    m, z0, H = _residual(nav, xs, row, par, w)
    assert m == 3
    for j in range(n):
        eps = 1e-6
        x = np.zeros(n)
        x[j] = eps
        zp = _residual(*_after_feedback(nav, xs, x), row, par, w)[1]
        zm = _residual(*_after_feedback(nav, xs, -x), row, par, w)[1]
        # feedback of x removes H x from the residual: z(+x) = z - H x
        num = (zm - zp) / (2 * eps)
        np.testing.assert_allclose(H[:, j], num, atol=2e-5 * max(1.0, np.abs(num).max()),
                                   err_msg=f"column {j} ({setup.config.model.layout.labels()[j]})")


def test_missing_axes_are_skipped():
    setup = _setup(False)
    n = setup.config.model.layout.n
    nav = make_nav(np.array([0.57, 0.61, -20.0]), np.array([1.0, 0.5, 0.0]),
                   attitude.euler_to_quat(np.array([0.0, 0.0, 0.5])))
    row = np.array([0.0, math.nan, 0.0, 0.02, 0.02, 0.0])  # y missing, z without sigma
    par = dvl.pack(_stream(), setup.sensor_options["dvl"])
    m, z, H = _residual(nav, np.zeros(n - N_CORE), row, par, np.zeros(3))
    assert m == 1


@pytest.mark.parametrize("error_model", ["phi", "st"])
def test_filter_estimates_the_dvl_scale_factor_in_both_error_models(error_model):
    """An error-free IMU and a DVL with a 0.3 % scale factor: the filter must find it."""
    from fuzzynav.filters.runner import InitialState, run_filter
    from fuzzynav.sim.sensors.dvl import Spec
    from fuzzynav.sim.trajectory import Segment, generate

    start = np.array([np.deg2rad(30.5), np.deg2rad(114.4), 20.0])
    segs = [Segment("accelerate", 10, speed_change_mps=2.0), Segment("turn", 40, turn_deg=180),
            Segment("cruise", 100), Segment("turn", 40, turn_deg=-180), Segment("cruise", 60)]
    tr = generate(start, segs, 50.0, 0.0, 0.0)
    d = Spec(rate_hz=2.0, sigma_mps=0.01, scale_factor=0.003,
             lever_arm_b_m=(0.0, 1.0, 0.0)).simulate(tr, np.random.default_rng(3))
    cfg = FilterConfig(init_att_sigma_deg=(0.01, 0.01, 0.05), init_vel_sigma_mps=0.05,
                       init_pos_sigma_m=0.1, gyro_sigma_dph=(0.01,), accel_sigma_ug=(10.0,),
                       arw_dpsh=0.001, vrw_ug_psqrthz=5.0, error_model=error_model)
    setup = with_sensor_states(FilterSetup(cfg), {"dvl": d})
    init = InitialState(float(tr.time_s[0]), tr.lla[0], tr.vel_n[0], tr.q_bn[0])
    res = run_filter(tr, {"dvl": d}, init, setup.config, {}, setup.sensor_options)
    assert res.ok
    k = res.sensor_states[-1, setup.config.model.layout.sensor_slice("dvl_scale")][0]
    sig = res.state_sigma("dvl_scale")[-1, 0]
    assert sig < 0.002  # observed (prior 0.01)
    assert abs(k - 0.003) < 3 * sig
    # the horizontal error stays at the dead-reckoning level: 0.01 m/s noise over 250 s
    err = np.hypot(*(np.array(res.lla[-1, :2] - tr.lla[-1, :2])
                     * [6.37e6, 6.37e6 * np.cos(start[0])]))
    assert err < 1.0
