"""Runs on recordings streamed chunk by chunk (``fuzzynav run --data ... --output-rate HZ``).

The errors at the reference epochs are formed chunk by chunk with the previous chunk's last
row in front (:mod:`fuzzynav.realdata.reference_scoring`): each epoch is interpolated from
the same two rows by the same arithmetic as in the whole run, so the streamed metrics must
equal the whole run's exactly, whatever the chunking; the kept solution is every k-th row.
"""
import json

import numpy as np
import pytest

from fuzzynav.metrics import errors_vs_reference
from fuzzynav.realdata.akit import run_trajectory
from fuzzynav.realdata.loaders.akit_recording import load_trajectory
from fuzzynav.realdata.loaders.rtklib import load_rtklib
from fuzzynav.realdata.reference_scoring import ReferenceScoring, _Track
from fuzzynav.realdata.score import outage_drifts, outage_scoring
from fuzzynav.realdata.validate import validate
from tests.conftest import datasets_dir
from tests.realdata.akit_files import auv_trajectory, write_akit
from tests.realdata.rtklib_files import write_drive
from tests.realdata.test_cli_errors import _run

LAT0, LON0 = np.radians(32.8), np.radians(34.9)


def _track(t):
    """A straight track north-east at 1e-7 rad/s, 50 m up, with its velocity."""
    lla = np.column_stack([LAT0 + 1e-7 * t, LON0 + 2e-7 * t, np.full(t.size, 50.0)])
    vel = np.tile([1.0, 0.5, 0.0], (t.size, 1))
    return _Track(t, lla, vel, np.tile([1.0, 0.0, 0.0, 0.0], (t.size, 1)))


def _cuts(track, edges):
    for a, b in zip(edges[:-1], edges[1:]):
        yield _Track.of(track, slice(a, b))


def test_streamed_errors_are_the_whole_runs_at_every_reference_epoch():
    t = np.arange(0.0, 20.0, 0.1)            # solution at 10 Hz, 200 rows
    sol = _track(t)
    # reference epochs: before the solution, on a chunk's first and last rows, between
    # two chunks, and after the solution (left out both ways)
    t_ref = np.array([-1.0, 0.0, 0.35, t[49], t[50], 0.5 * (t[99] + t[100]), 13.37, 19.9,
                      25.0])
    ref = _track(t_ref)
    ref_lla = ref.lla + np.array([1e-7, 0.0, 2.0])   # the reference 0.64 m north, 2 m up
    scoring = ReferenceScoring(
        lambda res: errors_vs_reference(res, t_ref, ref_lla, ref.vel_n),
        lambda err, t_res, res: {"err": err, "t_res": t_res}, marks_s=(5.0, 10.04, 30.0))
    whole = scoring(sol)
    np.testing.assert_array_equal(whole["err"].time_s, t_ref[1:-1])
    # the solution is the reference moved by the offset: the error is minus the offset
    a, e2 = 6_378_137.0, 6.69437999014e-3  # WGS-84: the meridian radius of curvature
    north = 1e-7 * (a * (1 - e2) / (1 - e2 * np.sin(LAT0) ** 2) ** 1.5 + 50.0)
    np.testing.assert_allclose(whole["err"].pos_m[:, 1], -north, rtol=1e-4)
    np.testing.assert_allclose(whole["err"].pos_m[:, 2], -2.0, atol=1e-6)
    for edges in ([0, 50, 100, 200], [0, 1, 2, 100, 101, 200], [0, 200], list(range(201))):
        acc = scoring.streaming()
        for part in _cuts(sol, edges):
            acc.add_result(part)
        got = scoring.streamed(None, acc)
        for f in ("time_s", "pos_m", "vel_mps"):
            np.testing.assert_array_equal(getattr(got["err"], f), getattr(whole["err"], f))
        # the solution times the drifts read: the last before each mark, and the last
        np.testing.assert_array_equal(got["t_res"], [t[49], t[100], t[-1]])


def test_drifts_read_from_the_streamed_solution_times_are_the_whole_runs():
    t = np.arange(0.0, 30.0, 0.1)
    sol = _track(t)
    t_ref = np.arange(0.0, 30.0, 0.25)
    ref = _track(t_ref)
    windows = np.array([[5.0, 9.97], [12.0, 18.0], [27.0, 40.0]])  # the last incomplete
    seen = {}
    scoring = outage_scoring(lambda res: errors_vs_reference(res, t_ref, ref.lla + 1e-8,
                                                               ref.vel_n), windows, 0.0, seen)
    whole = outage_drifts(scoring.errors(sol), t, windows)
    acc = scoring.streaming()
    for part in _cuts(sol, [0, 77, 100, 181, 300]):
        acc.add_result(part)
    scoring.streamed(None, acc)
    assert outage_drifts(seen["errors"], seen["solution_time_s"], windows) == whole
    assert [d.complete for d in whole] == [True, True, False]


def _same_metrics(a, b):
    assert list(a) == list(b)
    for k in a:
        assert a[k] == b[k] or (np.isnan(a[k]) and np.isnan(b[k])), (k, a[k], b[k])


def _decimated(whole, dec, k):
    for f in ("time_s", "lla", "vel_n", "q_bn", "sigma"):
        np.testing.assert_array_equal(getattr(dec, f), getattr(whole, f)[::k], err_msg=f)


@pytest.fixture(scope="module")
def auv(tmp_path_factory):
    d = tmp_path_factory.mktemp("akit-stream")
    write_akit(d, auv_trajectory(), n=1, lag=0.3)
    return d


def test_akit_run_streamed_is_the_whole_run(auv):
    rec = load_trajectory(auv, 1)
    whole_res, whole = run_trajectory(rec, "ekf")
    for kw, k in ((dict(chunk_samples=777, output_rate_hz=1.0), 10),
                  (dict(chunk_samples=5000), 1), (dict(output_rate_hz=5.0), 2)):
        res, metrics = run_trajectory(rec, "ekf", **kw)
        _same_metrics(metrics, whole)
        _decimated(whole_res, res, k)


def test_gnss_protocol_streamed_is_the_whole_run(tmp_path):
    write_drive(tmp_path)
    rec = load_rtklib(tmp_path)
    whole = validate(rec, "ekf")
    streamed = validate(rec, "ekf", chunk_samples=613, output_rate_hz=1.0)
    for feed, run in whole.runs.items():
        got = streamed.runs[feed]
        _same_metrics(got.metrics, run.metrics)
        assert got.drifts == run.drifts
        np.testing.assert_array_equal(got.errors.pos_m, run.errors.pos_m)
        _decimated(run.result, got.result, 10)


def test_cli_output_rate_on_recordings_gives_the_whole_runs_json(auv, tmp_path):
    write_drive(tmp_path)
    for spec in (f"akit:{auv}:1", f"rtklib:{tmp_path}"):
        code, whole, err = _run("run", "--data", spec, "--filter", "ekf", "--json")
        assert code == 0, err
        code, dec, err = _run("run", "--data", spec, "--filter", "ekf", "--json",
                              "--output-rate", "2", "--chunk", "7.3")
        assert code == 0, err
        assert json.loads(dec)["feeds"] == json.loads(whole)["feeds"], spec


def test_cli_output_rate_on_a_recording_refused_with_one_line(auv):
    code, _, err = _run("run", "--data", f"akit:{auv}:1", "--output-rate", "3")
    assert code == 2 and "--output-rate 3 Hz: must be the filter's output rate" in err
    assert err.count("\n") == 1, err
    code, _, err = _run("run", "--data", f"akit:{auv}:1", "--chunk", "-2")
    assert code == 2 and "--chunk must be a positive number" in err


DRIVE = datasets_dir() / "rtklib-drive"
AKIT = datasets_dir() / "akit"


@pytest.mark.skipif(not (AKIT / "IMU_trajectory1.csv").is_file(),
                    reason=f"real recording not found: {AKIT} (set FUZZYNAV_DATA)")
def test_real_akit_streamed_is_the_whole_run():
    rec = load_trajectory(AKIT, 1)
    whole_res, whole = run_trajectory(rec, "ekf")
    res, metrics = run_trajectory(rec, "ekf", chunk_samples=1234, output_rate_hz=1.0)
    _same_metrics(metrics, whole)
    _decimated(whole_res, res, 10)


@pytest.mark.skipif(not (DRIVE / "imu_1934.csv").is_file(),
                    reason=f"real recording not found: {DRIVE} (set FUZZYNAV_DATA)")
def test_real_drive_streamed_is_the_whole_run():
    rec = load_rtklib(DRIVE)
    whole = validate(rec, "ekf")
    streamed = validate(rec, "ekf", chunk_samples=3001, output_rate_hz=1.0)
    for feed, run in whole.runs.items():
        _same_metrics(streamed.runs[feed].metrics, run.metrics)
        assert streamed.runs[feed].drifts == run.drifts
