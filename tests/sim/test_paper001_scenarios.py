"""The paper001 scenario family: the paper's place, date, route and disturbance zone."""
import numpy as np
import pytest

from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import list_scenarios, load_scenario

FAMILY = ("paper001", "paper001-nodist", "paper001-strong", "paper001-outages",
          "paper001-mild", "paper001-double")


def test_family_is_listed():
    assert set(FAMILY) <= set(list_scenarios())


@pytest.fixture(scope="module")
def log():
    return simulate(load_scenario("paper001"), 0)


def test_place_date_and_route(log):
    scn = log.scenario
    assert (scn.start_lat_deg, scn.start_lon_deg) == (38.01868, 112.45152)
    assert scn.start_utc.date().isoformat() == "2021-03-05"
    t, v = log.truth.time_s, log.truth.vel_n
    travelled = np.sum(np.linalg.norm(v[:-1], axis=1) * np.diff(t))
    # 2 x (40 m of acceleration + 1 032 m straight) + a half circle of 8 m/s x 20 s
    assert travelled == pytest.approx(2 * (40.0 + 1032.0) + 160.0, abs=1.0)
    # out and back: the end is within a U-turn's diameter (2 x 160 m / pi) of the start
    lla = log.truth.lla
    d_north = (lla[-1, 0] - lla[0, 0]) * 6.37e6
    d_east = (lla[-1, 1] - lla[0, 1]) * 6.37e6 * np.cos(lla[0, 0])
    assert np.hypot(d_north, d_east) < 2 * 160.0 / np.pi + 1.0


def test_disturbance_sits_at_samples_200_to_300(log):
    mag = log.sensors["mag"]
    err = np.degrees(mag.meta["err_heading_rad"])
    k = np.arange(err.size)  # 1-Hz magnetometer: sample k at t = k s
    core = (k >= 210) & (k < 290)
    calm = (k < 195) | (k >= 305)
    assert np.all(np.abs(err[core] - 8.0) < 2.0)  # the zone's 8 deg, +- iron and noise
    assert np.all(np.abs(err[calm]) < 2.0)


def test_variants_change_what_they_say():
    strong = load_scenario("paper001-strong").sensors["mag"].disturbances
    assert [d.deflection_deg for d in strong] == [20.0]
    assert load_scenario("paper001-nodist").sensors["mag"].disturbances == ()
    out = load_scenario("paper001-outages").sensors["bds"].outages
    assert out == ((60.0, 90.0), (230.0, 260.0))
    assert load_scenario("paper001-outages").sensors["bds"].kind == "bds"
