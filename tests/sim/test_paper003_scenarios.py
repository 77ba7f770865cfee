"""The paper003 scenario family loads, carries the paper's figures and its variants differ as
their files say; the claims are registered for the family."""
import numpy as np
import pytest

from fuzzynav.papers.claims import find_claims
from fuzzynav.sim.scenario import list_scenarios, load_scenario, scenario_from_dict

VARIANTS = ("paper003", "paper003-current", "paper003-clouds", "paper003-noon", "paper003-storm")


def test_family_is_built_in_and_has_the_papers_figures():
    assert set(VARIANTS) <= set(list_scenarios())
    s = load_scenario("paper003")
    assert s.duration_s == pytest.approx(1800.0)
    assert (s.start_lat_deg, s.start_lon_deg) == (28.68, 115.89)
    assert s.imu.rate_hz == 50.0 and s.imu.filter_states == "markov"
    assert s.imu.gyro_bias_dph == (10.0, 10.0, 10.0) and s.imu.gyro_bi_tau_s == 600.0
    assert s.imu.accel_bi_sigma_ug == 3000.0 and s.imu.accel_bi_tau_s == 1200.0
    log = s.sensors["log"]
    assert (log.noise_mps, log.bias_mps, log.rate_hz) == (0.5, 0.5, 50.0)
    assert s.sensors["nhc"].sigma_mps == 0.2 and s.sensors["pol"].angle_noise_rad == 0.005


def test_variants_change_only_what_they_say():
    base = load_scenario("paper003")
    cur = load_scenario("paper003-current")
    assert cur.sea.current_changes == ((600.0, 700.0, 0.8, -0.6),)
    assert cur.segments == base.segments and cur.sensors == base.sensors
    assert load_scenario("paper003-clouds").sensors["pol"].clouds[1][2] == 0.0
    assert load_scenario("paper003-noon").start_utc.hour == 3


def test_scenario_round_trips_with_sea_and_filter_states():
    s = load_scenario("paper003-storm")
    again = scenario_from_dict(s.to_dict())
    assert again.canonical() == s.canonical() and again.sea == s.sea


def test_claims_cover_the_family():
    c = find_claims("paper003-noon")
    assert c is not None and c.prefix == "paper003"
    assert {k for _, k in c.rows} >= {"rms_heading_deg", "rms_vel_h_mps", "rms_pos_h_m"}
    assert np.all([k in c.table for k in ("rms_heading_deg", "rms_vel_h_mps", "rms_pos_h_m")])
