"""Sun position against NREL SPA (pvlib) and against closed-form facts."""
import datetime as dt

import numpy as np
import pandas as pd
import pytest

from fuzzynav.sim import sun

pvlib = pytest.importorskip("pvlib")

LATS_DEG = (-75.0, -40.0, 0.0, 23.44, 38.0178, 60.0, 75.0)
TOL_DEG = 0.01


def _year(year, step="47min"):
    return pd.date_range(f"{year}-01-01", f"{year + 1}-01-01", freq=step, tz="UTC")


def _compare(times, lat_deg, lon_deg):
    ref = pvlib.solarposition.get_solarposition(times, lat_deg, lon_deg, altitude=0.0,
                                                delta_t=None)
    jd = sun.julian_day(times.tz_convert(None).to_numpy())
    mine = sun.sun_position(jd, np.radians(lat_deg), np.radians(lon_deg))
    return ref, mine


@pytest.mark.parametrize("year", [1975, 2024, 2049])
def test_elevation_and_azimuth_match_spa_over_a_year(year):
    rng = np.random.default_rng(year)
    times = _year(year)
    for lat in LATS_DEG:
        lon = rng.uniform(-180.0, 180.0)
        ref, mine = _compare(times, lat, lon)
        el = np.degrees(mine.elevation_rad)
        d_el = el - ref["elevation"].to_numpy()
        d_az = (np.degrees(mine.azimuth_rad) - ref["azimuth"].to_numpy() + 180.0) % 360.0 - 180.0
        assert np.abs(d_el).max() < TOL_DEG, (lat, np.abs(d_el).max())
        # azimuth is ill-defined at the zenith: compare it as an arc on the sky everywhere,
        # and as an angle wherever the sun is not within 20 deg of the zenith or nadir
        assert np.abs(d_az * np.cos(np.radians(el))).max() < TOL_DEG, lat
        low = np.abs(el) < 70.0
        assert np.abs(d_az[low]).max() < TOL_DEG, (lat, np.abs(d_az[low]).max())


def test_equation_of_time_declination_and_hour_angle_match_spa():
    times = _year(2024, "3h")
    lat, lon = 38.0178, 112.4447
    ref, mine = _compare(times, lat, lon)
    # SPA reports the equation of time in minutes
    d_eot_s = mine.equation_of_time_s - 60.0 * ref["equation_of_time"].to_numpy()
    assert np.abs(d_eot_s).max() < 2.0  # 2 s = 0.008 deg of hour angle
    # declination from SPA's alt-az by spherical trigonometry (topocentric: <= 0.0025 deg off)
    el, az, phi = np.radians(ref["elevation"]), np.radians(ref["azimuth"]), np.radians(lat)
    decl_ref = np.degrees(np.arcsin(np.sin(phi) * np.sin(el)
                                    + np.cos(phi) * np.cos(el) * np.cos(az)))
    assert np.abs(np.degrees(mine.declination_rad) - decl_ref).max() < TOL_DEG
    ha_ref = pvlib.solarposition.hour_angle(times, lon, ref["equation_of_time"].to_numpy())
    d_ha = (np.degrees(mine.hour_angle_rad) - ha_ref + 180.0) % 360.0 - 180.0
    assert np.abs(d_ha).max() < TOL_DEG


def test_apparent_elevation_matches_spa_refraction():
    times = _year(2024, "29min")
    ref, mine = _compare(times, 52.0, 5.0)
    app = np.degrees(mine.apparent_elevation_rad(1013.25, 12.0))
    up = ref["elevation"].to_numpy() > 1.0
    assert np.abs(app - ref["apparent_elevation"].to_numpy())[up].max() < TOL_DEG


def test_sun_vector_is_unit_and_consistent_with_angles():
    jd = sun.julian_day("2024-06-21T04:00:00Z") + np.linspace(0, 1, 50)
    sp = sun.sun_position(jd, np.radians(38.0), np.radians(112.4))
    s = sp.sun_n
    np.testing.assert_allclose(np.linalg.norm(s, axis=-1), 1.0, atol=1e-15)
    np.testing.assert_allclose(np.arcsin(s[:, 2]), sp.elevation_rad, atol=1e-12)
    np.testing.assert_allclose(np.arctan2(s[:, 0], s[:, 1]) % (2 * np.pi), sp.azimuth_rad,
                               atol=1e-12)
    # the numba scalar kernel gives the same vector
    for i in (0, 17, 49):
        np.testing.assert_allclose(sun.sun_vector_nb(jd[i], np.radians(38.0),
                                                     np.radians(112.4), sun.DELTA_T_S),
                                   s[i], atol=1e-15)


def test_solar_noon_geometry():
    # at local apparent noon the hour angle is zero and the sun is due south (north of the
    # tropics): elevation = 90 - |lat - decl|
    lat, lon = np.radians(38.0), np.radians(112.4)
    jd = sun.julian_day("2024-03-20T00:00:00Z") + np.linspace(0.0, 1.0, 20001)
    sp = sun.sun_position(jd, lat, lon)
    i = np.argmin(np.abs(sp.hour_angle_rad))
    assert abs(np.degrees(sp.azimuth_rad[i]) - 180.0) < 0.05
    assert abs(sp.elevation_rad[i] - (np.pi / 2 - abs(lat - sp.declination_rad[i]))) < 1e-4


def test_julian_day_reference_values():
    assert sun.julian_day(dt.datetime(2000, 1, 1, 12)) == 2451545.0
    # Meeus example 7.a: 1957 October 4.81 UT = JD 2436116.31
    jd = sun.julian_day(dt.datetime(1957, 10, 4, 19, 26, 24))
    assert abs(jd - 2436116.31) < 1e-9
    aware = dt.datetime(2024, 6, 21, 12, 0, tzinfo=dt.timezone(dt.timedelta(hours=8)))
    assert sun.julian_day(aware) == sun.julian_day("2024-06-21T04:00:00Z")
    stamps = pd.date_range("2023-03-05", periods=5, freq="7h")
    np.testing.assert_allclose(sun.julian_day(stamps.values),
                               [s.to_julian_date() for s in stamps], rtol=0, atol=1e-9)


def test_refraction_is_zero_below_the_horizon_and_half_a_degree_at_it():
    r = np.degrees(sun.refraction_rad(np.radians([-5.0, 0.0, 45.0, 90.0])))
    assert r[0] == 0.0
    assert 0.45 < r[1] < 0.50
    assert 0.010 < r[2] < 0.020
    assert abs(r[3]) < 1e-4
