"""Filters on sensor subsets: the generic ``sensors`` option, paper 001's pairs, centralized."""
import numpy as np
import pytest

from fuzzynav.papers.claims import claims_for
from fuzzynav.errors import FuzzynavError
from fuzzynav.experiment import run_on_log, setup_for
from fuzzynav.filters.named import select_sensors
from fuzzynav.filters.runner import run_filter
from fuzzynav.experiment import perturbed_initial_state
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import load_scenario


@pytest.fixture(scope="module")
def log():
    return simulate(load_scenario("paper001"), 0)


def test_select_by_name_or_kind_and_refuse_unknown(log):
    assert set(select_sensors(log.sensors, ["bds", "polarization"])) == {"bds", "pol"}
    assert set(select_sensors(log.sensors, "mag")) == {"mag"}
    with pytest.raises(FuzzynavError, match="'gps'.*bds \\(bds\\)"):
        select_sensors(log.sensors, ["gps"])


@pytest.mark.parametrize("name,used", [("ekf-bds-pol", {"bds", "pol"}),
                                        ("ekf-bds-mag", {"bds", "mag"}),
                                        ("ekf-pol-mag", {"pol", "mag"}),
                                        ("centralized", {"bds", "pol", "mag"})])
def test_pairs_use_their_sensors_only(log, name, used):
    out = run_on_log(log, name)
    assert set(out.result.events) == used


def test_subset_run_equals_the_ekf_on_the_subset_log(log):
    """ekf-bds-mag is the EKF run on a log holding only those two sensors."""
    sub = {k: log.sensors[k] for k in ("bds", "mag")}
    setup = setup_for(log, "ekf")
    init = perturbed_initial_state(log, setup)
    direct = run_filter(log.imu, sub, init, setup.config)
    out = run_on_log(log, "ekf-bds-mag").result
    # the same computation on the same inputs (kernel and data identical): equal to rounding
    np.testing.assert_allclose(out.lla, direct.lla, rtol=0, atol=1e-12)


def test_sensors_option_applies_to_any_filter_and_to_its_adapters(log):
    setup = setup_for(log, "sage-husa", {"sensors": ["magnetometer"]})
    assert set(setup.adapters) == {"mag"}
    assert set(setup.sensors_for(log.sensors)) == {"mag"}


def test_fuzzy_mag_binds_the_magnetometer_rules(log):
    setup = setup_for(log, "fuzzy-mag")
    assert set(setup.adapters) == {"mag"}
    assert set(setup.sensors_for(log.sensors)) == {"bds", "pol", "mag"}
    assert setup_for(log, "fuzzy-bds-mag").sensors_for(log.sensors).keys() == {"bds", "mag"}


def test_paper001_family_prints_the_paper_claims():
    labels, table = claims_for("paper001-strong")
    assert labels[0].startswith("paper combined")
    assert table["rms_pos_e_m"][0] == "3.2305" and table["rms_pos_n_m"][0] == "3.7419"


@pytest.mark.parametrize("rules", [None, "rules/paper001_mag_tuned.json"])
def test_fuzzy_magnetometer_r_keeps_the_heading_through_the_disturbance(log, rules):
    """The 8-deg anomaly pulls a centralized EKF's heading off by over a degree; the fuzzy
    R-scaling (hand or tuned) inflates the magnetometer's R and stays near the polarization
    compass's accuracy (well under 0.3 deg)."""
    from fuzzynav.metrics import errors_vs_trajectory

    def zone_rms(name, opts=None):
        res = run_on_log(log, name, opts).result
        err = errors_vs_trajectory(res, log.truth)
        inside = (err.time_s >= 200.0) & (err.time_s < 300.0)
        return np.degrees(np.sqrt(np.mean(err.att_rad[inside, 2] ** 2)))

    plain = zone_rms("centralized")
    fuzzy = zone_rms("fuzzy-mag", {"rules": [rules]} if rules else None)
    assert plain > 1.0 and fuzzy < 0.3
