"""Measurement models: residual conventions and Jacobians against finite differences."""
import numpy as np
import pytest

from fuzzynav.filters.measurements import default_rows, get
from fuzzynav.nav import attitude, earth, strapdown
from fuzzynav.sim.sensors import SensorData
from fuzzynav.sim.sensors.polarization import Spec as PolSpec
from fuzzynav.sim.trajectory import Segment, generate

LLA = np.array([np.deg2rad(38.0), np.deg2rad(112.0), 800.0])
ATT = np.array([0.12, -0.2, 1.1])
VEL = np.array([12.0, -5.0, 0.8])


def _call(model, nav, row, par, dt_back=0.0, aux=None):
    C = attitude.quat_to_dcm(nav[0:4])
    z, H, R = np.zeros(9), np.zeros((9, 15)), np.zeros(9)
    chan = np.zeros(9, np.int64)
    m = model.kernel(nav, np.ascontiguousarray(C), np.zeros(6) if aux is None else aux,
                     row, par, dt_back, z, H, R, chan)
    return m, z[:m], H[:m], R[:m], chan[:m]


def _perturbed(nav, dx):
    """The navigation state carrying the error dx = (phi, dvel, dpos metres) on truth nav."""
    C = (np.eye(3) - attitude.skew(dx[:3])) @ attitude.quat_to_dcm(nav[0:4])
    d = earth.enu_to_delta_lla(dx[6:9], nav[7], nav[9])
    return strapdown.make_nav(nav[7:10] + np.array(d), nav[4:7] + dx[3:6], attitude.dcm_to_quat(C))


def _numeric_H(model, nav, row, par, m, steps, aux=None):
    H = np.zeros((m, 9))
    for j in range(9):
        dx = np.zeros(9)
        dx[j] = steps[j]
        zp = _call(model, _perturbed(nav, dx), row, par, aux=aux)[1]
        zm = _call(model, _perturbed(nav, -dx), row, par, aux=aux)[1]
        H[:, j] = (zp - zm) / (2 * steps[j])
    return H


def test_gnss_residual_and_jacobian_with_lever_arm():
    model = get("gnss")
    nav = strapdown.make_nav(LLA, VEL, attitude.euler_to_quat(ATT))
    lever = np.array([0.3, 1.2, -0.8])
    C = attitude.euler_to_dcm(ATT)
    ant = earth.enu_to_lla(C @ lever, *LLA)
    omega = np.array([0.01, -0.02, 0.05])
    v_ant = VEL + C @ np.cross(omega, lever)
    row = np.r_[ant, v_ant, [1.0, 1.0, 2.0, 0.1, 0.1, 0.2]]
    par = model.pack(SensorData("gnss", np.zeros(1), row[None, :6], row[None, 6:]),
                     {"lever_arm_b": lever})
    aux = np.r_[omega, 0, 0, 9.8]
    m, z, H, R, chan = _call(model, nav, row, par, aux=aux)
    assert m == 6 and list(chan) == [0, 0, 0, 1, 1, 1]
    np.testing.assert_allclose(z, 0.0, atol=1e-6)            # truth gives a zero residual
    np.testing.assert_allclose(R, np.square(row[6:]))
    Hn = _numeric_H(model, nav, row, par, m, [1e-6] * 3 + [1e-3] * 3 + [1e-1] * 3, aux)
    np.testing.assert_allclose(H[:3, :9], Hn[:3], atol=1e-6)  # position rows incl. lever arm
    np.testing.assert_allclose(H[3:, 3:6], np.eye(3))
    # a fix taken dt_back ago is compared with the INS moved back along its velocity
    _, z_back, *_ = _call(model, nav, row, par, dt_back=0.1, aux=aux)
    np.testing.assert_allclose(z_back[:3], -VEL * 0.1, atol=1e-6)


def test_gnss_skips_missing_components():
    model = get("gnss")
    nav = strapdown.make_nav(LLA, VEL, attitude.euler_to_quat(ATT))
    row = np.r_[LLA, [np.nan] * 3, [1.0, 1.0, 2.0], [np.nan] * 3]
    par = model.pack(SensorData("gnss", np.zeros(1), row[None, :6], row[None, 6:]), {})
    m, z, H, R, chan = _call(model, nav, row, par)
    assert m == 3 and set(chan) == {0}


def _polarization_row(spec_kw, att=ATT):
    tr = generate(LLA, [Segment("static", 2.0)], 10.0, 0.0, att[2])
    spec = PolSpec(**spec_kw, noise_deg=1e-9, rate_hz=1.0)
    import datetime
    data = spec.simulate(tr, np.random.default_rng(0),
                         datetime.datetime(2024, 3, 20, 4, 0, tzinfo=datetime.timezone.utc))
    return data, tr


@pytest.mark.parametrize("kw,mode", [({"sensor_type": "point"}, "angles"),
                                     ({"sensor_type": "imaging"}, "angles"),
                                     ({"sensor_type": "imaging"}, "aop")])
def test_polarization_residual_and_jacobian(kw, mode):
    data, tr = _polarization_row(kw)
    model = get("polarization")
    par = model.pack(data, {"mode": mode})
    row = model.rows(data)[0]  # the filter's rows (an imaging row carries data-only columns)
    k = int(round(data.time_s[0] * tr.imu_rate_hz))
    nav = strapdown.make_nav(tr.lla[k], tr.vel_n[k], tr.q_bn[k])
    m, z, H, R, chan = _call(model, nav, row, par)
    assert m >= 1 and np.all(R > 0)
    # a bare [z, sigma] row: the kernel forms those columns itself (another code path)
    for got, want in zip(_call(model, nav, default_rows(data)[0], par), (m, z, H, R, chan)):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(z, 0.0, atol=1e-7)
    Hn = _numeric_H(model, nav, row, par, m, [1e-5] * 3 + [1e-3] * 6)
    np.testing.assert_allclose(H[:, :3], Hn[:, :3], atol=2e-4 * max(1.0, np.abs(Hn).max()))
    np.testing.assert_allclose(H[:, 3:9], 0.0)


def test_nonholonomic_constraint_residual_and_jacobian():
    model = get("nhc")
    C = attitude.euler_to_dcm(ATT)
    vel = C @ np.array([0.0, 14.0, 0.0])          # moving along the body's forward axis
    nav = strapdown.make_nav(LLA, vel, attitude.euler_to_quat(ATT))
    row = np.array([0.0, 0.0, 0.1, 0.2])
    par = np.zeros(1)
    m, z, H, R, chan = _call(model, nav, row, par)
    assert m == 2 and np.allclose(z, 0.0, atol=1e-12) and np.allclose(R, [0.01, 0.04])
    Hn = _numeric_H(model, nav, row, par, m, [1e-6] * 3 + [1e-3] * 3 + [1.0] * 3)
    np.testing.assert_allclose(H[:, :9], Hn, atol=1e-6)
