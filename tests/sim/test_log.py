"""simulate(): determinism, independent component streams and the .npz cache."""
import numpy as np
import pytest

from fuzzynav.sim import sensor_log as simlog
from fuzzynav.sim.scenario import scenario_from_dict

DOC = {
    "name": "short",
    "start": {"lat_deg": 38.0, "lon_deg": 112.0, "h_m": 800.0},
    "imu": {"rate_hz": 100.0, "gyro_arw_dpsh": 0.1, "gyro_bias_sigma_dph": 1.0,
            "accel_vrw_ug_psqrthz": 50.0, "accel_bi_sigma_ug": 20.0, "accel_bi_tau_s": 100.0},
    "segments": [{"kind": "static", "duration_s": 5.0},
                 {"kind": "accelerate", "duration_s": 10.0, "speed_change_mps": 10.0},
                 {"kind": "turn", "duration_s": 10.0, "turn_deg": 90.0, "bank": True}],
    "sensors": {"gps": {"kind": "gnss", "rate_hz": 2.0, "outlier_rate": 0.1,
                        "outlier_pos_m": 10.0, "lever_arm_b_m": [0.0, 1.0, 0.5]}},
}


def scenario(**sensors):
    doc = {**DOC, "sensors": {**DOC["sensors"], **sensors}}
    return scenario_from_dict(doc)


def assert_same(a, b):
    for k in ("time_s", "lla", "vel_n", "att", "q_bn", "dtheta_b", "dv_b", "omega_nb_b"):
        np.testing.assert_array_equal(getattr(a.truth, k), getattr(b.truth, k))
    for k in ("time_s", "dtheta_b", "dv_b", "gyro_bias_rps", "accel_bias_mps2"):
        np.testing.assert_array_equal(getattr(a.imu, k), getattr(b.imu, k))
    assert sorted(a.sensors) == sorted(b.sensors)
    for name in a.sensors:
        x, y = a.sensors[name], b.sensors[name]
        assert x.kind == y.kind
        for k in ("time_s", "z", "sigma"):
            np.testing.assert_array_equal(getattr(x, k), getattr(y, k))
        assert sorted(x.meta) == sorted(y.meta)
        for k in x.meta:
            np.testing.assert_array_equal(x.meta[k], y.meta[k])
    for k in a.imu.meta:
        np.testing.assert_array_equal(a.imu.meta[k], b.imu.meta[k])


def test_same_seed_same_data_other_seed_other_data():
    s = scenario()
    a, b, c = simlog.simulate(s, 1), simlog.simulate(s, 1), simlog.simulate(s, 2)
    assert_same(a, b)
    assert not np.array_equal(a.imu.dtheta_b, c.imu.dtheta_b)
    assert not np.array_equal(a.sensors["gps"].z, c.sensors["gps"].z)


def test_adding_a_sensor_changes_nobody_elses_noise():
    a = simlog.simulate(scenario(), 7)
    b = simlog.simulate(scenario(gps2={"kind": "gnss", "rate_hz": 1.0}), 7)
    np.testing.assert_array_equal(a.imu.dtheta_b, b.imu.dtheta_b)
    np.testing.assert_array_equal(a.imu.dv_b, b.imu.dv_b)
    np.testing.assert_array_equal(a.sensors["gps"].z, b.sensors["gps"].z)
    assert "gps2" in b.sensors


def test_cache_returns_identical_arrays_without_recomputing(tmp_path, monkeypatch):
    s = scenario()
    first = simlog.simulate(s, 3, cache_dir=tmp_path)
    files = list(tmp_path.glob("*.npz"))
    assert len(files) == 1 and files[0].name.startswith("short-3-")

    def boom(*args):
        raise AssertionError("regenerated although the cache is valid")

    monkeypatch.setattr(simlog, "_generate", boom)
    again = simlog.simulate(s, 3, cache_dir=tmp_path)
    assert_same(first, again)
    assert again.truth.segments == s.segments
    assert not list(tmp_path.glob("*.tmp"))


@pytest.mark.parametrize("damage", ["garbage", "truncate", "other-key", "empty"])
def test_a_damaged_cache_file_is_regenerated(tmp_path, damage):
    s = scenario()
    fresh = simlog.simulate(s, 4)
    path = simlog.cache_path(tmp_path, s, 4)
    simlog.simulate(s, 4, cache_dir=tmp_path)
    data = path.read_bytes()
    if damage == "garbage":
        path.write_bytes(b"not a zip file at all" * 10)
    elif damage == "truncate":
        path.write_bytes(data[: len(data) // 2])
    elif damage == "empty":
        path.write_bytes(b"")
    else:  # a well-formed file made for another key must not be believed
        other = simlog.simulate(s, 5)
        simlog._write_cache(path, simlog._to_arrays(other, "0" * 64))
    log = simlog.simulate(s, 4, cache_dir=tmp_path)
    assert_same(fresh, log)
    with np.load(path, allow_pickle=False) as npz:  # and the file is good again
        assert str(npz["key"]) == simlog.cache_key(s, 4)


def test_cache_key_depends_on_seed_data_and_version(monkeypatch):
    s = scenario()
    k = simlog.cache_key(s, 1)
    assert simlog.cache_key(s, 2) != k
    assert simlog.cache_key(scenario(gps={"kind": "gnss", "rate_hz": 1.0}), 1) != k
    renamed = scenario_from_dict({**DOC, "name": "renamed", "description": "words"})
    assert simlog.cache_key(renamed, 1) == k
    monkeypatch.setattr(simlog, "DATA_VERSION", simlog.DATA_VERSION + 1)
    assert simlog.cache_key(s, 1) != k


def test_imu_truth_matches_the_applied_errors():
    log = simlog.simulate(scenario(), 8)
    # the accelerometer error minus white noise and GM integral is the turn-on bias only for
    # the gyro here (no gyro GM): mean gyro error per second equals the turn-on bias
    err = (log.imu.dtheta_b - log.truth.dtheta_b) * 100.0
    on = log.imu.meta["gyro_turn_on_rps"]
    noise_sd = 0.1 * np.pi / 180 / 60 * np.sqrt(100.0) / np.sqrt(err.shape[0])
    assert np.all(np.abs(err.mean(0) - on) < 6 * noise_sd)
    np.testing.assert_allclose(log.imu.gyro_bias_rps, np.tile(on, (err.shape[0] + 1, 1)))


def test_negative_seed_is_refused():
    with pytest.raises(ValueError):
        simlog.simulate(scenario(), -1)


def test_meta_that_would_need_a_pickle_is_refused(tmp_path):
    log = simlog.simulate(scenario(), 9)
    log.sensors["gps"].meta["bad"] = {"a": 1}
    with pytest.raises(TypeError, match="sensor.gps.meta.bad"):
        simlog._to_arrays(log, "k")
