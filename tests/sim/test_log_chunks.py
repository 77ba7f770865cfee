"""A cached whole log in chunks is the simulated chunks to the last bit.

:class:`fuzzynav.sim.log_chunks.LogChunks` against
:class:`fuzzynav.sim.stream.SimulatedChunks`, chunk by chunk, header by header, on every
paper's scenario family (cut short): every truth, IMU and sensor array and every ``meta``
entry, and the whole-run figure left out of a run of several chunks alike.
"""
import numpy as np
import pytest

from fuzzynav.sim import budget
from fuzzynav.sim.log_chunks import LogChunks, chunks_of
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.stream import SimulatedChunks

from .test_stream import _IMU, _TRUTH, short


def _same_data(a, b, where):
    assert a.kind == b.kind, where
    for f in ("time_s", "z", "sigma"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f"{where}.{f}")
    assert a.meta.keys() == b.meta.keys(), where
    for k in a.meta:
        np.testing.assert_array_equal(np.asarray(a.meta[k]), np.asarray(b.meta[k]),
                                      err_msg=f"{where}.meta.{k}")


def assert_same_chunks(cut, made):
    assert cut.header.keys() == made.header.keys()
    for nm in made.header:
        _same_data(cut.header[nm], made.header[nm], f"header {nm}")
    cut, made = list(cut), list(made)
    assert [(c.k0, c.k1) for c in cut] == [(c.k0, c.k1) for c in made]
    for a, b in zip(cut, made):
        for f in _TRUTH + _IMU:
            np.testing.assert_array_equal(getattr(a.truth, f), getattr(b.truth, f), err_msg=f)
        for f in _IMU + ("time_s", "gyro_bias_rps", "accel_bias_mps2"):
            np.testing.assert_array_equal(getattr(a.imu, f), getattr(b.imu, f), err_msg=f)
        assert a.sensors.keys() == b.sensors.keys()
        for nm in a.sensors:
            _same_data(a.sensors[nm], b.sensors[nm], f"chunk {a.k0} {nm}")
    return made


@pytest.mark.parametrize("name, seconds_per_chunk", [
    ("paper000", 9.97), ("paper001", 10.0), ("paper003", 9.97), ("paper003-clouds", 10.0),
    ("paper004", 9.97)])
def test_a_cached_log_cut_in_chunks_is_the_simulated_chunks(name, seconds_per_chunk):
    scn = short(name)
    chunk = int(round(seconds_per_chunk * scn.imu.rate_hz))
    made = assert_same_chunks(LogChunks(simulate(scn, 2), chunk),
                              SimulatedChunks(scn, 2, chunk))
    assert len(made) >= 9


def test_one_chunk_keeps_the_whole_run_figure():
    scn = short("paper003", 20.0)
    made = assert_same_chunks(LogChunks(simulate(scn, 0), 10**6),
                              SimulatedChunks(scn, 0, 10**6))
    assert len(made) == 1 and "true_sigma" in made[0].sensors["nhc"].meta


def test_the_cache_is_read_only_when_it_is_there_and_fits(tmp_path, monkeypatch):
    scn = short("paper000", 20.0)
    assert isinstance(chunks_of(scn, 4, 500, tmp_path), SimulatedChunks)
    assert not any(tmp_path.iterdir())  # a streamed run writes no cache
    simulate(scn, 4, tmp_path)
    assert isinstance(chunks_of(scn, 4, 500, tmp_path), LogChunks)
    assert isinstance(chunks_of(scn, 4, 500), SimulatedChunks)
    monkeypatch.setattr(budget, "TRUTH_STORE_BYTES", 1000.0)  # a file larger than that
    assert isinstance(chunks_of(scn, 4, 500, tmp_path), SimulatedChunks)
    monkeypatch.undo()
    next(tmp_path.iterdir()).write_bytes(b"damaged")
    assert isinstance(chunks_of(scn, 4, 500, tmp_path), SimulatedChunks)
    lc = LogChunks(simulate(scn, 4), 500)
    list(lc)
    with pytest.raises(RuntimeError, match="iterated once"):
        list(lc)
    with pytest.raises(ValueError, match="positive integer"):
        LogChunks(simulate(scn, 4), 0)
