"""WGS-84 model and conversions against pymap3d and closed forms."""
import numpy as np
import pymap3d
import pytest

from fuzzynav.nav import earth

RNG = np.random.default_rng(7)
LAT = np.deg2rad(RNG.uniform(-89.0, 89.0, 200))
LON = np.deg2rad(RNG.uniform(-180.0, 180.0, 200))
H = RNG.uniform(-500.0, 20000.0, 200)


def test_ecef_matches_pymap3d():
    xyz = earth.lla_to_ecef(LAT, LON, H)
    ref = np.stack(pymap3d.geodetic2ecef(LAT, LON, H, deg=False), -1)
    np.testing.assert_allclose(xyz, ref, atol=1e-6)


def test_ecef_to_lla_inverts_and_matches_pymap3d():
    xyz = earth.lla_to_ecef(LAT, LON, H)
    lat, lon, h = earth.ecef_to_lla(xyz)
    np.testing.assert_allclose(lat, LAT, atol=1e-12)
    np.testing.assert_allclose(lon, LON, atol=1e-12)
    np.testing.assert_allclose(h, H, atol=1e-6)
    plat, plon, ph = pymap3d.ecef2geodetic(*xyz.T, deg=False)
    np.testing.assert_allclose(lat, plat, atol=1e-11)
    np.testing.assert_allclose(h, ph, atol=1e-5)


def test_enu_matches_pymap3d_and_round_trips():
    lat0, lon0, h0 = np.deg2rad(38.0178), np.deg2rad(112.4447), 825.0
    lat = lat0 + np.deg2rad(RNG.uniform(-0.5, 0.5, 50))
    lon = lon0 + np.deg2rad(RNG.uniform(-0.5, 0.5, 50))
    h = RNG.uniform(0, 3000, 50)
    enu = earth.lla_to_enu(lat, lon, h, lat0, lon0, h0)
    ref = np.stack(pymap3d.geodetic2enu(lat, lon, h, lat0, lon0, h0, deg=False), -1)
    np.testing.assert_allclose(enu, ref, atol=1e-6)
    back = earth.enu_to_lla(enu, lat0, lon0, h0)
    np.testing.assert_allclose(back[0], lat, atol=1e-12)
    np.testing.assert_allclose(back[2], h, atol=1e-6)


def test_local_radii_give_small_offsets_to_first_order():
    lat0, h0 = np.deg2rad(45.0), 100.0
    d = earth.delta_lla_to_enu(1e-6, 2e-6, 3.0, lat0, h0)
    exact = earth.lla_to_enu(lat0 + 1e-6, 2e-6, h0 + 3.0, lat0, 0.0, h0)
    np.testing.assert_allclose(d, exact, atol=2e-3)  # second-order terms of a 10-m offset
    back = earth.enu_to_delta_lla(d, lat0, h0)
    np.testing.assert_allclose(back, (1e-6, 2e-6, 3.0), rtol=1e-12)


def test_radii_closed_forms_at_equator_and_pole():
    rm, rn = earth.radii(np.array([0.0, np.pi / 2]))
    assert rn[0] == pytest.approx(earth.A)
    assert rm[0] == pytest.approx(earth.A * (1 - earth.E2))
    assert rm[1] == pytest.approx(rn[1]) and rn[1] == pytest.approx(earth.A**2 / earth.B)


def test_normal_gravity_reference_values():
    # WGS-84 (NIMA TR8350.2) normal gravity: equator 9.7803253359, pole 9.8321849378 m/s^2
    assert earth.gravity(0.0, 0.0) == pytest.approx(9.7803253359, abs=1e-9)
    assert earth.gravity(np.pi / 2, 0.0) == pytest.approx(9.8321849378, abs=1e-9)
    # free-air gradient about -3.086e-6 s^-2 at mid latitudes
    grad = (earth.gravity(0.8, 1000.0) - earth.gravity(0.8, 0.0)) / 1000.0
    assert grad == pytest.approx(-3.086e-6, rel=2e-3)
    assert earth.gravity_nb(0.8, 1234.0) == pytest.approx(earth.gravity(0.8, 1234.0), rel=1e-15)


def test_transport_rate_of_a_northbound_vehicle():
    lat, h = np.deg2rad(30.0), 0.0
    rm, rn = earth.radii(lat)
    w = earth.omega_en_n(lat, h, np.array([0.0, 10.0, 0.0]))
    np.testing.assert_allclose(w, [-10.0 / rm, 0.0, 0.0])
    w = earth.omega_en_n(lat, h, np.array([10.0, 0.0, 0.0]))
    np.testing.assert_allclose(w, [0.0, 10.0 / rn, 10.0 * np.tan(lat) / rn])


def test_radii_and_gravity_at_once_agree_with_the_separate_functions():
    """The strapdown step's combined Earth model (one sqrt, one division) against the two
    separate functions: the same formulas, so equal to rounding (a few ulp)."""
    for lat, h in zip(LAT, H):
        s = np.sin(lat)
        rm, rn, g = earth.radii_gravity_sin_nb(s, h)
        rm_ref, rn_ref = earth.radii_sin_nb(s)
        assert rm == pytest.approx(rm_ref, rel=1e-15, abs=0)
        assert rn == pytest.approx(rn_ref, rel=1e-15, abs=0)
        assert g == pytest.approx(earth.gravity_sin_nb(s, h), rel=1e-15, abs=0)
