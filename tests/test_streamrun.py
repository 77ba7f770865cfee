"""A run on a scenario simulated chunk by chunk gives the whole log's run.

:func:`fuzzynav.streamrun.run_streamed` against :func:`fuzzynav.experiment.run_on_log` on
the whole simulated log fed in the same chunks (the same data, filter arithmetic and
streamed sums: identical metrics, solution and event logs), and its metrics against the
whole run in one piece, scored whole; on every paper's scenario family that navigates on
simulated data.  Also: the files of ``--output-dir``, the refusals (an oracle told the
whole run's noise, a run too long to simulate whole, one too long even in chunks).
"""
import numpy as np
import pytest

from fuzzynav import block_sums
from fuzzynav.errors import FuzzynavError, InputFileError
from fuzzynav.experiment import run_on_log
from fuzzynav.sim import budget
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.streamrun import run_streamed

from tests.floats import same_metrics
from tests.sim.test_budget import RUN as BUDGET_RUN
from tests.sim.test_stream import short


def _same(a, b):
    assert a.keys() == b.keys()
    for k in a:
        assert a[k] == b[k] or (np.isnan(a[k]) and np.isnan(b[k])), k


@pytest.mark.parametrize("name, filt", [("paper000", "fuzzy"), ("paper001", "fuzzy-mag"),
                                        ("paper003", "fuzzy-ship"), ("paper004", "huber"),
                                        ("paper003-storm", "ekf"),
                                        ("paper000", "strong-tracking")])
def test_streamed_run_is_the_whole_logs_run(name, filt, monkeypatch):
    # sums in blocks of 50 outputs, which the chunks of 73 cut across (fuzzynav.block_sums)
    monkeypatch.setattr(block_sums, "BLOCK_COLUMNS", 50)
    scn = short(name, 60.0)
    chunk = int(round(7.3 * scn.imu.rate_hz))  # boundaries between and (every 73 s) on epochs
    log = simulate(scn, 2)
    whole = run_on_log(log, filt, chunk_samples=chunk, output_rate_hz=1.0)
    got = run_streamed(scn, 2, filt, chunk_samples=chunk, output_rate_hz=1.0,
                       keep_events=True)
    _same(got.metrics, whole.metrics)
    # and the run in one piece, scored whole: the same sums of errors formed on other slices
    same_metrics(got.metrics, run_on_log(log, filt).metrics)
    if name == "paper001":
        assert any(k.startswith("r_use") for k in got.metrics)
    for f in ("time_s", "lla", "vel_n", "q_bn", "sigma", "sensor_states"):
        np.testing.assert_array_equal(getattr(got.result, f), getattr(whole.result, f))
    assert got.result.events.keys() == whole.result.events.keys()
    for nm, ev in whole.result.events.items():
        for f in ("time_s", "residual", "S_diag", "nis", "flag", "diag"):
            np.testing.assert_array_equal(getattr(got.result.events[nm], f), getattr(ev, f),
                                          err_msg=f"{nm}.{f}")


@pytest.mark.parametrize("name, filt", [("paper000", "fuzzy"), ("paper003", "fuzzy-ship")])
def test_a_streamed_run_on_the_cached_log_is_the_simulated_one(tmp_path, name, filt):
    scn = short(name, 60.0)
    chunk = int(round(7.3 * scn.imu.rate_hz))
    simulate(scn, 2, tmp_path)  # the whole path's cache file
    made = run_streamed(scn, 2, filt, chunk_samples=chunk, output_rate_hz=1.0)
    cut = run_streamed(scn, 2, filt, chunk_samples=chunk, output_rate_hz=1.0,
                       cache_dir=tmp_path)
    _same(cut.metrics, made.metrics)
    for f in ("time_s", "lla", "vel_n", "q_bn", "sigma"):
        np.testing.assert_array_equal(getattr(cut.result, f), getattr(made.result, f))
    refused = []  # the oracle alike: the whole-run figure is left out of both
    for cache in (None, tmp_path):
        with pytest.raises(FuzzynavError, match="ekf-true") as exc:
            run_streamed(scn, 2, "ekf-true", chunk_samples=chunk, cache_dir=cache)
        refused.append(str(exc.value))
    assert refused[0] == refused[1]


def test_one_chunk_is_the_whole_run():
    scn = short("paper003", 60.0)
    whole = run_on_log(simulate(scn, 0), "ekf")
    got = run_streamed(scn, 0, "ekf", chunk_samples=10**6, keep_events=True)
    _same({k: v for k, v in got.metrics.items()}, whole.metrics)
    np.testing.assert_array_equal(got.result.lla, whole.result.lla)


def test_output_dir_holds_every_chunk(tmp_path):
    scn = short("paper003", 30.0)
    out = run_streamed(scn, 0, "ekf", chunk_samples=500, output_rate_hz=2.0,
                       output_dir=tmp_path / "out")
    files = sorted((tmp_path / "out").iterdir())
    assert [f.name for f in files] == [f"chunk-{i:06d}.npz" for i in range(3)]
    assert not out.result.events  # written, not kept
    with np.load(files[1]) as z:
        t = z["time_s"]
        assert np.all(np.diff(t) == 0.5) and t[0] == 10.5  # 2 Hz, after chunk 0's 0..10 s
        ev_t = z["events.log.time_s"]  # the log's epochs of samples 501..1000 (50 Hz)
        np.testing.assert_array_equal(ev_t, np.arange(501, 1001) / 50.0)
        assert z["events.log.nis"].shape == ev_t.shape
    # a shorter run into the same directory would leave chunk 2 behind as its own: refused
    from fuzzynav.errors import OutputError

    with pytest.raises(OutputError, match="holds 3 chunk file"):
        run_streamed(short("paper003", 10.0), 0, "ekf", chunk_samples=500,
                     output_rate_hz=2.0, output_dir=tmp_path / "out")
    assert sorted((tmp_path / "out").iterdir()) == files



def test_chunk_files_of_a_run_on_held_data_hold_the_held_runs_rows_and_events(tmp_path):
    """Held data with ``output_dir`` is cut into chunks (filters.runner.HeldChunks) and given
    its epochs chunk by chunk: the files hold the held run's rows and events to the bit, and
    the metrics are the held run's; run_filter itself still refuses chunk files of a run
    whose event logs are made whole."""
    from fuzzynav.experiment import SimulatedSource
    from fuzzynav.filters.chunk_files import read_chunks
    from fuzzynav.filters.runner import run_filter
    from fuzzynav.runpath import run

    log = simulate(short("paper003", 30.0), 0)
    whole = run(SimulatedSource(log), "fuzzy-ship", chunk_samples=500)
    got = run(SimulatedSource(log), "fuzzy-ship", chunk_samples=500, output_dir=tmp_path / "o")
    _same(got.metrics, whole.metrics)
    files = read_chunks(tmp_path / "o")
    assert len(files.files) == 3 and not got.result.events
    for f in ("time_s", "lla", "sigma"):
        np.testing.assert_array_equal(getattr(files, f), getattr(whole.result, f))
    for nm, ev in whole.result.events.items():
        for f in ("time_s", "residual", "S_diag", "nis", "flag", "diag"):
            np.testing.assert_array_equal(getattr(files.events[nm], f), getattr(ev, f))
    with pytest.raises(FuzzynavError, match="not for a held one"):
        run_filter(log.imu, log.sensors, whole.result, output_dir=tmp_path / "x")

def test_an_oracle_told_the_whole_runs_noise_is_refused():
    with pytest.raises(FuzzynavError, match="ekf-true: told each epoch's sigma"):
        run_streamed(short("paper004", 20.0), 0, "ekf-true", chunk_samples=100)



def test_a_streamed_run_passes_the_run_paths_output_check(monkeypatch):
    """The streamed run goes through runpath.run: its kept outputs are sized before it
    runs, decimated ones as decimated, beside a chunk's made before decimation (60 s of
    the 10-Hz filter: 600 rows, at 1 Hz 60 and the 100 of a 501-sample chunk at 50 Hz)."""
    scn = short("paper003", 60.0)
    monkeypatch.setenv(budget.ENV_VAR, "1e-6")  # 1 kiB: nothing fits
    for rate, rows in ((None, "600 kept outputs and"),
                       (1.0, r"60 kept outputs \(and 100 made at a time before decimation\)")):
        with pytest.raises(InputFileError, match=f"its {rows}"):
            run_streamed(scn, 0, "ekf", chunk_samples=500, output_rate_hz=rate)
    monkeypatch.delenv(budget.ENV_VAR)
    assert run_streamed(scn, 0, "ekf", chunk_samples=500).metrics["completed"] == 1.0

#: a cruise with a ship's log at the IMU's rate (one epoch a sample)
RUN = BUDGET_RUN.replace('[sensors.gps]\nkind = "gnss"', '[sensors.log]\nkind = "log"\n'
                         'rate_hz = {rate}')


def test_a_run_that_fits_only_in_chunks_is_refused_whole_with_both_estimates(tmp_path,
                                                                             monkeypatch):
    from fuzzynav.sim.scenario import load_scenario

    monkeypatch.setenv(budget.ENV_VAR, "1")
    # 200 Hz x 86 400 s = 1.728e7 samples; whole: x 1024 B + 2**18 x 3072 B + the log's
    # 1.728e7 epochs x 1 column x 128 B = 20 711 866 368 B = 19.3 GiB; in chunks:
    # 15 000 x 4096 B + 1.728e7 epoch indices x 48 B + 86 400 1-Hz rows x 1024 B + the
    # scorer's block (budget.SCORER_BYTES, 12 058 624 B) = 991 412 224 B = 945 MiB (by hand;
    # twice as long: 1 909 325 824 B = 1.78 GiB)
    path = tmp_path / "day.toml"
    path.write_text(RUN.format(rate=200, duration=86400))
    scn = load_scenario(path)  # fits in chunks: accepted
    with pytest.raises(InputFileError) as exc:
        simulate(scn, 0)
    assert exc.value.where == "imu.rate_hz"
    assert "needs ~19.3 GB simulated whole; the limit is 1 GB" in exc.value.what
    assert "in chunks it needs ~945 MB: run it with --output-rate" in exc.value.what
    # twice as long does not fit even in chunks: refused when read
    path.write_text(RUN.format(rate=200, duration=2 * 86400))
    with pytest.raises(InputFileError, match=r"samples needs ~1.78 GB even simulated and "
                                             "filtered in chunks of 15000 samples with 1-Hz "
                                             "output; the limit is 1 GB"):
        load_scenario(path)


def test_read_chunks_joins_a_runs_files_back_into_its_result(tmp_path):
    from fuzzynav.filters.chunk_files import read_chunks

    scn = short("paper003", 30.0)
    out = run_streamed(scn, 0, "ekf", chunk_samples=500, output_rate_hz=2.0,
                       output_dir=tmp_path / "out", keep_events=True)
    got = read_chunks(tmp_path / "out")
    assert [f.name for f in got.files] == [f"chunk-{i:06d}.npz" for i in range(3)]
    for f in ("time_s", "lla", "vel_n", "q_bn", "sigma", "sensor_states"):
        np.testing.assert_array_equal(getattr(got, f), getattr(out.result, f), err_msg=f)
    assert got.state_labels == tuple(out.result.state_labels)
    assert got.events.keys() == out.result.events.keys()
    for nm, ev in out.result.events.items():
        for f in ("time_s", "residual", "S_diag", "nis", "flag", "diag"):
            np.testing.assert_array_equal(getattr(got.events[nm], f), getattr(ev, f))
        assert got.events[nm].diag_names == tuple(ev.diag_names)


def test_read_chunks_refuses_a_gap_a_damaged_file_and_another_runs_chunk(tmp_path):
    import shutil

    from fuzzynav.filters.chunk_files import read_chunks

    scn = short("paper003", 30.0)
    run_streamed(scn, 0, "ekf", chunk_samples=500, output_rate_hz=2.0,
                 output_dir=tmp_path / "a")
    run_streamed(scn, 0, "ekf", chunk_samples=300, output_rate_hz=2.0,
                 output_dir=tmp_path / "b")
    cases = {}
    for name, damage in (("gap", lambda d: (d / "chunk-000001.npz").unlink()),
                         ("cut", lambda d: (d / "chunk-000002.npz").write_bytes(b"PK\x03")),
                         ("mixed", lambda d: shutil.copy(tmp_path / "b" / "chunk-000000.npz",
                                                         d / "chunk-000002.npz")),
                         ("short", lambda d: _drop_last_row(d / "chunk-000001.npz", "lla"))):
        d = tmp_path / name
        shutil.copytree(tmp_path / "a", d)
        damage(d)
        with pytest.raises(InputFileError) as exc:
            read_chunks(d)
        cases[name] = str(exc.value)
    assert cases["gap"].startswith(f"{tmp_path / 'gap' / 'chunk-000001.npz'}: missing")
    assert cases["cut"].startswith(f"{tmp_path / 'cut' / 'chunk-000002.npz'}: is not a "
                                   "readable npz file")
    assert cases["mixed"].startswith(f"{tmp_path / 'mixed' / 'chunk-000002.npz'}: time_s: "
                                     "starts at")
    assert cases["short"].startswith(f"{tmp_path / 'short' / 'chunk-000001.npz'}: lla: has "
                                     "shape")
    with pytest.raises(InputFileError, match="holds no chunk files"):
        read_chunks(tmp_path / "nowhere")


def _drop_last_row(path, field):
    """Rewrite a chunk file with one of its arrays a row short (a damaged file)."""
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    arrays[field] = arrays[field][:-1]
    np.savez(path, **arrays)
