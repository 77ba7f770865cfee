"""Rayleigh sky: geometry, brute-force dipole scattering, symmetry, conventions."""
import numpy as np
import pytest

from fuzzynav.sim import skylight as sk

RNG = np.random.default_rng(11)


def _random_unit(n, rng=RNG):
    v = rng.standard_normal((n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _fold_diff(a, b):
    return sk.fold_half_pi(np.asarray(a) - np.asarray(b))


def test_e_vector_is_perpendicular_to_view_and_scattering_plane():
    v, s = _random_unit(500), _random_unit(500)
    e = sk.e_vector(v, s)
    np.testing.assert_allclose(np.linalg.norm(e, axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(np.sum(e * v, 1), 0.0, atol=1e-14)
    np.testing.assert_allclose(np.sum(e * s, 1), 0.0, atol=1e-14)
    assert np.isnan(sk.e_vector([0, 0, 1.0], [0, 0, 2.0])).all()


def test_dop_zero_at_sun_and_antisun_and_max_at_ninety_degrees():
    s = np.array([0.3, -0.2, 0.9])
    s /= np.linalg.norm(s)
    perp = np.cross(s, [1.0, 0, 0])
    assert sk.degree_of_polarization(s, s, 0.8) == pytest.approx(0.0, abs=1e-15)
    assert sk.degree_of_polarization(-s, s, 0.8) == pytest.approx(0.0, abs=1e-15)
    assert sk.degree_of_polarization(perp, s, 0.8) == pytest.approx(0.8, abs=1e-15)
    # maximum over random views is at gamma = 90 deg and never exceeds dop_max
    v = _random_unit(20000)
    d = sk.degree_of_polarization(v, s, 0.8)
    g = sk.scattering_angle(v, s)
    assert d.max() <= 0.8 + 1e-15
    assert abs(np.degrees(g[np.argmax(d)]) - 90.0) < 2.0


def test_dop_and_e_vector_match_brute_force_dipole_scattering():
    # unpolarized light travelling along -s is a mix of linear polarizations p (p . s = 0);
    # a molecule re-radiates each towards the observer (direction -v) as the component of p
    # transverse to -v.  Averaging the coherency matrix gives DoP and E-vector independently
    # of the closed forms.
    s = np.array([0.2, 0.5, 0.7])
    s /= np.linalg.norm(s)
    a = np.cross(s, [0.0, 0.0, 1.0])
    a /= np.linalg.norm(a)
    b = np.cross(s, a)
    psi = np.linspace(0.0, np.pi, 720, endpoint=False)
    p = np.cos(psi)[:, None] * a + np.sin(psi)[:, None] * b
    for v in _random_unit(25):
        e_scat = p - (p @ v)[:, None] * v
        J = e_scat.T @ e_scat / len(psi)
        w, vec = np.linalg.eigh(J)
        dop_ref = (w[2] - w[1]) / (w[2] + w[1])
        assert sk.degree_of_polarization(v, s, 1.0) == pytest.approx(dop_ref, abs=1e-12)
        if dop_ref > 1e-6:
            assert abs(abs(sk.e_vector(v, s) @ vec[:, 2]) - 1.0) < 1e-10


def test_aop_pattern_is_symmetric_about_the_solar_meridian():
    # zenith sensor whose y axis points at the sun's azimuth: the solar meridian is the
    # y-z plane, mirroring x -> -x flips the sign of the AoP and keeps the DoP
    elev = np.radians(35.0)
    s = np.array([0.0, np.cos(elev), np.sin(elev)])
    v = _random_unit(400)
    v[:, 2] = np.abs(v[:, 2])
    m = v * [-1.0, 1.0, 1.0]
    ok = np.abs(v[:, 0]) < 0.95  # the local reference needs v away from +-x
    a, am = sk.angle_of_polarization(v[ok], s), sk.angle_of_polarization(m[ok], s)
    np.testing.assert_allclose(_fold_diff(am, -a), 0.0, atol=1e-12)
    np.testing.assert_allclose(sk.degree_of_polarization(m, s), sk.degree_of_polarization(v, s),
                               atol=1e-15)


def test_zenith_e_vector_is_horizontal_and_perpendicular_to_the_solar_meridian():
    for az in np.radians([0.0, 37.0, 123.0, 250.0]):
        s = np.array([np.cos(0.4) * np.sin(az), np.cos(0.4) * np.cos(az), np.sin(0.4)])
        e = sk.e_vector([0.0, 0.0, 1.0], s)
        assert abs(e[2]) < 1e-15
        assert abs(e @ [np.sin(az), np.cos(az), 0.0]) < 1e-15


def test_aop_on_the_boresight_is_the_angle_from_x_towards_y():
    s = _random_unit(200)
    a = sk.angle_of_polarization([0.0, 0.0, 1.0], s)
    e = sk.e_vector([0.0, 0.0, 1.0], s)
    np.testing.assert_allclose(_fold_diff(a, np.arctan2(e[:, 1], e[:, 0])), 0.0, atol=1e-12)


def test_rotating_the_sensor_about_its_boresight_shifts_the_aop():
    # sensor turned by +alpha about z_c: vectors in the new frame are R3(-alpha) v
    v, s = _random_unit(300), _random_unit(300)
    v[:, 2] = np.abs(v[:, 2]) + 0.3
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    alpha = 0.7
    c, sn = np.cos(alpha), np.sin(alpha)
    R = np.array([[c, sn, 0.0], [-sn, c, 0.0], [0.0, 0.0, 1.0]])  # R3(-alpha)
    a0 = sk.angle_of_polarization([0, 0, 1.0], s)
    a1 = sk.angle_of_polarization([0, 0, 1.0], s @ R.T)
    np.testing.assert_allclose(_fold_diff(a1, a0 - alpha), 0.0, atol=1e-12)


def test_stokes_parameters_give_back_aop_and_dop():
    v, s = _random_unit(100), _random_unit(100)
    v[:, 2] = np.abs(v[:, 2]) + 0.2
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    i, q, u = sk.stokes(v, s, 0.7, 2.0).T
    np.testing.assert_allclose(i, 2.0)
    np.testing.assert_allclose(0.5 * np.arctan2(u, q),
                               sk.angle_of_polarization(v, s) + 0.0, atol=1e-12)
    np.testing.assert_allclose(np.hypot(q, u) / i, sk.degree_of_polarization(v, s, 0.7),
                               atol=1e-14)


def test_view_direction_convention():
    np.testing.assert_allclose(sk.view_direction(0.0, 1.0), [0, 0, 1], atol=1e-16)
    # 90 deg off the axis at azimuth 90 deg: along +x (east / right)
    np.testing.assert_allclose(sk.view_direction(np.pi / 2, np.pi / 2), [1, 0, 0], atol=1e-16)
    np.testing.assert_allclose(sk.view_direction(np.pi / 2, 0.0), [0, 1, 0], atol=1e-16)
