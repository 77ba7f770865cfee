"""Memory budget, ``base =`` confinement and file-reading limits of scenario files."""
import os
import tracemalloc

import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.fileio import safe_stem
from fuzzynav.sim import budget
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.sim.tomltable import MAX_TOML_BYTES

RUN = """
name = "r"
[start]
lat_deg = 30.0
lon_deg = 110.0
speed_mps = 10.0
[imu]
rate_hz = {rate}
[[segments]]
kind = "cruise"
duration_s = {duration}
[sensors.gps]
kind = "gnss"
"""


def _write(path, text):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def test_the_estimate_is_samples_times_bytes_and_names_the_limit(tmp_path, monkeypatch):
    monkeypatch.setenv(budget.ENV_VAR, "0.5")
    # 100 Hz x 20 000 s = 2e6 samples x 1024 B + one block of 2**18 samples x 3072 B
    # + 20 000 GNSS epochs x 6 columns x 128 B = 2 048 000 000 + 805 306 368 + 15 360 000 B
    # = 2.67 GiB whole; in chunks 15 000 x 4096 B + the GNSS epochs + 20 000 1-Hz output
    # rows x 1024 B + the scorer's block = 61 440 000 + 15 360 000 + 20 480 000 + 12 058 624
    # B = 104 MiB (by hand)
    path = _write(tmp_path / "big.toml", RUN.format(rate=100, duration=20000))
    scn = load_scenario(path)  # it fits in chunks
    with pytest.raises(InputFileError) as exc:
        simulate(scn, 0)
    assert exc.value.where == "imu.rate_hz"
    assert "= 2e+06 samples needs ~2.67 GB simulated whole" in exc.value.what
    assert "the limit is 512 MB ($FUZZYNAV_MAX_MEMORY_GB)" in exc.value.what
    assert "in chunks it needs ~104 MB" in exc.value.what
    monkeypatch.setenv(budget.ENV_VAR, "0.05")  # 51.2 MiB: not even in chunks
    with pytest.raises(InputFileError, match="samples needs ~104 MB even simulated and "
                                             "filtered in chunks of 15000 samples with 1-Hz "
                                             "output; the limit is 51.2 MB"):
        load_scenario(path)
    monkeypatch.setenv(budget.ENV_VAR, "8")
    assert load_scenario(path).duration_s == 20000.0


def _traced_streamed(path):
    """The traced peak of a streamed EKF run on ``path`` (chunks of 500 samples, 1 Hz)."""
    from fuzzynav.streamrun import run_streamed

    scn = load_scenario(path)
    tracemalloc.start()
    try:
        run_streamed(scn, 0, "ekf", chunk_samples=500, output_rate_hz=1.0)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_the_streamed_figures_bound_a_real_streamed_run(tmp_path):
    # a streamed run's peak grows with the run by the streamed sensors' epoch indices and
    # the kept outputs only (a ship's log at the IMU's 50 Hz: one epoch a sample), and its
    # chunk's share stays under the per-chunk-sample figure
    text = RUN.replace('[sensors.gps]\nkind = "gnss"', '[sensors.log]\nkind = "log"\n'
                       'rate_hz = 50.0')
    paths = [_write(tmp_path / f"{d}.toml", text.format(rate=50, duration=d))
             for d in (2, 40, 80)]
    _traced_streamed(paths[0])
    small, large = _traced_streamed(paths[1]), _traced_streamed(paths[2])
    per_sample = (large - small) / (40 * 50)
    assert per_sample < budget.BYTES_PER_STREAM_EPOCH + budget.BYTES_PER_OUTPUT_ROW / 50
    assert small < 500 * budget.BYTES_PER_CHUNK_SAMPLE + 2000 * (
        budget.BYTES_PER_STREAM_EPOCH + budget.BYTES_PER_OUTPUT_ROW / 50) + 2**20


def test_a_streamed_run_counts_the_truth_it_keeps(tmp_path, monkeypatch):
    # a GNSS-aided run short enough keeps its first pass's truth (184 B a sample): 1 000 s at
    # 50 Hz is 15 000 x 4096 + 50 001 x 184 + 1 000 GNSS epochs x 6 x 128 + 1 000 rows x 1024
    # = 61 440 000 + 9 200 184 + 768 000 + 1 024 000 B (by hand) simulated; its log (50 001 x
    # 288 + 768 000 = 15 168 288 B, under 128 MB) may be cached, and the chunks are then cut
    # from it held whole: that is the larger, 61 440 000 + 15 168 288 + 1 024 000 B, and the
    # scorer's block of 65 536 epochs x 23 rows x 8 B = 12 058 624 B. At 20 000 s its 184 MB
    # of truth is over the 128 MB kept, its log too large to be cut from, and each chunk
    # generates its own again
    short_run = load_scenario(_write(tmp_path / "a.toml", RUN.format(rate=50, duration=1000)))
    assert budget.SCORER_BYTES == 12_058_624
    assert budget.streamed_estimate(1000.0, 50.0, short_run.sensors) == 77_632_288 + 12_058_624
    assert budget.streamed_estimate(20000.0, 50.0, short_run.sensors) == (
        15_000 * 4096 + 20_000 * 6 * 128 + 20_000 * 1024 + 12_058_624)
    # the traced peak grows by the kept truth, and that growth stays under its figure
    paths = [_write(tmp_path / f"{d}.toml", RUN.format(rate=50, duration=d)) for d in (2, 40, 80)]
    _traced_streamed(paths[0])
    growth = {}
    for kept in (budget.TRUTH_STORE_BYTES, 0):
        monkeypatch.setattr(budget, "TRUTH_STORE_BYTES", kept)
        growth[kept] = (_traced_streamed(paths[2]) - _traced_streamed(paths[1])) / (40 * 50)
    stored = growth[max(growth)] - growth[0]
    assert 0.5 * budget.BYTES_PER_TRUTH_SAMPLE < stored < 1.5 * budget.BYTES_PER_TRUTH_SAMPLE
    assert growth[max(growth)] < budget.BYTES_PER_TRUTH_SAMPLE + (
        6 * budget.BYTES_PER_EPOCH_COLUMN + budget.BYTES_PER_OUTPUT_ROW) / 50


@pytest.mark.parametrize("value", ["0", "-1", "lots", "inf"])
def test_a_bad_memory_limit_variable_is_named(tmp_path, monkeypatch, value):
    monkeypatch.setenv(budget.ENV_VAR, value)
    with pytest.raises(InputFileError, match=budget.ENV_VAR):
        load_scenario(_write(tmp_path / "s.toml", RUN.format(rate=50, duration=10)))


def test_the_default_limit_is_half_the_physical_memory(monkeypatch):
    monkeypatch.delenv(budget.ENV_VAR, raising=False)
    limit, source = budget.memory_limit()
    physical = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    assert limit == pytest.approx(0.5 * physical, rel=1e-12) and "half" in source


def _traced_peak(path):
    """The traced peak of simulating ``path`` and of running the EKF on it after."""
    from fuzzynav.experiment import run_on_log

    scn = load_scenario(path)
    tracemalloc.start()
    try:
        log = simulate(scn, 0)
        sim = tracemalloc.get_traced_memory()[1]
        tracemalloc.reset_peak()
        run_on_log(log, "ekf")
        return sim, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("block", [None, 500])
def test_the_per_sample_figures_bound_a_real_run(tmp_path, monkeypatch, block):
    # the marginal memory of a sample (peak growth between a 40-s and an 80-s run, after a
    # warm-up that pays the one-off imports) stays under the budget's figures: within one
    # block of the trajectory generator (the shipped runs) the block's figure counts too;
    # with blocks of 500 samples (a long run) the per-sample figure alone
    from fuzzynav.sim import trajectory

    if block:
        monkeypatch.setattr(trajectory, "BLOCK_SAMPLES", block)
    paths = [_write(tmp_path / f"{d}.toml", RUN.format(rate=50, duration=d)) for d in (1, 40, 80)]
    _traced_peak(paths[0])
    small, large = _traced_peak(paths[1]), _traced_peak(paths[2])
    sim, run = ((b - a) / (40 * 50) for a, b in zip(small, large))
    bound = budget.BYTES_PER_IMU_SAMPLE + (0 if block else budget.BYTES_PER_BLOCK_SAMPLE)
    assert 0 < sim < bound and 0 < run < bound
    # the figures are of a whole run: the simulation's and the filter's peaks together
    assert sim + run < bound


def test_base_files_stay_inside_the_scenario_directory(tmp_path):
    _write(tmp_path / "parts" / "parent.toml", RUN.format(rate=50, duration=10))
    child = _write(tmp_path / "child.toml", 'base = "parts/parent.toml"\nname = "c"\n')
    assert load_scenario(child).name == "c"
    outside = _write(tmp_path / "outside.toml", RUN.format(rate=50, duration=10))
    inner = _write(tmp_path / "inner" / "x.toml", 'base = "../outside.toml"\n')
    with pytest.raises(InputFileError, match="outside the scenario's own directory") as exc:
        load_scenario(inner)
    assert exc.value.where == "base" and exc.value.path == str(inner)
    # a link inside the directory that points out of it is followed, then refused
    (tmp_path / "inner" / "link.toml").symlink_to(outside)
    _write(tmp_path / "inner" / "y.toml", 'base = "link.toml"\n')
    with pytest.raises(InputFileError, match="outside"):
        load_scenario(tmp_path / "inner" / "y.toml")


def test_special_and_huge_files_are_refused_unread(tmp_path):
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)  # opening it would block forever
    with pytest.raises(InputFileError, match="not a regular file"):
        load_scenario(fifo)
    huge = tmp_path / "huge.toml"
    with open(huge, "wb") as fh:
        fh.truncate(MAX_TOML_BYTES + 1)  # sparse
    with pytest.raises(InputFileError, match=f"at most {MAX_TOML_BYTES} bytes"):
        load_scenario(huge)


def test_safe_stem():
    assert safe_stem("paper000-alt") == "paper000-alt"
    assert safe_stem("../a b/c") == "_a_b_c"
    long_a, long_b = safe_stem("x" * 300), safe_stem("x" * 299 + "y")
    assert len(long_a) == 64 and long_a != long_b


def test_a_run_cut_from_its_cached_log_stays_within_the_streamed_estimate(tmp_path):
    """The chunks of a short run are cut from its cached whole log when there is one, which
    the run then holds (288 B a sample, more than the 184 B of truth a simulated run keeps):
    the traced peak of such a run is over the log's size and under
    :func:`streamed_estimate`, which counts that log."""
    from fuzzynav.streamrun import run_streamed

    path = _write(tmp_path / "c.toml", RUN.format(rate=50, duration=2000))
    scn, cache = load_scenario(path), tmp_path / "cache"
    simulate(scn, 0, cache)  # the cache the chunks are cut from
    run_streamed(scn, 0, "ekf", chunk_samples=500, output_rate_hz=1.0, cache_dir=cache)
    tracemalloc.start()
    try:
        run_streamed(scn, 0, "ekf", chunk_samples=500, output_rate_hz=1.0, cache_dir=cache)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    log = budget.held_log_bytes(2000.0, 50.0, scn.sensors)
    simulated_path = (500 * budget.BYTES_PER_CHUNK_SAMPLE + budget.stored_truth_bytes(1e5)
                      + 2000 * (6 * budget.BYTES_PER_EPOCH_COLUMN + budget.BYTES_PER_OUTPUT_ROW))
    assert simulated_path < log < peak  # the figure of the simulated path alone is short
    assert peak < budget.streamed_estimate(2000.0, 50.0, scn.sensors, chunk_samples=500)


def test_a_base_is_not_refused_for_its_own_length(tmp_path, monkeypatch):
    """A short run derived from a long base fits a limit its base does not: the base is
    never simulated, only the derived run's size is checked (the tiny study flight was
    refused under 86 MB, paper000's streamed estimate).  A derived run made longer than
    the limit allows is still refused, under its own file's name."""
    base = _write(tmp_path / "long.toml", RUN.format(rate=100.0, duration=40_000.0))
    short = _write(tmp_path / "short.toml", 'base = "long.toml"\nname = "short"\n'
                   '[[segments]]\nkind = "cruise"\nduration_s = 60.0\n')
    longer = _write(tmp_path / "longer.toml", 'base = "short.toml"\nname = "longer"\n'
                    '[imu]\nrate_hz = 400.0\n[[segments]]\nkind = "cruise"\n'
                    'duration_s = 80000.0\n')
    monkeypatch.setenv(budget.ENV_VAR, str(64 / 1024))       # 64 MB
    with pytest.raises(InputFileError, match="limit"):
        load_scenario(str(base))
    scn = load_scenario(str(short))                            # its base: 40 000 s
    assert scn.duration_s == 60.0 and scn.imu.rate_hz == 100.0
    with pytest.raises(InputFileError, match="limit") as exc:   # its own 80 000 s at 400 Hz
        load_scenario(str(longer))
    assert "longer.toml" in str(exc.value)


def test_a_base_with_a_bad_value_is_still_refused_naming_the_base(tmp_path):
    """Only the size is left to the derived run: every other check of the base runs."""
    _write(tmp_path / "bad.toml", RUN.format(rate=-5.0, duration=100.0))
    derived = _write(tmp_path / "d.toml", 'base = "bad.toml"\n[imu]\nrate_hz = 50.0\n')
    with pytest.raises(InputFileError) as exc:
        load_scenario(str(derived))
    assert "bad.toml" in str(exc.value) and "rate_hz" in str(exc.value)


def test_a_navigation_file_based_on_an_alignment_scenario_says_which_kind_it_needs(tmp_path):
    """``base = "paper002"`` in a file without ``kind = "alignment"`` was "unknown scenario"
    with only the navigation built-ins listed."""
    derived = _write(tmp_path / "d.toml", 'base = "paper002-gusts"\nduration_s = 100.0\n')
    with pytest.raises(InputFileError) as exc:
        load_scenario(str(derived))
    assert exc.value.where == "base" and 'needs kind = "alignment"' in str(exc.value)
    with pytest.raises(InputFileError) as exc:          # a name of neither kind: no hint
        load_scenario(str(_write(tmp_path / "e.toml", 'base = "nowhere"\n')))
    assert "alignment" not in str(exc.value)
