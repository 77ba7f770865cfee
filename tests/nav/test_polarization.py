"""Polarization solvers: exact inverses of the sky model, ambiguities, sensitivities."""
import numpy as np
import pytest
from scipy.optimize import brentq

from fuzzynav.nav.attitude import dcm_to_euler, euler_to_dcm, rotvec_to_dcm
from fuzzynav.nav import polarization_solver as ps
from fuzzynav.sim import skylight as sk

ZENITH = np.array([0.0, 0.0, 1.0])
MAX_TILT = np.radians(30.0)
VIEWS = sk.view_direction(np.radians([0, 30, 30, 30, 30, 30, 30]),
                          np.radians([0, 0, 60, 120, 180, 240, 300]))


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def _sun(elev, azim):
    return np.array([np.cos(elev) * np.sin(azim), np.cos(elev) * np.cos(azim), np.sin(elev)])


def _cases(n, seed, max_tilt=MAX_TILT, elev_deg=(5.0, 80.0)):
    """Random (pitch, roll, heading, sun_n): tilts up to max_tilt, all headings."""
    rng = np.random.default_rng(seed)
    for _ in range(n):
        pitch, roll = rng.uniform(-max_tilt, max_tilt, 2)
        heading = rng.uniform(0.0, 2 * np.pi)
        sun_n = _sun(np.radians(rng.uniform(*elev_deg)), rng.uniform(0.0, 2 * np.pi))
        yield pitch, roll, heading, sun_n


def test_numba_aop_kernels_agree_with_the_sky_model():
    for pitch, roll, heading, sun_n in _cases(300, 1):
        C = euler_to_dcm([pitch, roll, heading])
        s_b = C.T @ sun_n
        assert ps.zenith_aop(C, sun_n) == pytest.approx(
            sk.angle_of_polarization(ZENITH, s_b), abs=1e-13)
        ref = sk.angle_of_polarization(VIEWS, s_b)
        for v, a_ref in zip(VIEWS, ref):
            a = ps.aop_euler_partials(v, sun_n, pitch, roll, heading)[0]
            assert abs(sk.fold_half_pi(a - a_ref)) < 1e-13
            assert abs(sk.fold_half_pi(ps.view_aop(v, s_b) - a_ref)) < 1e-13


def test_zenith_heading_round_trip():
    worst = 0.0
    for pitch, roll, heading, sun_n in _cases(3000, 2):
        aop = sk.angle_of_polarization(ZENITH, euler_to_dcm([pitch, roll, heading]).T @ sun_n)
        h, _ = ps.heading_from_zenith_aop(aop, sun_n, pitch, roll, heading)
        worst = max(worst, abs(_wrap(h - heading)))
    assert worst < 1e-9


def _ambiguity_margin(pitch, roll, elev):
    """Half the smallest possible separation of the two heading roots [rad].

    The E-vector axis lies in the body x-y plane, so its elevation is at most the tilt tau;
    the roots are then pi - 2 asin(tan(elev) tan(eps)) apart, eps <= tau.
    """
    tau = np.arccos(np.cos(pitch) * np.cos(roll))
    x = min(1.0, np.tan(elev) * np.tan(tau))
    return 0.5 * np.pi - np.arcsin(x)


def test_zenith_ambiguity_resolved_by_prior_within_the_geometric_margin():
    rng = np.random.default_rng(3)
    n_checked = 0
    for pitch, roll, heading, sun_n in _cases(3000, 3):
        margin = _ambiguity_margin(pitch, roll, np.arcsin(sun_n[2]))
        if margin < np.radians(2.0):
            continue
        aop = ps.zenith_aop(euler_to_dcm([pitch, roll, heading]), sun_n)
        err = rng.uniform(-1.0, 1.0) * (margin - np.radians(1.0))
        h, _ = ps.heading_from_zenith_aop(aop, sun_n, pitch, roll, heading + err)
        assert abs(_wrap(h - heading)) < 1e-9, np.degrees([pitch, roll, heading, margin, err])
        n_checked += 1
    assert n_checked > 1500


def test_zenith_ambiguity_with_prior_errors_up_to_80_deg():
    # mild tilt and sun: the margin exceeds 80 deg, so any prior within +-80 deg must work
    for pitch, roll, heading, sun_n in _cases(600, 4, np.radians(5.0), (5.0, 50.0)):
        assert _ambiguity_margin(pitch, roll, np.arcsin(sun_n[2])) > np.radians(80.5)
        aop = ps.zenith_aop(euler_to_dcm([pitch, roll, heading]), sun_n)
        for err_deg in (-80.0, -45.0, 45.0, 80.0):
            h, _ = ps.heading_from_zenith_aop(aop, sun_n, pitch, roll,
                                              heading + np.radians(err_deg))
            assert abs(_wrap(h - heading)) < 1e-9
    # the other root is a genuine alternative: it reproduces the same AoP
    pitch, roll, heading, sun_n = next(_cases(1, 5))
    aop = ps.zenith_aop(euler_to_dcm([pitch, roll, heading]), sun_n)
    h_alt, _ = ps.heading_from_zenith_aop(aop, sun_n, pitch, roll, heading + np.pi)
    assert abs(_wrap(h_alt - heading)) > 1.0
    assert abs(sk.fold_half_pi(ps.zenith_aop(euler_to_dcm([pitch, roll, h_alt]), sun_n)
                               - aop)) < 1e-12


def test_heading_sensitivity_is_one_when_level_and_matches_finite_differences():
    for _, _, heading, sun_n in _cases(200, 6):
        aop = ps.zenith_aop(euler_to_dcm([0.0, 0.0, heading]), sun_n)
        _, dh = ps.heading_from_zenith_aop(aop, sun_n, 0.0, 0.0, heading)
        assert dh == pytest.approx(1.0, abs=1e-12)
    eps = 1e-6
    for pitch, roll, heading, sun_n in _cases(500, 7):
        aop = ps.zenith_aop(euler_to_dcm([pitch, roll, heading]), sun_n)
        h, dh = ps.heading_from_zenith_aop(aop, sun_n, pitch, roll, heading)
        if abs(dh) > 10.0:  # near a double root the heading is ill-conditioned
            continue
        hp, _ = ps.heading_from_zenith_aop(aop + eps, sun_n, pitch, roll, h)
        hm, _ = ps.heading_from_zenith_aop(aop - eps, sun_n, pitch, roll, h)
        assert _wrap(hp - hm) / (2 * eps) == pytest.approx(dh, rel=1e-5, abs=1e-7)


def test_tilt_partials_match_finite_differences():
    eps = 1e-6
    for pitch, roll, heading, sun_n in _cases(300, 8):
        aop = ps.zenith_aop(euler_to_dcm([pitch, roll, heading]), sun_n)
        _, dh = ps.heading_from_zenith_aop(aop, sun_n, pitch, roll, heading)
        if abs(dh) > 10.0:
            continue
        dp, dr = ps.zenith_heading_tilt_partials(sun_n, pitch, roll, heading)

        def h_of(p, r):
            return ps.heading_from_zenith_aop(aop, sun_n, p, r, heading)[0]

        fd_p = _wrap(h_of(pitch + eps, roll) - h_of(pitch - eps, roll)) / (2 * eps)
        fd_r = _wrap(h_of(pitch, roll + eps) - h_of(pitch, roll - eps)) / (2 * eps)
        assert dp == pytest.approx(fd_p, rel=1e-5, abs=1e-7)
        assert dr == pytest.approx(fd_r, rel=1e-5, abs=1e-7)


def test_aop_attitude_jacobian_matches_the_attitude_error_definition():
    # C_calc = (I - [phi x]) C_true, i.e. exp(-[phi x]) C_true to first order
    eps = 1e-6
    for pitch, roll, heading, sun_n in _cases(100, 9):
        C = euler_to_dcm([pitch, roll, heading])
        for v in (ZENITH, VIEWS[3]):
            a0, H = ps.aop_attitude_jacobian(C, v, sun_n)
            assert a0 == pytest.approx(ps.view_aop(v, C.T @ sun_n), abs=1e-14)
            for i in range(3):
                phi = np.zeros(3)
                phi[i] = eps
                ap = ps.view_aop(v, (rotvec_to_dcm(-phi) @ C).T @ sun_n)
                am = ps.view_aop(v, (rotvec_to_dcm(phi) @ C).T @ sun_n)
                assert sk.fold_half_pi(ap - am) / (2 * eps) == pytest.approx(H[i], abs=1e-6)


def test_documented_heading_difference_model():
    # docs/polarization.md: z = psi_ins - psi_pol = H phi for a noise-free AoP, with psi_pol
    # converted at the INS tilt and H from the Euler-error rows and the tilt partials
    rng = np.random.default_rng(14)
    for pitch, roll, heading, sun_n in _cases(200, 15, np.radians(20.0), (5.0, 70.0)):
        C = euler_to_dcm([pitch, roll, heading])
        aop = ps.zenith_aop(C, sun_n)
        _, dh = ps.heading_from_zenith_aop(aop, sun_n, pitch, roll, heading)
        if abs(dh) > 10.0:
            continue
        phi = 1e-7 * rng.standard_normal(3)
        p_i, r_i, h_i = dcm_to_euler(rotvec_to_dcm(-phi) @ C)
        h_pol, _ = ps.heading_from_zenith_aop(aop, sun_n, p_i, r_i, h_i)
        z = _wrap(h_i - h_pol)
        sh, ch, t = np.sin(heading), np.cos(heading), np.tan(pitch)
        d_pitch = sh * phi[1] - ch * phi[0]
        d_roll = -(sh * phi[0] + ch * phi[1]) / np.cos(pitch)
        d_head = phi[2] - t * (sh * phi[0] + ch * phi[1])
        dp, dr = ps.zenith_heading_tilt_partials(sun_n, pitch, roll, heading)
        assert z == pytest.approx(d_head - dp * d_pitch - dr * d_roll, rel=1e-4, abs=1e-12)


def test_no_root_gives_nan():
    # E-vector along the body y axis, pitched up 30 deg: it climbs 30 deg, but with the sun
    # 80 deg high every E-vector (perpendicular to the sun) is within 10 deg of horizontal
    sun_n = _sun(np.radians(80.0), 0.0)
    h, dh = ps.heading_from_zenith_aop(np.pi / 2, sun_n, np.radians(30.0), 0.0, 0.0)
    h_level, _ = ps.heading_from_zenith_aop(np.pi / 2, sun_n, 0.0, 0.0, 0.0)
    assert np.isfinite(h_level)
    assert np.isnan(h) and np.isnan(dh)
    assert np.isnan(ps.zenith_aop(np.eye(3), ZENITH))
    aop, H = ps.aop_attitude_jacobian(np.eye(3), ZENITH, ZENITH)
    assert np.isnan(aop) and np.isnan(H).all()


def _imaging(pitch, roll, heading, sun_n, views=VIEWS):
    return sk.angle_of_polarization(views, euler_to_dcm([pitch, roll, heading]).T @ sun_n)


def test_imaging_round_trip():
    sig = np.radians(0.3)
    for pitch, roll, heading, sun_n in _cases(1500, 10):
        p, h, cov, k = ps.imaging_pitch_heading(_imaging(pitch, roll, heading, sun_n), VIEWS,
                                                sun_n, roll, pitch, heading, 0.01, 1.0, sig)
        assert k == len(VIEWS)
        assert abs(p - pitch) < 1e-9 and abs(_wrap(h - heading)) < 1e-9
        assert np.all(np.isfinite(cov)) and np.all(np.linalg.eigvalsh(cov) > 0)


def _pitch_roots(s_b, sun_n, roll):
    """All pitches where +-s_b rises to the sun's elevation (brute-force bracketing)."""
    roots = []
    grid = np.radians(np.linspace(-90.0, 90.0, 1801))
    for sign in (1.0, -1.0):
        def f(p):
            return (euler_to_dcm([p, roll, 0.0]) @ (sign * s_b))[2] - sun_n[2]

        att = np.stack([grid, np.full_like(grid, roll), np.zeros_like(grid)], -1)
        vals = (euler_to_dcm(att) @ (sign * s_b))[:, 2] - sun_n[2]
        for i in np.nonzero(np.sign(vals[:-1]) != np.sign(vals[1:]))[0]:
            roots.append(brentq(f, grid[i], grid[i + 1], xtol=1e-14))
    return np.array(roots)


def test_imaging_ambiguities_resolved_with_heading_prior_errors_up_to_80_deg():
    rng = np.random.default_rng(11)
    n_checked = 0
    for pitch, roll, heading, sun_n in _cases(300, 12):
        s_b = euler_to_dcm([pitch, roll, heading]).T @ sun_n
        others = [r for r in _pitch_roots(s_b, sun_n, roll) if abs(r - pitch) > 1e-7]
        # a pitch prior good to 1 deg can only tell roots apart that are 4 deg away
        if others and min(abs(np.array(others) - pitch)) < np.radians(4.0):
            continue
        aops = _imaging(pitch, roll, heading, sun_n)
        prior_p = pitch + np.radians(rng.uniform(-1.0, 1.0))
        prior_h = heading + np.radians(rng.choice([-80.0, 80.0]) * rng.uniform(0.5, 1.0))
        p, h, _, _ = ps.imaging_pitch_heading(aops, VIEWS, sun_n, roll, prior_p, prior_h,
                                              np.radians(1.0), np.radians(60.0), 0.005)
        assert abs(p - pitch) < 1e-9 and abs(_wrap(h - heading)) < 1e-9
        n_checked += 1
    assert n_checked > 200


def test_imaging_covariance_matches_monte_carlo_scatter():
    rng = np.random.default_rng(13)
    pitch, roll, heading = np.radians([8.0, -5.0, 130.0])
    sun_n = _sun(np.radians(35.0), np.radians(200.0))
    sig = np.radians(0.3)
    clean = _imaging(pitch, roll, heading, sun_n)
    sols = []
    for _ in range(1000):
        noisy = clean + sig * rng.standard_normal(clean.shape)
        p, h, cov, _ = ps.imaging_pitch_heading(noisy, VIEWS, sun_n, roll, pitch, heading,
                                                0.02, 0.5, sig)
        sols.append([p - pitch, _wrap(h - heading)])
    sols = np.array(sols)
    # unbiased, and the scatter agrees with the predicted covariance: the normalised
    # squared errors average 2 (chi-square, 2 dof; 1000 draws -> 2 +- 0.2 at 3 sigma)
    assert np.all(np.abs(sols.mean(0)) < 4 * np.sqrt(np.diag(cov) / len(sols)))
    nees = np.einsum("ki,ij,kj->k", sols, np.linalg.inv(cov), sols)
    assert nees.mean() > 1.8 and nees.mean() < 2.2


def test_imaging_skips_nan_views_and_needs_two():
    pitch, roll, heading = 0.1, 0.05, 2.0
    sun_n = _sun(np.radians(30.0), 1.0)
    aops = _imaging(pitch, roll, heading, sun_n)
    aops[[0, 2, 3, 5]] = np.nan
    p, h, _, k = ps.imaging_pitch_heading(aops, VIEWS, sun_n, roll, pitch, heading,
                                          0.02, 0.5, 0.005)
    assert k == 3 and abs(p - pitch) < 1e-9 and abs(_wrap(h - heading)) < 1e-9
    aops[[1, 4]] = np.nan
    p, h, cov, k = ps.imaging_pitch_heading(aops, VIEWS, sun_n, roll, pitch, heading,
                                            0.02, 0.5, 0.005)
    assert k == 1 and np.isnan(p) and np.isnan(h) and np.isnan(cov).all()
