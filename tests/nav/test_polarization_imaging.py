"""Imaging solver internals: closed-form eigenvector, and the fit lands on the LSQ minimum."""
import numpy as np

from fuzzynav.nav import polarization_geometry as pg
from fuzzynav.nav import polarization_imaging as pim
from fuzzynav.nav.attitude import euler_to_dcm
from fuzzynav.sim import skylight as sk

VIEWS = sk.view_direction(np.radians([0, 30, 30, 30, 30, 30, 30]),
                          np.radians([0, 0, 60, 120, 180, 240, 300]))


def _upper(m):
    return m[0, 0], m[0, 1], m[0, 2], m[1, 1], m[1, 2], m[2, 2]


def _unit_rows(rng, n):
    v = rng.standard_normal((n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def test_smallest_eigenvector_matches_lapack():
    rng = np.random.default_rng(1)
    for _ in range(2000):
        s = _unit_rows(rng, 1)[0]
        # E-vectors perpendicular to s, then perturbed: from exact rank 2 to well spread
        e = np.cross(s, _unit_rows(rng, rng.integers(2, 8)))
        e += 10.0 ** rng.uniform(-8, 0) * rng.standard_normal(e.shape)
        e /= np.linalg.norm(e, axis=1, keepdims=True)
        m = e.T @ e
        w, vecs = np.linalg.eigh(m)
        got = np.array(pim._smallest_eigenvector(*_upper(m)))
        assert abs(np.linalg.norm(got) - 1.0) < 1e-14
        # eigenvector accuracy of any backward-stable method: eps * |M| / gap
        tol = 20 * np.finfo(float).eps * w[2] / (w[1] - w[0])
        assert abs(abs(got @ vecs[:, 0]) - 1.0) < max(tol, 1e-14)


def test_smallest_eigenvector_degenerate_cases():
    # all E-vectors parallel: any vector perpendicular to them is an eigenvector of the
    # (double) zero eigenvalue; isotropic: no direction at all
    e = np.array([0.6, 0.8, 0.0])
    got = np.array(pim._smallest_eigenvector(*_upper(3.0 * np.outer(e, e))))
    assert abs(np.linalg.norm(got) - 1.0) < 1e-14 and abs(got @ e) < 1e-12
    assert np.isnan(pim._smallest_eigenvector(*_upper(np.eye(3)))).all()


def _residuals(x, aops, sun_n, roll):
    s_b = euler_to_dcm([x[0], roll, x[1]]).T @ sun_n
    return sk.fold_half_pi(aops - sk.angle_of_polarization(VIEWS, s_b))


def _numpy_least_squares(x, aops, sun_n, roll, d=1e-5):
    """Independent Gauss-Newton: numpy sky model, 5-point finite-difference Jacobian."""
    for _ in range(50):
        jac = np.empty((aops.size, 2))
        for j in range(2):
            dx = np.zeros(2)
            dx[j] = d
            f = [_residuals(x + k * dx, aops, sun_n, roll) for k in (-2, -1, 1, 2)]
            jac[:, j] = (f[0] - 8 * f[1] + 8 * f[2] - f[3]) / (12 * d)
        step = np.linalg.lstsq(jac, -_residuals(x, aops, sun_n, roll), rcond=None)[0]
        x = x + step
        if np.abs(step).sum() < 1e-15:
            break
    return x


def test_noisy_fit_is_the_least_squares_minimum():
    # the stopping rules must not leave the fit short of the minimum, however ill-conditioned
    rng = np.random.default_rng(2)
    sig = np.radians(0.3)
    n_checked = 0
    for _ in range(150):
        pitch, roll = rng.uniform(-0.3, 0.3, 2)
        heading = rng.uniform(0.0, 2 * np.pi)
        el, az = np.radians(rng.uniform(5.0, 80.0)), rng.uniform(0.0, 2 * np.pi)
        sun_n = np.array([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)])
        aops = sk.angle_of_polarization(VIEWS, euler_to_dcm([pitch, roll, heading]).T @ sun_n)
        aops = aops + sig * rng.standard_normal(aops.shape)
        p, h, cov, _ = pim.imaging_pitch_heading(aops, VIEWS, sun_n, roll, pitch, heading,
                                                 0.02, 0.5, sig)
        if not (np.isfinite(p) and cov[0, 0] < 0.01 and cov[1, 1] < 0.01):
            continue  # undetermined fits (fold) have no sharp minimum to compare with
        ref = _numpy_least_squares(np.array([p, h]), aops, sun_n, roll)
        assert abs(p - ref[0]) < 1e-9 and abs(sk.fold_half_pi(h - ref[1])) < 1e-9
        n_checked += 1
    assert n_checked > 130


def test_aop_gradient_alone_is_the_slope_of_the_angle():
    # the gradient-only helper (no atan2) must give the slope of the AoP itself: checked
    # against central differences of the angle, and equal to the combined helper's
    rng = np.random.default_rng(3)
    h = 1e-6
    for v in VIEWS[1:]:
        s = _unit_rows(rng, 1)[0]
        g = np.array(pg.aop_gradient(v, *s))
        # two functions: equal up to rounding, not promised bit for bit on every CPU
        np.testing.assert_allclose(g, pg.aop_unfolded_and_gradient(v, *s)[1:], rtol=1e-12,
                                   atol=1e-15)
        fd = [(pg.aop_unfolded_and_gradient(v, *(s + h * e))[0]
               - pg.aop_unfolded_and_gradient(v, *(s - h * e))[0]) / (2 * h) for e in np.eye(3)]
        np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-8)
    assert np.isnan(pg.aop_gradient(np.array([1.0, 0.0, 0.0]), 1.0, 0.0, 0.0)).all()


def test_imaging_fit_is_the_solver_with_scalar_covariance():
    rng = np.random.default_rng(4)
    sun_n = np.array([0.3, 0.5, 0.81])
    sun_n /= np.linalg.norm(sun_n)
    for _ in range(20):
        pitch, roll, heading = rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(0, 6)
        aops = sk.angle_of_polarization(VIEWS, euler_to_dcm([pitch, roll, heading]).T @ sun_n)
        aops = aops + 0.01 * rng.standard_normal(aops.shape)
        p, hd, cov, k = pim.imaging_pitch_heading(aops, VIEWS, sun_n, roll, pitch, heading,
                                                  0.1, 0.2, 0.01)
        fit = pim.imaging_fit(aops, VIEWS, sun_n, roll, pitch, heading, 0.1, 0.2, 0.01)
        np.testing.assert_array_equal(fit[:2], (p, hd))
        np.testing.assert_array_equal(fit[2:5], (cov[0, 0], cov[0, 1], cov[1, 1]))
        np.testing.assert_array_equal(cov[0, 1], cov[1, 0])  # NaN for a fit on the fold
        assert fit[5] == k


def test_view_frames_are_the_sky_models_aop_axes():
    frames = pim.view_frames(VIEWS).reshape(-1, pim.FRAME)
    np.testing.assert_array_equal(frames[:, :3], VIEWS)
    x_ref, y_ref = frames[:, 3:6], frames[:, 6:9]
    np.testing.assert_allclose(np.linalg.norm(x_ref, axis=1), 1.0, rtol=1e-14)
    np.testing.assert_allclose(np.einsum("ij,ij->i", x_ref, VIEWS), 0.0, atol=1e-15)
    np.testing.assert_allclose(y_ref, np.cross(VIEWS, x_ref), atol=1e-15)
    # the angle of the E-vector (v x s) in these axes is the sky model's AoP
    for s in _unit_rows(np.random.default_rng(6), 20):
        e = np.cross(VIEWS, s)
        aop = np.arctan2(np.einsum("ij,ij->i", e, y_ref), np.einsum("ij,ij->i", e, x_ref))
        d = (aop - sk.angle_of_polarization(VIEWS, s) + np.pi / 2) % np.pi - np.pi / 2
        np.testing.assert_allclose(d, 0.0, atol=1e-12)


def test_roll_sensitivity_is_the_slope_of_the_fit():
    """Implicit differentiation against central differences of the fit in the given roll."""
    sun_n = np.array([0.3, 0.5, 0.81])
    sun_n /= np.linalg.norm(sun_n)
    frames, d, used = pim.view_frames(VIEWS), 1e-6, 0
    # (seed, heading, AoP noise); seed 3 at 1e-4 rad: the fit starts below 2 pi and ends
    # above it, so the slope is re-evaluated at the heading reported (taken modulo 2 pi)
    for seed, heading, noise in ((3, 1e-4, 0.001), (7, 2 * np.pi - 1e-6, 0.01),
                                 (8, 1.0, 0.01), (9, 2.0, 0.01), (10, 3.0, 0.01),
                                 (11, 4.5, 0.01), (12, 5.5, 0.01)):
        rng = np.random.default_rng(seed)
        pitch, roll = rng.uniform(-0.3, 0.3, 2)
        aops = sk.angle_of_polarization(VIEWS, euler_to_dcm([pitch, roll, heading]).T @ sun_n)
        aops = aops + noise * rng.standard_normal(aops.shape)
        fit = pim.imaging_fit_frames(aops, pim.aop_trig(aops), frames, sun_n,
                                     np.arctan2(sun_n[1], sun_n[0]), roll, pitch, heading,
                                     0.1, 0.2, 0.01)
        if not (fit[2] < 0.01 and fit[4] < 0.01):
            continue  # a fit on the fold: the attitude is undetermined, no slope to compare
        used += 1
        up, down = (pim.imaging_fit(aops, VIEWS, sun_n, roll + s * d, pitch, heading, 0.1, 0.2,
                                    0.01) for s in (1.0, -1.0))
        dp = (up[0] - down[0]) / (2 * d)
        dh = ((up[1] - down[1] + np.pi) % (2 * np.pi) - np.pi) / (2 * d)
        np.testing.assert_allclose(fit[6:], (dp, dh), rtol=1e-5, atol=1e-7)
    assert used >= 5


def test_residual_by_atan_is_the_folded_angle_difference():
    rng = np.random.default_rng(9)
    for _ in range(500):
        v, s = _unit_rows(rng, 2)
        a = pg.aop_unfolded_and_gradient(v, *s)
        meas = a[0] + rng.choice([rng.uniform(-1.5, 1.5), rng.uniform(-1e-3, 1e-3)]) \
            + np.pi * rng.integers(-2, 3)
        r, *g = pg.aop_residual_and_gradient3(np.cos(meas), np.sin(meas), *v, *s)
        ref = (meas - a[0] + np.pi / 2) % np.pi - np.pi / 2
        assert abs(r - ref) < 1e-12 or abs(abs(r - ref) - np.pi) < 1e-12  # ends of the fold
        np.testing.assert_allclose(g, a[1:], rtol=1e-12, atol=1e-15)
    nan = pg.aop_residual_and_gradient3(1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
    assert np.isnan(nan).all()  # sun on the view axis: no angle


def test_small_tangent_series_is_atan_to_rounding():
    """The residuals' atan: its series below the switch and the library above agree with
    numpy's arctan within 2 ulp on both sides of the switch and at tiny arguments."""
    switch = pg._ATAN_SERIES * (1 + np.arange(-40, 41) * 1e-15)
    t = np.concatenate([np.geomspace(1e-300, 0.2, 4000), switch])
    for v in np.concatenate([t, -t]):
        ref = np.arctan(v)
        assert abs(pg.atan_small(v) - ref) <= 2 * np.spacing(abs(ref)), v
    assert np.isnan(pg.atan_small(np.nan))
