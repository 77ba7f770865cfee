"""A run fed in chunks of the IMU is the whole run, to the last bit.

The compiled loop carries everything it keeps between samples across chunk boundaries
(:class:`fuzzynav.filters.runner.FilterRun`); these tests run each paper's scenario family
whole and in chunks whose boundaries fall on measurement epochs and between them, and
compare every recorded array, every event log and every metric exactly.
"""
import dataclasses

import numpy as np
import pytest

from fuzzynav.errors import FuzzynavError
from fuzzynav.experiment import SimulatedSource
from fuzzynav.filters.runner import FilterRun
from fuzzynav.runpath import make_setup, run
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.sim.sensor_log import simulate

_ARRAYS = ("time_s", "lla", "vel_n", "q_bn", "sensor_states", "sigma")
_EVENTS = ("time_s", "residual", "S_diag", "nis", "flag", "diag")


def _log(name, sim_cache, seconds=None):
    """The scenario's log for seed 0; ``seconds``: its first seconds only (a shorter run)."""
    log = simulate(load_scenario(name), 0, sim_cache)
    if seconds is None:
        return log
    n = int(np.searchsorted(log.imu.time_s, log.imu.time_s[0] + seconds))
    imu = log.imu
    short = dataclasses.replace(imu, time_s=imu.time_s[:n + 1], dtheta_b=imu.dtheta_b[:n],
                                dv_b=imu.dv_b[:n], gyro_bias_rps=imu.gyro_bias_rps[:n + 1],
                                accel_bias_mps2=imu.accel_bias_mps2[:n + 1])
    return dataclasses.replace(log, imu=short)


def assert_same_run(a, b):
    """Every recorded array, local state, event log field and metric equal to the bit."""
    ra, rb = a.result, b.result
    assert ra.status == rb.status
    for f in _ARRAYS:
        np.testing.assert_array_equal(getattr(ra, f), getattr(rb, f), err_msg=f)
    for f in ("x", "sigma", "P_end", "P_fused", "beta"):
        np.testing.assert_array_equal(getattr(ra.locals, f), getattr(rb.locals, f),
                                      err_msg=f"locals.{f}")
    assert sorted(ra.events) == sorted(rb.events)
    for nm in ra.events:
        for f in _EVENTS:
            np.testing.assert_array_equal(getattr(ra.events[nm], f),
                                          getattr(rb.events[nm], f), err_msg=f"{nm}.{f}")
    assert a.metrics.keys() == b.metrics.keys()
    for k in a.metrics:  # NaN == NaN here: a metric without truth is NaN both ways
        assert np.array_equal(a.metrics[k], b.metrics[k], equal_nan=True), k


def _epoch_spacing(log):
    """IMU samples between the first sensor's epochs (a chunk of it ends on each epoch)."""
    dt = float(np.median(np.diff(log.imu.time_s)))
    period = min(float(np.median(np.diff(d.time_s))) for d in log.sensors.values())
    return int(round(period / dt))


@pytest.mark.parametrize("scenario, filt, seconds", [
    ("paper000", "ekf", None),
    ("paper000", "fakf", None),
    ("paper000", "sage-husa", 200.0),
    ("paper003", "ekf", 600.0),
    ("paper003", "fuzzy-ship", 600.0),
    ("paper004", "ekf", 400.0),
    ("paper004", "huber", 400.0),
    ("paper001", "federated-fuzzy-beta", None),
    ("paper000", "ekf-st", 200.0),
])
def test_chunked_equals_whole(scenario, filt, seconds, sim_cache):
    log = _log(scenario, sim_cache, seconds)
    src = SimulatedSource(log)
    whole = run(src, filt)
    assert whole.result.ok
    on_epochs = _epoch_spacing(log)  # boundaries on the (first) measurement epochs
    for chunk in (on_epochs, 3 * on_epochs + 7, 1013):
        assert_same_run(whole, run(src, filt, chunk_samples=chunk))


def test_chunk_of_one_sample(sim_cache):
    """The smallest chunk (one IMU sample per call) still gives the whole run."""
    log = _log("paper000", sim_cache, 30.0)
    src = SimulatedSource(log)
    assert_same_run(run(src, "fakf"), run(src, "fakf", chunk_samples=1))


def test_chunk_after_a_stop_records_nothing(sim_cache):
    """A run that lost its covariance stops in its chunk; later chunks add no outputs."""
    log = _log("paper000", sim_cache, 200.0)
    src = SimulatedSource(log)
    setup = make_setup(src, "ekf")
    # an absurd initial attitude sigma (1e100 deg): some update far into the run breaks the
    # covariance check, so the stop falls inside a later chunk, not the first
    bad = dataclasses.replace(setup, config=setup.config.with_(init_att_sigma_deg=(1e100,) * 3))
    whole = run(src, "ekf", setup=bad)
    chunked = run(src, "ekf", setup=bad, chunk_samples=500)
    assert not whole.result.ok and "covariance" in whole.result.status
    assert whole.result.time_s[-1] > 500 * float(np.median(np.diff(log.imu.time_s)))
    assert_same_run(whole, chunked)


def test_chunks_must_join(sim_cache):
    log = _log("paper000", sim_cache, 10.0)
    src = SimulatedSource(log)
    setup = make_setup(src, "ekf")
    inp = src.inputs(setup)
    fr = FilterRun(setup.sensors_for(inp.sensors), inp.init, setup.config, setup.adapters,
                   setup.sensor_options, dt_nom_s=0.01)
    imu = log.imu
    fr.feed_arrays(imu.time_s[:101].copy(), imu.dtheta_b[:100].copy(), imu.dv_b[:100].copy())
    with pytest.raises(FuzzynavError, match="previous chunk's last sample time"):
        fr.feed_arrays(imu.time_s[101:202].copy(), imu.dtheta_b[101:201].copy(),
                       imu.dv_b[101:201].copy())


def test_chunked_after_paper002_alignment(sim_cache):
    """Paper 002's family (alignment) feeds the loop only as ``run --align``: the
    navigation started behind the fuzzy alignment (its IMU and streams cut at the
    alignment's end) chunked is the whole run."""
    from fuzzynav.align.chain import AlignedSource, align_on_rest

    log = _log("paper000", sim_cache, 200.0)  # the 60-s rest and a stretch of the drive
    src = AlignedSource(log, *align_on_rest(log, "align-fuzzy"))
    whole = run(src, "fakf")
    rest_s = log.scenario.segments[0].duration_s
    assert whole.result.ok and whole.result.time_s[0] > 0.9 * rest_s
    for chunk in (100, 1013):
        assert_same_run(whole, run(src, "fakf", chunk_samples=chunk))
