"""Scenario files: the built-in paper000, round trips, inheritance and one error per problem."""
import numpy as np
import pytest

from fuzzynav.errors import DataMissingError, InputFileError, UnknownNameError
from fuzzynav.sim.scenario import list_scenarios, load_scenario, scenario_from_dict
from fuzzynav.sim.trajectory import generate

MINIMAL = """
name = "mini"
[start]
lat_deg = 30.0
lon_deg = 110.0
[imu]
rate_hz = 100
[[segments]]
kind = "static"
duration_s = 10
[sensors.gps]
kind = "gnss"
"""


@pytest.fixture(scope="module")
def paper000():
    return load_scenario("paper000")


def test_paper000_is_built_in(paper000):
    assert "paper000" in list_scenarios()
    assert (paper000.start_lon_deg, paper000.start_lat_deg, paper000.start_h_m) == \
        (112.4447, 38.0178, 825.0)
    assert paper000.imu.gyro_bias_dph == (1.0, 1.0, 1.0)
    gps = paper000.sensors["gps"]
    assert gps.kind == "gnss" and gps.rate_hz == 1.0 and gps.velocity
    kinds = {s.kind for s in paper000.segments}
    assert {"static", "accelerate", "turn", "climb"} <= kinds
    assert kinds & {"figure8", "s-turns"}
    assert paper000.segments[0].kind == "static"


def test_paper000_trajectory_is_three_dimensional_and_long_enough(paper000):
    truth = generate(paper000.start_lla_rad, paper000.segments, 10.0)
    assert truth.duration_s >= 600.0
    h = truth.lla[:, 2]
    assert h.max() - h.min() > 50.0                        # climb and dive
    assert np.ptp(np.rad2deg(truth.att[:, 1])) > 10.0     # banked turns
    assert np.linalg.norm(truth.vel_n[: 10 * 60], axis=1).max() == 0.0  # static start
    heading_rate = np.abs(np.diff(np.unwrap(truth.att[:, 2])))
    assert heading_rate.sum() > 4 * np.pi                  # at least two full circles of turning


def test_round_trip_through_the_canonical_table(paper000):
    again = scenario_from_dict(paper000.to_dict())
    assert again == paper000
    assert again.canonical() == paper000.canonical()


def test_canonical_form_ignores_name_but_not_data(paper000):
    d = paper000.to_dict()
    d["name"], d["description"] = "other", "other words"
    assert scenario_from_dict(d).canonical() == paper000.canonical()
    d["sensors"]["gps"]["rate_hz"] = 2.0
    assert scenario_from_dict(d).canonical() != paper000.canonical()


def write(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_minimal_file_and_defaults(tmp_path):
    s = load_scenario(write(tmp_path, MINIMAL))
    assert s.name == "mini" and s.start_h_m == 0.0 and s.start_utc.year == 2024
    assert s.sensors["gps"].pos_sigma_m == (1.5, 1.5, 3.0)


@pytest.mark.parametrize("edit, where, what", [
    (("[start]", "colour = 3\n[start]"), "colour", "unknown key"),
    (("rate_hz = 100", 'rate_hz = "fast"'), "imu.rate_hz", "must be a number"),
    (("rate_hz = 100", "rate_hz = 100\ngyro_arw_dpsh = -1"), "imu.gyro_arw_dpsh", "must lie"),
    (('kind = "static"', 'kind = "hover"'), "segments[0].kind", "must be one of"),
    (("duration_s = 10", "duration_s = -10"), "segments[0].duration_s", "must lie"),
    (("duration_s = 10", "duration_s = 10\nturn_dg = 3"), "segments[0].turn_dg", "unknown key"),
    (('kind = "gnss"', 'kind = "lidar"'), "sensors.gps.kind", "unknown sensor kind 'lidar'"),
    (('kind = "gnss"', 'kind = "gnss"\nrate = 2'), "sensors.gps.rate", "unknown key"),
    (("lat_deg = 30.0", "lat_deg = 95.0"), "start.lat_deg", "must lie"),
    (("lat_deg = 30.0", ""), "start.lat_deg", "missing required key"),
    (("[sensors.gps]", "[sensors.'bad name']"), "sensors.bad name", "sensor name"),
    (('name = "mini"', 'name = "mini"\n[start]\nlat_deg = 1'), "", "invalid TOML"),
    (('[start]', 'utc = 2024-01-01T00:00:00\n[start]'), "utc", "unknown key"),
])
def test_every_problem_names_file_and_key(tmp_path, edit, where, what):
    path = write(tmp_path, MINIMAL.replace(*edit, 1))
    with pytest.raises(InputFileError) as exc:
        load_scenario(path)
    assert exc.value.path == str(path)
    assert exc.value.where == where
    assert what in exc.value.what
    assert str(path) in str(exc.value)


def test_local_time_without_offset_is_refused(tmp_path):
    path = write(tmp_path, MINIMAL.replace("lon_deg = 110.0",
                                           "lon_deg = 110.0\nutc = 2024-01-01T00:00:00"))
    with pytest.raises(InputFileError, match="UTC offset") as exc:
        load_scenario(path)
    assert exc.value.where == "start.utc"


def test_motion_errors_are_reported_at_load_time(tmp_path):
    text = MINIMAL.replace('kind = "static"', 'kind = "turn"\nturn_deg = 90')
    with pytest.raises(InputFileError, match="moving vehicle") as exc:
        load_scenario(write(tmp_path, text))
    assert exc.value.where == "segments[0]"


def test_unknown_names_and_missing_files():
    with pytest.raises(UnknownNameError, match="paper000"):
        load_scenario("paper999")
    with pytest.raises(DataMissingError, match="nowhere.toml"):
        load_scenario("/nowhere/nowhere.toml")


def test_a_misspelt_sensor_of_the_base_is_named(tmp_path):
    """[sensors.gpz] in a file derived from paper000 is a new sensor without a kind: the
    message lists the kinds and names the base's sensor it resembles."""
    bad = write(tmp_path, 'base = "paper000"\n[sensors.gpz]\nrate_hz = 1.0\n', "bad.toml")
    with pytest.raises(InputFileError) as exc:
        load_scenario(bad)
    assert exc.value.where == "sensors.gpz.kind"
    assert "needs kind = one of" in str(exc.value) and "gnss" in str(exc.value)
    assert "the sensor 'gps', misspelt?" in str(exc.value)


def test_a_file_can_derive_from_a_built_in(tmp_path, paper000):
    path = write(tmp_path, 'base = "paper000"\n[sensors.gps]\noutlier_rate = 0.02\n'
                           'outlier_pos_m = 20.0\n', "variant.toml")
    s = load_scenario(path)
    assert s.name == "variant"
    assert s.segments == paper000.segments and s.imu == paper000.imu
    assert s.sensors["gps"].outlier_rate == 0.02
    assert s.sensors["gps"].pos_sigma_m == paper000.sensors["gps"].pos_sigma_m
    bad = write(tmp_path, 'base = "paper000"\n[sensors.gps]\noutlier_rat = 0.02\n', "bad.toml")
    with pytest.raises(InputFileError) as exc:
        load_scenario(bad)
    assert exc.value.path == str(bad) and exc.value.where == "sensors.gps.outlier_rat"
