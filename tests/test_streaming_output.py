"""Streaming metrics and decimated output (``fuzzynav run --output-rate HZ [--chunk S]``).

:class:`~fuzzynav.metrics.StreamingRms` is checked against :func:`rms_metrics` on errors
cut into uneven chunks (the same sums, :mod:`fuzzynav.block_sums`: equal to the last bit)
and against numpy's mean of squares, and a decimated run against every k-th row of the
whole run.
"""
import dataclasses

import numpy as np
import pytest

from fuzzynav import block_sums
from fuzzynav.cli import main
from fuzzynav.errors import FuzzynavError
from fuzzynav.experiment import SimulatedSource
from fuzzynav.metrics import NavErrors, StreamingRms, rms_metrics
from fuzzynav.runpath import keep_every, run
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.sim.sensor_log import simulate
from tests.floats import METRICS_RTOL, same_metrics, sum_order_rtol


def _errors(n, seed=0):
    rng = np.random.default_rng(seed)
    return NavErrors(np.arange(n) * 0.1, rng.normal(0, 3, (n, 3)), rng.normal(0, 0.1, (n, 3)),
                     rng.normal(0, 1e-3, (n, 3)))


def _cut(err, edges):
    for a, b in zip(edges[:-1], edges[1:]):
        yield NavErrors(err.time_s[a:b], err.pos_m[a:b], err.vel_mps[a:b], err.att_rad[a:b])


@pytest.mark.parametrize("t_start_s", [0.0, 37.05])
def test_streaming_rms_is_rms_metrics_over_chunks(t_start_s):
    err = _errors(2000)
    ref = rms_metrics(err, t_start_s)
    acc = StreamingRms(t_start_s)
    for part in _cut(err, [0, 1, 250, 371, 1500, 2000]):  # t_start falls inside a chunk
        acc.add(part)
    got = acc.metrics()
    assert list(got) == list(ref)  # the same names in the same order
    # the same errors given, each term an IEEE operation or hypot of its own element (no
    # vectorised transcendental), and the same additions: the same path, to the bit
    assert got == ref
    # a figure from its definition: under BLOCK_COLUMNS epochs, numpy's mean of squares
    sel = err.time_s >= t_start_s
    assert got["rms_pos_e_m"] == float(np.sqrt(np.mean(err.pos_m[sel, 0] ** 2)))
    assert got["mean_pos_h_m"] == float(np.mean(np.hypot(*err.pos_m[sel, :2].T)))


@pytest.mark.parametrize("block", [50, None])
def test_streaming_rms_over_many_blocks_is_rms_metrics_to_the_bit(block, monkeypatch):
    if block:   # many small blocks and chunks cut across them
        monkeypatch.setattr(block_sums, "BLOCK_COLUMNS", block)
    n = 2 * block_sums.BLOCK_COLUMNS + 777
    err = _errors(n, seed=3)
    ref = rms_metrics(err, 1.0)
    rng = np.random.default_rng(11)
    for _ in range(3):
        edges = np.unique(np.concatenate([[0, n], rng.integers(1, n, 9)]))
        acc = StreamingRms(1.0)
        for part in _cut(err, edges):
            acc.add(part)
        assert acc.metrics() == ref
    sel = err.time_s >= 1.0   # against one pairwise sum: within its rounding bound
    assert ref["rms_pos_n_m"] == pytest.approx(
        np.sqrt(np.mean(err.pos_m[sel, 1] ** 2)), rel=sum_order_rtol(n), abs=0.0)


def test_streaming_rms_nan_sticks_and_empty_is_nan():
    err = _errors(300)
    err.pos_m[120, 0] = np.nan  # a diverged epoch in the second chunk
    acc = StreamingRms()
    for part in _cut(err, [0, 100, 200, 300]):
        acc.add(part)
    assert np.isnan(acc.metrics()["max_pos_h_m"]) and np.isnan(acc.metrics()["rms_pos_m"])
    assert np.isnan(rms_metrics(err)["max_pos_h_m"])
    empty = StreamingRms(t_start_s=1e9)
    empty.add(err)
    assert all(np.isnan(v) for v in empty.metrics().values())


@pytest.mark.parametrize("filt", ["ekf", "federated-fuzzy-beta"])
def test_decimated_run_keeps_every_kth_row_and_the_metrics(filt, sim_cache):
    scenario = "paper001" if filt.startswith("federated") else "paper000"
    src = SimulatedSource(simulate(load_scenario(scenario), 0, sim_cache))
    whole = run(src, filt)
    dec = run(src, filt, chunk_samples=777, output_rate_hz=1.0)
    k = 10  # the filters' 10 Hz output kept at 1 Hz
    rw, rd = whole.result, dec.result
    for f in ("time_s", "lla", "vel_n", "q_bn", "sensor_states", "sigma"):
        np.testing.assert_array_equal(getattr(rd, f), getattr(rw, f)[::k], err_msg=f)
    if rw.locals.x.ndim == 3:  # a bank's locals are decimated alike
        np.testing.assert_array_equal(rd.locals.x, rw.locals.x[::k])
    for nm in rw.events:  # the events are every event
        np.testing.assert_array_equal(rd.events[nm].nis, rw.events[nm].nis)
    # scored at 10 Hz chunk by chunk, not at 1 Hz: the same block sums of errors formed on
    # the chunks' slices (two paths: tests/floats.py)
    same_metrics(dec.metrics, whole.metrics)


def test_output_rate_must_divide_the_filters():
    assert keep_every(10.0, 1.0) == 10 and keep_every(10.0, 10.0) == 1
    assert keep_every(10.0, 0.1) == 100
    for bad in (3.0, 20.0, 0.0, -1.0, float("nan")):
        with pytest.raises(FuzzynavError, match="must be the filter's output rate 10 Hz"):
            keep_every(10.0, bad)


def _cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_output_rate_gives_the_whole_runs_table(capsys, sim_cache):
    base = ("run", "paper000", "--filter", "ekf", "--cache", str(sim_cache), "--json")
    code, whole, _ = _cli(capsys, *base)
    assert code == 0
    code, dec, _ = _cli(capsys, *base, "--output-rate", "2", "--chunk", "61.3")
    assert code == 0
    import json

    # simulated chunk by chunk (the whole log's numbers, tests/sim/test_stream.py), scored
    # with the same block sums on the chunks' errors (two paths: tests/floats.py)
    a, b = json.loads(whole)["filters"]["ekf"], json.loads(dec)["filters"]["ekf"]
    assert list(b) == list(a)
    for m in a:
        assert b[m]["mean"] == pytest.approx(a[m]["mean"], rel=METRICS_RTOL), m


@pytest.mark.parametrize("argv, fragment", [
    (["run", "paper000", "--output-rate", "3"], "--output-rate 3 Hz: must be the filter's"),
    (["run", "paper000", "--chunk", "0"], "--chunk must be a positive number"),
    (["run", "paper000", "--output-rate", "-1"], "--output-rate must be a positive number"),
    (["compare", "paper002", "--filters", "align-kf,align-fuzzy", "--output-rate", "1"],
     "--output-rate (its outputs are its filter epochs): not available with alignment"),
])
def test_cli_streaming_options_refused_with_one_line(capsys, argv, fragment, sim_cache,
                                                     tmp_path):
    argv = [a.format(dir=tmp_path) for a in argv]  # a directory: refused before it is read
    code, _, err = _cli(capsys, *argv, "--cache", str(sim_cache))
    assert code == 2, err
    assert fragment in err and err.count("\n") == 1, err


def test_decimating_refuses_a_source_that_scores_whole(sim_cache):
    log = simulate(load_scenario("paper000"), 0, sim_cache)

    @dataclasses.dataclass(frozen=True)
    class Whole(SimulatedSource):  # a source without a streaming scorer
        streaming_scorer = property()  # hides the attribute: hasattr() is False

    with pytest.raises(FuzzynavError, match="score their whole result"):
        run(Whole(log), "ekf", output_rate_hz=1.0)


def test_streamed_run_keeps_the_sensor_usage_metrics(tmp_path):
    # the r_use_* figures come from the event logs, not the solution: a decimated, chunked
    # run must give them as the whole run does (and every metric the whole run has)
    log = simulate(load_scenario("paper001"), 0, tmp_path)
    whole = run(SimulatedSource(log), "fuzzy-mag").metrics
    streamed = run(SimulatedSource(log), "fuzzy-mag", chunk_samples=3000,
                   output_rate_hz=1.0).metrics
    assert set(streamed) == set(whole)
    usage = [k for k in whole if k.startswith("r_use_")]
    # two code paths (chunked vs whole): equal within a stated tolerance
    assert usage and all(streamed[k] == pytest.approx(whole[k], rel=1e-12, nan_ok=True)
                         for k in usage)


def test_streaming_rms_sums_are_blocks_added_in_order(monkeypatch):
    """The accumulator's RMS is the square root of the mean of the blocks' sums of squares
    (blocks of BLOCK_COLUMNS from the first epoch, each summed as np.sum sums a row), added
    in order, whatever the chunks: the rule written out, to the last bit."""
    monkeypatch.setattr(block_sums, "BLOCK_COLUMNS", 1000)
    err = _errors(3001, seed=5)
    acc = StreamingRms()
    for part in _cut(err, [0, 7, 1000, 1001, 2999, 3001]):
        acc.add(part)
    rows = {"rms_pos_n_m": np.square(err.pos_m[:, 1]),
            "rms_vel_h_mps": np.square(np.hypot(err.vel_mps[:, 0], err.vel_mps[:, 1])),
            "rms_att_deg": np.square(np.linalg.norm(np.rad2deg(err.att_rad), axis=1))}
    got = acc.metrics()
    for k, sq in rows.items():
        s = 0.0
        for a in range(0, 3001, 1000):
            s += float(np.sum(sq[a:a + 1000]))
        assert got[k] == float(np.sqrt(s / 3001)), k


def test_cli_output_dir_holding_an_earlier_runs_chunks_is_refused(capsys, sim_cache, tmp_path):
    """A second run into the same --output-dir would leave the first's chunks beside its
    own (a shorter run, its last ones): refused, one line naming the directory, before any
    run writes; the files already there unchanged."""
    out = tmp_path / "out"
    argv = ("run", "paper000", "--filter", "ekf", "--cache", str(sim_cache), "--output-rate",
            "1", "--output-dir", str(out))
    code, _, err = _cli(capsys, *argv)
    assert code == 0, err
    files = sorted(out.rglob("*"))
    assert [f.name for f in files if f.is_file()][:1] == ["chunk-000000.npz"]
    before = {f: f.read_bytes() for f in files if f.is_file()}
    code, table, err = _cli(capsys, *argv)
    assert code == 2 and not table
    assert err.startswith(f"fuzzynav: error: {out}: cannot write the streamed run output") \
        and "holds 3 chunk file(s) of an earlier run" in err and err.count("\n") == 1, err
    assert sorted(out.rglob("*")) == files
    assert all(f.read_bytes() == b for f, b in before.items())
