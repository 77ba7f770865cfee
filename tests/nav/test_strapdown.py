"""Strapdown mechanization replayed on error-free increments from the trajectory generator."""
import numpy as np

from fuzzynav.nav import attitude, earth, strapdown
from fuzzynav.nav.state_layout import PREV_SIZE, Q_SLICE
from fuzzynav.sim.segments import manoeuvring_profile
from fuzzynav.sim.trajectory import Segment, generate

START = np.array([np.deg2rad(38.0178), np.deg2rad(112.4447), 825.0])


def test_one_hour_replay_stays_on_truth():
    tr = generate(START, manoeuvring_profile(3600.0), 100.0, 0.0, 0.3)
    assert tr.duration_s >= 3600.0
    out = strapdown.integrate(tr.lla[0], tr.vel_n[0], tr.q_bn[0], tr.dtheta_b, tr.dv_b,
                              0.01, stride=100)
    idx = np.arange(0, tr.n_samples + 1, 100)
    lla, ref = out["lla"], tr.lla[idx]
    err = np.array([earth.lla_to_enu(*a, *b) for a, b in zip(lla[::10], ref[::10])])
    assert np.abs(err).max() < 0.05
    phi = attitude.attitude_error(attitude.quat_to_dcm(out["q_bn"]),
                                  attitude.quat_to_dcm(tr.q_bn[idx]))
    assert np.rad2deg(np.abs(phi)).max() < 1e-4
    # the trajectory really manoeuvres: km travelled, 3-D, banked
    assert np.ptp(tr.lla[:, 2]) > 100 and np.abs(tr.att[:, 1]).max() > 0.1


def test_error_of_the_algorithm_shrinks_with_the_step():
    """A wrong term would show as an error that does not converge at the algorithm's order."""
    segs = [Segment("accelerate", 20, speed_change_mps=15)] + \
        [Segment("climb", 60, pitch_deg=5), Segment("turn", 30, turn_deg=-120, bank=True)] * 4
    errs = []
    for rate in (25.0, 50.0):
        tr = generate(START, segs, rate, 0.0, 1.0)
        out = strapdown.integrate(tr.lla[0], tr.vel_n[0], tr.q_bn[0], tr.dtheta_b, tr.dv_b,
                                  1.0 / rate, stride=tr.n_samples)
        errs.append(np.abs(out["vel_n"][-1] - tr.vel_n[-1]).max())
    assert errs[1] < errs[0] / 3.0  # at least second order


def test_static_vehicle_stays_put_and_keeps_gravity_balance():
    tr = generate(START, [Segment("static", 600)], 100.0)
    np.testing.assert_allclose(tr.dv_b[:, :2], 0.0, atol=1e-15)
    # float sample times carry ~1e-13 s of rounding, hence the 1e-10 relative tolerance
    np.testing.assert_allclose(tr.dv_b[:, 2] / 0.01, earth.gravity(START[0], START[2]), rtol=1e-10)
    omega = np.linalg.norm(tr.dtheta_b, axis=1) / 0.01
    np.testing.assert_allclose(omega, earth.OMEGA_IE, rtol=1e-10)
    out = strapdown.integrate(tr.lla[0], tr.vel_n[0], tr.q_bn[0], tr.dtheta_b, tr.dv_b, 0.01,
                              stride=tr.n_samples)
    assert np.abs(out["vel_n"][-1]).max() < 1e-9


def test_rotation_vector_series_matches_the_closed_form_across_its_switch():
    """The small-angle series must agree with cos(a/2), sin(a/2)/a to rounding on both sides
    of its switch (a^2 = 1e-4) and far below it (a numpy closed form, no shared code)."""
    axis = np.array([0.48, -0.6, 0.64])  # unit length
    for a in (1e-7, 1e-4, 3e-3, 0.0099, 0.01001, 0.02, 0.7):
        q = np.array(strapdown.rv2q(*(a * axis)))
        ref = np.concatenate([[np.cos(a / 2)], np.sin(a / 2) * axis])
        assert np.abs(q - ref).max() < 4e-16, a


def test_step_hands_back_the_attitude_matrix_of_its_new_quaternion():
    """mech_step replaces C with C_bn of the quaternion it stores: the loop relies on it."""
    tr = generate(START, [Segment("turn", 2, turn_deg=30, bank=True)], 100.0, 20.0, 0.3)
    nav = strapdown.make_nav(tr.lla[0], tr.vel_n[0], tr.q_bn[0])
    prev, f_n, C = np.zeros(PREV_SIZE), np.zeros(3), np.zeros((3, 3))
    strapdown.init_prev(nav, prev)
    strapdown.quat_to_dcm_into(nav, C)
    for k in range(50):
        strapdown.mech_step(nav, prev, tr.dtheta_b[k], tr.dv_b[k], 0.01, f_n, C)
    assert np.abs(C - attitude.quat_to_dcm(nav[Q_SLICE])).max() < 1e-14


def test_latitude_trig_followed_across_steps_stays_at_rounding():
    """sin_cos_lat follows the midpoint latitude's sine and cosine by the angle-addition
    formulas: over a drive north (many follow-on steps, several exact re-evaluations) and a
    feedback-sized jump they stay within a few ulp of numpy's sin and cos."""
    prev = np.zeros(PREV_SIZE)
    lat = 0.6
    worst = 0.0
    for k in range(3000):
        lat += 3e-8 if k != 1500 else 5e-6  # ~0.2 m a step; one jump past the follow limit
        s, c = strapdown.sin_cos_lat(lat, prev)
        worst = max(worst, abs(s - np.sin(lat)), abs(c - np.cos(lat)))
    assert worst < 1e-15


def test_step_hands_back_the_specific_force_increment_in_the_navigation_frame():
    """At rest the specific-force increment of a step is gravity's reaction times dt, up in
    ENU (the loop divides the summed increments by the interval for the error model)."""
    tr = generate(START, [Segment("static", 1)], 100.0)
    nav = strapdown.make_nav(tr.lla[0], tr.vel_n[0], tr.q_bn[0])
    prev, dv_sf, C = np.zeros(PREV_SIZE), np.zeros(3), np.zeros((3, 3))
    strapdown.init_prev(nav, prev)
    strapdown.quat_to_dcm_into(nav, C)
    strapdown.mech_step(nav, prev, tr.dtheta_b[0], tr.dv_b[0], 0.01, dv_sf, C)
    g = earth.gravity(START[0], START[2])
    np.testing.assert_allclose(dv_sf, [0.0, 0.0, g * 0.01], atol=1e-7)


def test_quaternion_renormalisation_is_the_inverse_square_root_to_rounding():
    """inv_norm's Newton step near 1 and its exact branch beyond the switch, against numpy."""
    for e in np.concatenate([[0.0], np.geomspace(1e-16, 1e-3, 60)]):
        for s in (1.0 + e, 1.0 - e):
            assert abs(strapdown.inv_norm(s) - 1.0 / np.sqrt(s)) <= 2 * np.spacing(1.0), s
