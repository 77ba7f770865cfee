"""Magnetometer simulation: the field model against published values, the compass heading
and its error sources (disturbance zones, hard iron), and the scenario table."""
import datetime as dt
from pathlib import Path

import numpy as np
import ppigrf
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.sim import geomag
from fuzzynav.sim.sensors import spec_class
from fuzzynav.sim.sensors.magnetometer import Spec
from tests.sim.test_polarization import _trajectory

# NOAA/NCEI geomagnetic calculator (IGRF2020 model, calculator 0.5.1.11) at 38 N 112 E,
# 5 km above the WGS-84 ellipsoid, as published in ppigrf's test data
# (test/data/<date>/b_e.csv, b_n.csv, b_z.csv; Z is downwards) [nT]
NCEI = {dt.datetime(2020, 1, 1): (-2755.5, 29054.2, 45733.7),
        dt.datetime(2022, 10, 5): (-2901.0, 29006.2, 45910.0)}
LAT, LON = np.radians(38.01868), np.radians(112.45152)
DATE = dt.datetime(2021, 3, 5, 2, 0, tzinfo=dt.timezone.utc)


@pytest.mark.parametrize("when", sorted(NCEI))
def test_igrf_field_matches_the_ncei_calculator(when):
    east, north, down = NCEI[when]
    place = (np.radians(38.0), np.radians(112.0), 5000.0, when)
    igrf13 = Path(ppigrf.__file__).parent / "IGRF13.shc"
    f13 = geomag.field_enu_t(*place, coeff_file=igrf13) / 1e-9
    # the calculator's model with the same coefficients: components, signs and units agree
    # to 2 nT (ppigrf interpolates the coefficients in time its own way: 1.5 nT seen in
    # 2022, ten days of the -53 nT/yr change here, 0.003 deg of declination)
    np.testing.assert_allclose(f13[0], [east, north, -down], atol=2.0)
    # the default IGRF-14 revised the 2020-2025 secular variation: tens of nT here
    f = geomag.field_enu_t(*place) / 1e-9
    np.testing.assert_allclose(f[0], [east, north, -down], atol=100.0)
    deg = np.degrees  # the declination the compass corrects by
    assert deg(geomag.declination_rad(f13))[0] == pytest.approx(
        deg(np.arctan2(east, north)), abs=0.01)


def test_dipole_inclination_follows_tan_i_equals_two_tan_latitude():
    axial = {"g10": -30000.0, "g11": 0.0, "h11": 0.0}  # a dipole along the rotation axis
    lat = np.radians([-60.0, -10.0, 0.0, 25.0, 38.0, 70.0])
    f = geomag.dipole_enu_t(lat, np.radians(112.0), 0.0, axial)
    np.testing.assert_allclose(np.tan(geomag.inclination_rad(f)), 2.0 * np.tan(lat),
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(f[:, 0], 0.0, atol=1e-20)  # no declination
    # the IGRF-2020 dipole at the paper-001 place against ppigrf's IGRF-13 cut at degree 1
    # (geodetic, exact radius): our geocentric shortcut costs ~0.2 deg of latitude, < 1 %
    be, bn, bu = ppigrf.igrf(np.degrees(LON), np.degrees(LAT), 0.8, dt.datetime(2020, 1, 1),
                             coeff_fn=str(Path(ppigrf.__file__).parent / "IGRF13.shc"),
                             max_degree=1)
    ref = np.array([be, bn, bu]).ravel() * 1e-9
    dip = geomag.dipole_enu_t(LAT, LON, 800.0)[0]
    assert np.linalg.norm(dip - ref) < 0.01 * np.linalg.norm(ref)


def _turning(n=361, rate_hz=1.0):
    att = np.column_stack([np.zeros(n), np.zeros(n), np.radians(np.arange(n) % 360.0)])
    return _trajectory(att, rate_hz, LAT, LON)


def test_disturbance_zone_bends_the_heading_by_its_deflection():
    zone = {"start_s": 100.0, "end_s": 200.0, "deflection_deg": 6.0, "ramp_s": 10.0}
    spec = Spec.from_dict({"kind": "magnetometer", "rate_hz": 1.0, "noise_nt": 0.0,
                           "claimed_sigma_deg": 0.5, "disturbances": [zone]}, "sensors.mag")
    d = spec.simulate(_turning(), np.random.default_rng(0), DATE)
    err = np.degrees(d.meta["err_heading_rad"])
    t = d.time_s
    np.testing.assert_allclose(err[(t >= 110) & (t < 190)], 6.0, atol=1e-9)
    np.testing.assert_allclose(err[(t < 100) | (t >= 200)], 0.0, atol=1e-9)
    ramp = (t > 100) & (t < 110)
    assert np.all((err[ramp] > 0.0) & (err[ramp] < 6.0)) and np.all(np.diff(err[ramp]) > 0)


def test_sample_range_zone_and_hard_iron_one_cycle_error():
    hard = 500.0  # nT along body x (right)
    spec = Spec.from_dict({"kind": "magnetometer", "rate_hz": 1.0, "noise_nt": 0.0,
                           "claimed_sigma_deg": 1.0, "hard_iron_nt": [hard, 0.0, 0.0], "field_model": "dipole",
                           "disturbances": [{"start_sample": 200, "end_sample": 300,
                                             "deflection_deg": 3.0, "ramp_s": 0.0}]},
                          "sensors.mag")
    assert (spec.disturbances[0].start_s, spec.disturbances[0].end_s) == (200.0, 300.0)
    d = spec.simulate(_turning(), np.random.default_rng(0), DATE)
    field = geomag.dipole_enu_t(LAT, LON, 825.0)[0] / 1e-9
    H = np.hypot(field[0], field[1])
    t = d.time_s
    zone = np.where((t >= 200) & (t < 300), np.radians(3.0), 0.0)
    # the field's azimuth seen from the vehicle (turned by the zone)
    alpha = geomag.declination_rad(field)[0] - zone - np.radians(np.arange(361) % 360.0)
    # level sensor: field (H sin a + b, H cos a) in (right, forward); the compass reads the
    # angle of that vector, so the heading is off by a - atan2(H sin a + b, H cos a), plus
    # the zone's turn
    expected = alpha - np.arctan2(H * np.sin(alpha) + hard, H * np.cos(alpha)) + zone
    expected = np.angle(np.exp(1j * expected))
    np.testing.assert_allclose(d.meta["err_heading_rad"], expected, atol=1e-9)
    # one-cycle: the amplitude is about b / H
    assert np.max(np.abs(expected[t < 200])) == pytest.approx(hard / H, rel=0.05)


def test_noise_gives_the_claimed_heading_sigma():
    spec = Spec(rate_hz=1.0, noise_nt=150.0)
    d = spec.simulate(_turning(3601), np.random.default_rng(1), DATE)
    err = d.meta["err_heading_rad"]
    # level sensor: heading noise = per-axis noise / H; 3600 samples: +-2.4 % at 2 sigma
    assert np.std(err) == pytest.approx(d.sigma[0, 0], rel=0.06)
    assert np.all(np.isfinite(d.z[:, 1:])) and d.z.shape == (3601, 4)


@pytest.mark.parametrize("table,key", [
    ({"noise_nt": -1.0}, "sensors.mag.noise_nt"),
    ({"soft_iron": [[1, 0, 0], [0, 1, 0], [0, 0, 0]]}, "sensors.mag.soft_iron"),
    ({"field_model": "wmm"}, "sensors.mag.field_model"),
    ({"disturbances": [{"start_s": 10.0, "end_s": 5.0}]}, "sensors.mag.disturbances[0].end_s"),
    ({"disturbances": [{"start_s": 0.0, "end_s": 5.0, "ramp_s": 4.0}]},
     "sensors.mag.disturbances[0].ramp_s"),
    ({"disturbances": [{"start_s": 0.0, "end_s": 50.0, "deflection": 4.0}]},
     "sensors.mag.disturbances[0].deflection"),
])
def test_bad_tables_name_the_key(table, key):
    with pytest.raises(InputFileError) as e:
        spec_class("magnetometer").from_dict({"kind": "magnetometer", **table}, "sensors.mag")
    assert key in str(e.value)


def test_table_round_trip():
    d = {"kind": "magnetometer", "rate_hz": 2.0, "hard_iron_nt": [1.0, 2.0, 3.0],
         "disturbances": [{"start_s": 1.0, "end_s": 30.0, "deflection_deg": -4.0}]}
    spec = Spec.from_dict(d, "s")
    assert Spec.from_dict(spec.to_dict(), "s") == spec
