"""Alignment runs simulated and mechanized chunk by chunk (``compare paper002 --chunk S``).

A chunk is the whole run's piece: the time grid is numpy's linspace point by point, each
chunk's acceleration is formed over its piece widened by one grid point each side (so only
the run's own ends take the one-sided formula), the gusts and the IMU errors carry their
random processes across, and the mechanization carries its state over chunks of whole
epochs.  The same arithmetic on the same numbers, only the array lengths differ: on this
machine the epochs and metrics equal the whole run's to the last bit, but numpy's vector
functions (sin, exp) and stacked products may round a piece of another length differently
on another CPU (tests/floats.py), so the comparisons allow :data:`RTOL`; a chunking error
(a lost or repeated sample, a one-sided difference inside the run) is orders larger.
"""
import contextlib
import dataclasses
import io
import json
import tracemalloc

import numpy as np
import pytest

from fuzzynav.align import alignment_run as R
from fuzzynav.align import run_size as run_size
from fuzzynav.align.mechanize import Mechanizer, mechanize
from fuzzynav.align.scenario import list_alignment_scenarios, load_alignment_scenario
from fuzzynav.align.simulate import AlignChunks, gradient, grid, simulate_alignment
from fuzzynav.cli import main
from fuzzynav.errors import InputFileError
from fuzzynav.sim import budget
from fuzzynav.sim.imu import ImuData
from fuzzynav.sim.sensor_log import component_rng

#: two paths' agreement: a few ulps on O(1) numbers, grown by the cancellation in the
#: increments (rotations 1e-4 rad apart) and by the filter; a lost sample is ~1e-2
RTOL, ATOL = 1e-9, 1e-15
FILTERS = ("align-kf", "align-kf12", "align-kf-fast", "align-fuzzy", "align-fuzzy-fast")


def _short(name, duration_s=60.0):
    return dataclasses.replace(load_alignment_scenario(name), duration_s=duration_s)


def _chunks(scn, seed, chunk):
    return list(AlignChunks(scn.imu, np.radians(scn.lat_deg), scn.h_m,
                            np.radians(scn.att_deg), scn.duration_s,
                            component_rng(seed, "align-imu"), scn.sway, chunk))


def _close(got, ref):
    np.testing.assert_allclose(got, ref, rtol=RTOL, atol=ATOL)


def _same_metrics(got: dict, ref: dict):
    assert list(got) == list(ref)
    for k, v in ref.items():
        assert got[k] == pytest.approx(v, rel=RTOL, abs=ATOL), k


def _joined(chunks, field):
    """A per-sample field of consecutive chunks (each repeats the last one's end sample)."""
    parts = [getattr(c, field) if field != "time_s" else c.imu.time_s for c in chunks]
    return np.concatenate([parts[0][:1]] + [p[1:] for p in parts])


@pytest.mark.parametrize("chunk", [1, 7, 250, 5999, 6000, 10 ** 6])
def test_chunks_are_the_whole_runs_samples(chunk):
    """Swaying with gusts (every term of the simulation at work), chunk sizes from one
    sample to more than the run, odd ones included."""
    scn = _short("paper002-gusts")
    whole = R.simulate(scn, 3)
    chunks = _chunks(scn, 3, chunk)
    assert len(chunks) == -(-6000 // chunk)
    np.testing.assert_array_equal(_joined(chunks, "time_s"), whole.imu.time_s)  # j * step
    for field in ("dtheta_b", "dv_b"):
        _close(np.concatenate([getattr(c.imu, field) for c in chunks]),
               getattr(whole.imu, field))
    _close(_joined(chunks, "C_bn"), whole.C_bn)
    _close(_joined(chunks, "vel_n"), whole.vel_n)
    assert np.abs(whole.vel_n).max() > 0.01          # the gusts did move the base


@pytest.mark.parametrize("num, stop", [(2, 1.0), (3, 0.1), (80001, 400.0), (12345, 7.3)])
def test_the_grid_is_linspace_point_by_point(num, stop):
    # one IEEE product per point, as numpy's linspace makes it: exact on any CPU
    whole = np.linspace(0.0, stop, num)
    np.testing.assert_array_equal(grid(0, num, num, stop), whole)
    cut = num // 3 + 1
    np.testing.assert_array_equal(np.concatenate([grid(0, cut, num, stop),
                                                  grid(cut, num, num, stop)]), whole)


def test_the_gradient_is_numpys_on_an_uneven_grid_and_exact_on_a_quadratic():
    t = np.cumsum(np.random.default_rng(0).uniform(0.5, 1.5, 40))
    f = np.column_stack([np.sin(t), t ** 2])
    # the same IEEE +, *, / element by element on the same inputs: exact on any CPU
    np.testing.assert_array_equal(gradient(f, t), np.gradient(f, t, axis=0))
    # the three-point formula is exact for a quadratic at interior points, even grid or not
    even = np.arange(10.0)
    np.testing.assert_allclose(gradient(even[:, None] ** 2, even)[1:-1, 0], 2 * even[1:-1],
                               rtol=1e-12)


def test_the_mechanization_over_chunks_is_the_whole_one():
    scn = _short("paper002-sway")
    log = R.simulate(scn, 1)
    C0 = log.C_bn[0]
    lat = np.radians(scn.lat_deg)
    whole = mechanize(log.imu, C0, lat, scn.h_m, 100)
    m = Mechanizer(C0, lat, scn.h_m, 100)
    for k0 in range(0, 6000, 700):                      # 7 epochs a chunk, the last 4.x
        k1 = min(k0 + 700, 6000 - 37)                   # a run ending inside an epoch
        m.feed(ImuData(time_s=log.imu.time_s[k0:k1 + 1], dtheta_b=log.imu.dtheta_b[k0:k1],
                       dv_b=log.imu.dv_b[k0:k1]))
        if k1 == 6000 - 37:
            break
    cut = mechanize(ImuData(time_s=log.imu.time_s[:6000 - 36],
                            dtheta_b=log.imu.dtheta_b[:6000 - 37],
                            dv_b=log.imu.dv_b[:6000 - 37]), C0, lat, scn.h_m, 100)
    for got, ref in zip(m.result(), cut):
        _close(got, ref)
    assert cut[0].shape[0] == 60 and whole[0].shape[0] == 61
    with pytest.raises(ValueError, match="whole number of epochs"):
        m.feed(log.imu)


@pytest.mark.parametrize("name", list_alignment_scenarios())
def test_every_paper002_scenario_streamed_gives_the_whole_metrics(name):
    scn = _short(name, 120.0)
    whole = R.seed_runs(scn)(2)
    for chunk in (100, 1234):
        streamed = R.seed_runs(scn, chunk_samples=chunk)(2)
        for f in FILTERS:
            _same_metrics(streamed(f), whole(f))


def _cli(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(argv))
    return code, out.getvalue(), err.getvalue()


def test_compare_with_chunk_prints_the_whole_runs_table():
    args = ("compare", "paper002", "--filters", "align-kf,align-fuzzy", "--mc", "2", "--json")
    code, whole, err = _cli(*args)
    assert code == 0, err
    code, chunked, err = _cli(*args, "--chunk", "13")
    assert code == 0, err
    a, b = json.loads(chunked), json.loads(whole)
    assert a["seeds"] == b["seeds"] and list(a["filters"]) == list(b["filters"])
    for f, rows in b["filters"].items():
        for k, est in rows.items():
            _close(a["filters"][f][k]["mean"], est["mean"])
            _close(a["filters"][f][k]["ci95"], est["ci95"])
    code, _, err = _cli("compare", "paper002", "--filters", "align-kf,align-fuzzy",
                        "--output-rate", "1")
    assert code == 2 and "--output-rate" in err and "filter epochs" in err


def test_a_run_too_large_whole_is_refused_with_the_chunked_estimate(monkeypatch):
    """paper002 (400 s at 100 Hz): ~51 MB whole, ~16 MB in 60-s chunks; a 40-MB limit
    refuses the first with both figures and the option, runs the second."""
    scn = load_alignment_scenario("paper002")
    whole, chunked = run_size.estimate(scn), run_size.estimate(scn, 6000)
    limit = 40 * 2**20
    assert chunked < limit < whole                       # the premise
    monkeypatch.setenv(budget.ENV_VAR, str(limit / 2**30))
    with pytest.raises(InputFileError) as exc:
        R.seed_runs(scn)(0)
    msg = str(exc.value)
    assert exc.value.where == "duration_s" and "--chunk" in msg, msg
    assert f"~{budget.human_bytes(whole)}" in msg and "limit is 40 MB" in msg, msg
    assert np.isfinite(R.seed_runs(scn, chunk_samples=6000)(0)("align-kf")["align_time_s"])
    code, _, err = _cli("compare", "paper002", "--filters", "align-kf,align-fuzzy")
    assert code == 2 and "--chunk S" in err and err.count("\n") == 1, err


@pytest.mark.parametrize("chunk", [None, 1000])
def test_the_estimates_bound_a_traced_run(chunk):
    """The estimate against tracemalloc's peak of one seed and one filter (measured 930 B
    a sample whole, ~1.5 kB an epoch, ~3.5 MB a run): it must bound the run, within 4x."""
    scn = _short("paper002-gusts", 200.0)
    R.seed_runs(scn, chunk_samples=chunk)(0)("align-fuzzy")   # compiled before the trace
    tracemalloc.start()
    R.seed_runs(scn, chunk_samples=chunk)(0)("align-fuzzy")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    need = run_size.estimate(scn, chunk)
    assert peak <= need <= 4 * peak, (peak, need)


def test_transitions_made_in_blocks_are_the_whole_runs(monkeypatch):
    """The fine filter makes its transition matrices a block of epochs at a time; each
    epoch's is its own Taylor series, so any block size gives the same filter run."""
    from fuzzynav.align import fine

    scn = _short("paper002-sway", 120.0)
    ep = R.streamed_epochs(scn, 4, 3000)
    runs = []
    for block in (fine.TRANSITION_BLOCK, 7, 1):
        monkeypatch.setattr(fine, "TRANSITION_BLOCK", block)
        runs.append(R.run_align_filter("align-fuzzy", scn, None, ep))
    for other in runs[1:]:   # stacked products of other stack sizes: to rounding
        _close(other.result.x, runs[0].result.x)
        _close(other.result.P, runs[0].result.P)
        _close(other.phi_hat, runs[0].phi_hat)


@pytest.mark.parametrize("chunk", [6000, 777, 100_000])
def test_run_align_streamed_aligns_on_the_same_samples_and_navigates_alike(chunk, sim_cache):
    """``run --align`` on a scenario simulated chunk by chunk: the alignment takes the
    chunks that hold the opening rest (the whole log's samples, so the aligned attitude's
    errors are the whole run's), the navigation starts at its end (a chunk cut there; with
    6 000-sample chunks the end is a chunk boundary, whose epochs at that instant are the
    previous chunk's: dropping them moved the RMS by 0.2 %) and its metrics are the whole
    run's (the same samples and sums, fuzzynav.block_sums; two paths, so RTOL)."""
    from fuzzynav.align.chain import run_aligned, run_aligned_streamed
    from fuzzynav.sim.scenario import load_scenario
    from fuzzynav.sim.sensor_log import simulate

    scn = load_scenario("paper000-nominal")
    whole = run_aligned(simulate(scn, 1, sim_cache), "ekf").metrics
    got = run_aligned_streamed(scn, 1, "ekf", chunk_samples=chunk, output_rate_hz=1.0,
                               cache_dir=sim_cache).metrics
    assert set(got) == set(whole) and whole["align_end_s"] == 60.0
    assert got["completed"] == whole["completed"] == 1.0
    for k, v in whole.items():   # the same sums of errors formed on other slices
        assert got[k] == pytest.approx(v, rel=RTOL, abs=ATOL), k


def test_cli_run_align_streamed_prints_the_whole_runs_table(sim_cache):
    args = ("run", "paper000-nominal", "--filter", "ekf", "--align", "align-kf", "--cache",
            str(sim_cache))
    code, whole, err = _cli(*args)
    assert code == 0, err
    code, streamed, err = _cli(*args, "--output-rate", "1", "--chunk", "45")
    assert code == 0, err
    assert streamed == whole and "aligned with align-kf" in whole
