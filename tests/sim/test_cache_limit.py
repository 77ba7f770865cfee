"""A log above the cache-file limit is not written but simulated again: the same data."""
import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.sim import budget
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.sim.sensor_log import cache_path, simulate


def _same(a, b):
    assert np.array_equal(a.imu.dtheta_b, b.imu.dtheta_b)
    assert np.array_equal(a.imu.dv_b, b.imu.dv_b)
    assert a.sensors.keys() == b.sensors.keys()
    for name in a.sensors:
        assert np.array_equal(a.sensors[name].z, b.sensors[name].z, equal_nan=True), name


def test_log_above_the_limit_is_not_cached_and_regenerates_identically(tmp_path, monkeypatch,
                                                                      capsys):
    scn = load_scenario("paper000")
    monkeypatch.setenv(budget.CACHE_ENV_VAR, "0.001")  # 1 kB: every log is larger
    first = simulate(scn, 3, tmp_path)
    assert not cache_path(tmp_path, scn, 3).exists()
    assert list(tmp_path.iterdir()) == []  # no temporary file left either
    assert "not cached: paper000 seed 3" in capsys.readouterr().err
    _same(first, simulate(scn, 3, tmp_path))
    monkeypatch.delenv(budget.CACHE_ENV_VAR)
    cached = simulate(scn, 3, tmp_path)  # under the default limit: written, then read
    assert cache_path(tmp_path, scn, 3).is_file()
    _same(first, cached)
    _same(first, simulate(scn, 3, tmp_path))


@pytest.mark.parametrize("value", ["0", "-5", "lots", "inf"])
def test_bad_limit_is_one_clear_error(monkeypatch, value):
    monkeypatch.setenv(budget.CACHE_ENV_VAR, value)
    with pytest.raises(InputFileError, match=f"{budget.CACHE_ENV_VAR}.*positive number of MB"):
        budget.cache_file_limit()


def test_default_limit(monkeypatch):
    monkeypatch.delenv(budget.CACHE_ENV_VAR, raising=False)
    assert budget.cache_file_limit() == budget.DEFAULT_CACHE_FILE_MB * 2**20
