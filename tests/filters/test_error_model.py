"""The error model's F against finite differences of the mechanization it linearises."""
import numpy as np
import pytest
from scipy.linalg import expm

from fuzzynav.filters.error_model import ErrorModel, discretize, fill_F
from fuzzynav.nav import attitude, earth, strapdown
from fuzzynav.sim.trajectory import Segment, generate

START = np.array([np.deg2rad(61.0), np.deg2rad(25.0), 300.0])
MODEL = ErrorModel(gyro_tau_s=(np.inf,), accel_tau_s=(np.inf,))
SCALES = np.r_[[2e-6] * 3, [2e-3] * 3, [2.0] * 3, [1e-6] * 3, [1e-4] * 3]


def _trajectory():
    segs = [Segment("accelerate", 5, speed_change_mps=40),
            Segment("turn", 20, turn_deg=120, bank=True), Segment("climb", 20, pitch_deg=8)]
    return generate(START, segs, 100.0, 0.0, 0.7)


def _perturbed_run(tr, k0, steps, dx):
    """Run the mechanization from truth at sample k0 with error dx; return the error after."""
    C_true = attitude.quat_to_dcm(tr.q_bn[k0])
    C_calc = (np.eye(3) - attitude.skew(dx[:3])) @ C_true
    dlat, dlon, dh = earth.enu_to_delta_lla(dx[6:9], tr.lla[k0, 0], tr.lla[k0, 2])
    lla = tr.lla[k0] + np.array([dlat, dlon, dh])
    sl = slice(k0, k0 + steps)
    out = strapdown.integrate(lla, tr.vel_n[k0] + dx[3:6], attitude.dcm_to_quat(C_calc),
                              tr.dtheta_b[sl] + dx[9:12] * 0.01, tr.dv_b[sl] + dx[12:15] * 0.01,
                              0.01, stride=steps)
    k1 = k0 + steps
    err = np.empty(15)
    err[:3] = attitude.attitude_error(attitude.quat_to_dcm(out["q_bn"][-1]),
                                      attitude.quat_to_dcm(tr.q_bn[k1]))
    err[3:6] = out["vel_n"][-1] - tr.vel_n[k1]
    d = out["lla"][-1] - tr.lla[k1]
    err[6:9] = earth.delta_lla_to_enu(d[0], d[1], d[2], tr.lla[k1, 0], tr.lla[k1, 2])
    err[9:] = dx[9:]
    return err


@pytest.mark.parametrize("k0", [600, 1500, 3200])
def test_transition_matrix_matches_finite_differences(k0):
    tr = _trajectory()
    steps = 20  # 0.2 s
    # F at the interval: mean attitude and specific force as the filter loop forms them
    nav = strapdown.make_nav(tr.lla[k0 + steps // 2], tr.vel_n[k0 + steps // 2],
                             tr.q_bn[k0 + steps // 2])
    C_mid = attitude.quat_to_dcm(tr.q_bn[k0 + steps // 2])
    f_n = C_mid @ (tr.dv_b[k0:k0 + steps].mean(0) / 0.01)
    F = np.zeros((15, 15))
    start, kind, inv_tau = MODEL.block_arrays()
    fill_F(F, nav, C_mid, f_n, start, kind, inv_tau)
    Phi_ref = expm(F * 0.2)
    Phi_num = np.empty((15, 15))
    for j in range(15):
        dx = np.zeros(15)
        dx[j] = SCALES[j]
        Phi_num[:, j] = (_perturbed_run(tr, k0, steps, dx)
                         - _perturbed_run(tr, k0, steps, -dx)) / (2 * SCALES[j])
    # compare the change over the interval, scaled to the state units
    D_num = (Phi_num - np.eye(15)) * SCALES[None, :] / SCALES[:, None]
    D_ref = (Phi_ref - np.eye(15)) * SCALES[None, :] / SCALES[:, None]
    np.testing.assert_allclose(D_num, D_ref, atol=2e-3 * np.abs(D_ref).max(), rtol=3e-2)


def test_discretisation_matches_van_loan():
    rng = np.random.default_rng(0)
    F = rng.normal(0, 0.05, (15, 15))
    q = rng.uniform(0, 1e-3, 15)
    dt = 0.5
    Phi, Qd, work = np.zeros((15, 15)), np.zeros((15, 15)), np.zeros((15, 15))
    discretize(F, q, dt, Phi, Qd, work)
    n = 15
    A = np.zeros((2 * n, 2 * n))
    A[:n, :n], A[:n, n:], A[n:, n:] = -F, np.diag(q), F.T
    B = expm(A * dt)
    Phi_ref = B[n:, n:].T
    Qd_ref = Phi_ref @ B[:n, n:]
    # second-order series: errors of order (F dt)^3
    assert np.abs(Phi - Phi_ref).max() < np.abs(F * dt).max() ** 3
    assert np.abs(Qd - Qd_ref).max() < 1e-2 * np.abs(Qd_ref).max()


def test_discretisation_of_the_structured_model_matches_the_series():
    """The kernels treat the sensor-block rows (decays only) as a diagonal: the 18-state
    model with Gauss-Markov blocks and unforced position states must still give exactly
    the second-order series written out with dense numpy products."""
    model = ErrorModel(gyro_tau_s=(np.inf, 300.0), accel_tau_s=(200.0,))
    n = model.n_states
    q_bn = attitude.euler_to_quat(np.deg2rad([3.0, -2.0, 40.0]))
    nav = strapdown.make_nav(START, np.array([12.0, -7.0, 0.4]), q_bn)
    C = attitude.quat_to_dcm(q_bn)
    F = np.zeros((n, n))
    fill_F(F, nav, C, np.array([0.4, -0.2, 9.81]), *model.block_arrays())
    q = np.random.default_rng(5).uniform(1e-9, 1e-6, n)
    q[6:9] = 0.0  # no noise drives the position error directly
    dt = 0.2
    Phi, Qd, work = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    discretize(F, q, dt, Phi, Qd, work)
    Q = np.diag(q)
    Phi_ref = np.eye(n) + F * dt + F @ F * dt**2 / 2
    Qd_ref = Q * dt + (F @ Q + Q @ F.T) * dt**2 / 2 + F @ Q @ F.T * dt**3 / 3
    assert np.abs(np.diag(F)[15:]).min() > 0.0  # the tail really decays
    np.testing.assert_allclose(Phi, Phi_ref, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(Qd, Qd_ref, rtol=1e-12, atol=1e-12 * np.abs(Qd_ref).max())
    np.testing.assert_array_equal(Qd, Qd.T)
