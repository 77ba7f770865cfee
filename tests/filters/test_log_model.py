"""Electromagnetic-log measurement model: residual and Jacobian against finite differences,
and the state blocks it asks for."""
import numpy as np
import pytest

from fuzzynav.filters.config import FilterConfig
from fuzzynav.filters.layout import N_CORE
from fuzzynav.filters.measurements import get
from fuzzynav.filters.named import FilterSetup
from fuzzynav.filters.sensor_states import with_sensor_states
from fuzzynav.nav import attitude, strapdown
from fuzzynav.sim.sensors import SensorData
from tests.filters.test_measurements import ATT, LLA, _perturbed

N = 19  # 15 core+bias states, then log_scale (15), log_bias (16), water_current (17, 18)
STARTS = {"log_scale": 15, "log_bias": 16, "water_current": 17}
XS = np.zeros(N - N_CORE)
XS[15 - N_CORE:] = [0.02, 0.4, 0.3, -0.2]  # k, b, w_e, w_n


def _call(nav, row, xs, par):
    C = np.ascontiguousarray(attitude.quat_to_dcm(nav[0:4]))
    z, H, R = np.zeros(2), np.zeros((2, N)), np.zeros(2)
    chan = np.zeros(2, np.int64)
    aux = np.concatenate([np.zeros(6), xs])
    m = get("log").kernel(nav, C, aux, row, par, 0.0, z, H, R, chan)
    return m, z[:m], H[:m], R[:m]


def test_residual_is_the_log_equation():
    model = get("log")
    par = model.pack(None, {"state_start": STARTS})
    np.testing.assert_array_equal(par, [15, 16, 17])
    vel = np.array([6.0, 7.0, 0.3])
    nav = strapdown.make_nav(LLA, vel, attitude.euler_to_quat(ATT))
    keel = attitude.euler_to_dcm(ATT)[:, 1]
    m, z, H, R = _call(nav, np.array([5.0, 0.5]), XS, par)
    expect = 1.02 * keel @ (vel - [0.3, -0.2, 0.0]) + 0.4 - 5.0
    assert m == 1 and z[0] == pytest.approx(expect, abs=1e-12) and R[0] == pytest.approx(0.25)


def test_jacobian_matches_finite_differences():
    par = get("log").pack(None, {"state_start": STARTS})
    nav = strapdown.make_nav(LLA, np.array([6.0, 7.0, 0.3]), attitude.euler_to_quat(ATT))
    row = np.array([5.0, 0.5])
    _, _, H, _ = _call(nav, row, XS, par)
    steps = [1e-6] * 3 + [1e-3] * 3 + [1.0] * 3
    num = np.zeros(N)
    for j in range(9):  # navigation errors: perturb the INS state
        dx = np.zeros(9)
        dx[j] = steps[j]
        zp = _call(_perturbed(nav, dx), row, XS, par)[1][0]
        zm = _call(_perturbed(nav, -dx), row, XS, par)[1][0]
        num[j] = (zp - zm) / (2 * steps[j])
    for j in range(15, N):  # log states: their error is true minus estimate (added on
        e = np.zeros_like(XS)  # feedback), so z moves by -H when the estimate moves up
        e[j - N_CORE] = 1e-4
        num[j] = -(_call(nav, row, XS + e, par)[1][0] - _call(nav, row, XS - e, par)[1][0]) / 2e-4
    np.testing.assert_allclose(H[0], num, atol=1e-6)
    assert np.all(H[0, 9:15] == 0.0)


def test_without_states_the_model_ignores_them():
    par = get("log").pack(None, {})
    np.testing.assert_array_equal(par, [-1, -1, -1])
    nav = strapdown.make_nav(LLA, np.array([6.0, 7.0, 0.3]), attitude.euler_to_quat(ATT))
    _, z, H, _ = _call(nav, np.array([5.0, 0.5]), XS, par)
    keel = attitude.euler_to_dcm(ATT)[:, 1]
    assert z[0] == pytest.approx(keel @ [6.0, 7.0, 0.3] - 5.0, abs=1e-12)
    assert np.all(H[0, 9:] == 0.0)


def test_with_sensor_states_adds_the_blocks_and_their_starts():
    data = SensorData("log", np.zeros(1), np.zeros((1, 1)), np.full((1, 1), 0.5))
    every = {"log_states": ["log_scale", "log_bias", "water_current"]}
    base = FilterSetup(FilterConfig(), sensor_options={"log": every, "two": every})
    assert with_sensor_states(FilterSetup(FilterConfig()), {"log": data}).config.model.extra == ()
    out = with_sensor_states(base, {"log": data, "two": data})
    lay = out.config.model.layout
    assert lay.n == 15 + 2 * 4
    assert out.sensor_options["log"]["state_start"] == {
        "log_scale": lay.start("log_scale"), "log_bias": lay.start("log_bias"),
        "water_current": lay.start("water_current")}
    assert out.sensor_options["two"]["state_start"]["log_bias"] == lay.start("log_bias:two")
    # P0 carries the model's priors; the Gauss-Markov current gets 2 sigma^2 / tau
    P0, q = np.diag(out.config.P0()), out.config.q_diag()
    assert P0[lay.start("log_bias")] == pytest.approx(1.0)
    assert q[lay.start("water_current")] == pytest.approx(2 * 0.5**2 / 1800.0)
    assert q[lay.start("log_scale")] == 0.0


def test_log_scale_and_bias_converge_with_a_position_fix():
    """Observable once positions are fixed: the states find the simulated 2 % and 0.5 m/s."""
    from dataclasses import replace

    from fuzzynav.experiment import run_on_log, setup_for
    from fuzzynav.sim.sensor_log import simulate
    from fuzzynav.sim.scenario import load_scenario, scenario_from_dict

    d = load_scenario("paper003").to_dict()
    d["segments"] = d["segments"][:5]  # 900 s with a turn, an acceleration and s-turns
    d["sea"]["current_mps"] = [0.0, 0.0]
    d["sensors"]["log"]["scale"] = 0.02
    d["sensors"]["gps"] = {"kind": "gnss", "rate_hz": 1.0, "pos_sigma_m": [2.5, 2.5, 5.0]}
    log = simulate(scenario_from_dict(d), 0)
    setup = setup_for(log, "ekf")
    setup = replace(setup, sensor_options={"log": {"log_states": ["log_scale", "log_bias"]},
                                           "gps": {"use_velocity": False}})
    setup = with_sensor_states(setup, log.sensors)
    res = run_on_log(log, "ekf", setup=setup).result
    assert res.ok
    late = res.time_s > 600.0
    k = res.sensor_states[late, res.layout.sensor_slice("log_scale")]
    b = res.sensor_states[late, res.layout.sensor_slice("log_bias")]
    sk, sb = res.state_sigma("log_scale")[-1, 0], res.state_sigma("log_bias")[-1, 0]
    assert abs(k.mean() - 0.02) < max(3 * sk, 0.005) and sk < 0.005
    assert abs(b.mean() - 0.5) < max(3 * sb, 0.05) and sb < 0.05
