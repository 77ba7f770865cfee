"""A recording is judged by the memory its load needs, not by its file's size.

The loaders count a file's lines before parsing one (:func:`chunked.counted_lines`): a file
that is not text lines (megabytes in a few lines) is refused there, and so is one whose
lines, held once read, need more than one run may use (``$FUZZYNAV_MAX_MEMORY_GB``); the
message names the file, its lines, the estimate and the limit.
"""
import io

import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.realdata.loaders import akit_checks, chunked
from fuzzynav.realdata.loaders.akit_recording import read_table
from fuzzynav.realdata.loaders.imu_csv import (BLOCK_BYTES_PER_LINE, HELD_BYTES_PER_LINE,
                                               read_imu_csv)
from fuzzynav.sim import budget


def _akit_imu(path, n):
    t = np.arange(n) / 100.0
    rows = np.column_stack([t, np.random.default_rng(1).normal(0.0, 1.0, (n, 6))])
    path.write_text("Time [s],a,b,c,d,e,f\n" + "\n".join(",".join(repr(float(x)) for x in r)
                                                      for r in rows) + "\n")
    return rows


def _rtklib_imu(path, n):
    vals = np.random.default_rng(2).normal(0.0, 1.0, (n, 6))
    path.write_text("cut\n" + "\n".join(",".join(f"{x:.6f}" for x in r) + f",{1000 + 10 * k}"
                                        for k, r in enumerate(vals)) + "\n")


@pytest.mark.parametrize("text", [b"a\nb\nc", b"a\r\nb\r\nc\r\n", b"a\rb\rc", b"a\r\n\rb\n\nc\r",
                                  b"", b"\r", b"x"])
def test_universal_line_count_is_what_text_mode_reads(tmp_path, text):
    path = tmp_path / "f.csv"
    path.write_bytes(text)
    with open(path) as f:
        assert chunked.count_lines(path, universal=True) == len(f.readlines())
    assert chunked.count_lines(path) == len(io.BytesIO(text).readlines())


def test_a_crlf_pair_split_across_count_blocks_is_one_line_end(tmp_path):
    path = tmp_path / "f.csv"  # \r the last byte of the first 1-MB block, \n the next's first
    path.write_bytes(b"x" * ((1 << 20) - 1) + b"\r\n" + b"y\r\n")
    with open(path) as f:
        assert chunked.count_lines(path, universal=True) == len(f.readlines()) == 2


def test_an_akit_file_over_the_memory_limit_is_refused_with_its_estimate(tmp_path, monkeypatch):
    path = tmp_path / "IMU_trajectory1.csv"
    rows = _akit_imu(path, 2000)
    np.testing.assert_array_equal(read_table(path, "IMU"), rows)  # it fits the default
    monkeypatch.setenv(budget.ENV_VAR, str(1e-4))  # 105 kB
    need = 2001 * akit_checks.held_bytes_per_row(7)
    assert need > 1e-4 * 2**30
    with pytest.raises(InputFileError) as exc:
        read_table(path, "IMU")
    msg = str(exc.value)
    assert msg.startswith(str(path)) and "has 2001 lines" in msg, msg
    assert budget.human_bytes(need) in msg and f"${budget.ENV_VAR}" in msg, msg


def test_an_rtklib_imu_file_over_the_memory_limit_is_refused_with_its_estimate(tmp_path,
                                                                               monkeypatch):
    path = tmp_path / "imu_1.csv"
    _rtklib_imu(path, 400)
    assert read_imu_csv(path)[0].shape == (400, 7)
    need = 401 * (HELD_BYTES_PER_LINE + BLOCK_BYTES_PER_LINE)   # one block: the whole file
    monkeypatch.setenv(budget.ENV_VAR, str(need / 2 / 2**30))
    with pytest.raises(InputFileError) as exc:
        read_imu_csv(path)
    msg = str(exc.value)
    assert msg.startswith(str(path)) and "has 401 lines" in msg
    assert budget.human_bytes(need) in msg, msg
    # read 100 lines at a time, it holds its lines and one block of 100
    monkeypatch.setenv(budget.ENV_VAR, str(
        (401 * HELD_BYTES_PER_LINE + 100 * BLOCK_BYTES_PER_LINE) * 1.01 / 2**30))
    assert read_imu_csv(path, chunk_rows=100)[0].shape == (400, 7)


@pytest.mark.parametrize("write, read", [(_akit_imu, lambda p: read_table(p, "IMU")),
                                         (_rtklib_imu, read_imu_csv)])
def test_a_file_padded_with_nuls_is_not_read_as_one_huge_line(tmp_path, write, read):
    path = tmp_path / "imu.csv"
    write(path, 50)
    with open(path, "ab") as fh:  # sparse: nothing is really written
        fh.truncate(chunked.MAX_MEAN_LINE_BYTES * 52 + 1)
    with pytest.raises(InputFileError, match="MAX_MEAN_LINE_BYTES") as exc:
        read(path)
    assert str(exc.value).startswith(str(path))


@pytest.fixture(scope="module")
def auv_recording(tmp_path_factory):
    """A 300-s synthetic A-KIT trajectory, loaded (100-Hz IMU, 1-Hz DVL)."""
    from fuzzynav.realdata.loaders.akit_recording import load_trajectory
    from tests.realdata.akit_files import auv_trajectory, write_akit

    d = tmp_path_factory.mktemp("auv300")
    write_akit(d, auv_trajectory(300.0), n=1, lag=1.0)
    return load_trajectory(d, 1)


def test_the_output_estimate_bounds_what_a_run_on_a_recording_allocates(auv_recording):
    """``budget.check_run_outputs``'s figures against the peak tracemalloc sees while the
    run path filters a loaded recording at its full 10-Hz output: the estimate must bound
    it, and not by more than 4x (measured 540 B per output row with the events, against
    1 024 + 0.1 x 512 estimated)."""
    import tracemalloc

    from fuzzynav.realdata.akit import AkitSource
    from fuzzynav.runpath import run

    src = AkitSource(auv_recording)
    run(src, "ekf")                                   # compiled before the trace
    tracemalloc.start()
    out = run(src, "ekf")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    rows, epochs = out.result.time_s.size, sum(e.time_s.size for e in
                                               out.result.events.values())
    estimate = rows * budget.BYTES_PER_OUTPUT_ROW + epochs * budget.BYTES_PER_EVENT_ROW
    assert rows > 2900 and peak <= estimate <= 4 * peak, (rows, epochs, peak, estimate)


def test_a_run_whose_outputs_do_not_fit_is_refused_before_it_runs(auv_recording,
                                                                  monkeypatch):
    """Loaded, the recording's data fits a 2.5-MB limit; its 3 000 undecimated outputs do not:
    the run is refused naming the run, both figures and how to decimate; kept at 1 Hz in
    one piece it is refused too (all 3 000 rows are made before they are decimated), in
    chunks of 500 samples it runs (what ``--output-rate 1`` does)."""
    from fuzzynav.realdata.akit import AkitSource
    from fuzzynav.runpath import run

    src = AkitSource(auv_recording)
    imu = auv_recording.imu
    held = imu.time_s.nbytes + imu.dtheta_b.nbytes + imu.dv_b.nbytes
    limit = 2.5 * 2**20
    assert held < limit < held + 3000 * budget.BYTES_PER_OUTPUT_ROW   # the premise
    monkeypatch.setenv(budget.ENV_VAR, str(limit / 2**30))
    with pytest.raises(InputFileError) as exc:
        run(src, "ekf")
    msg = str(exc.value)
    assert exc.value.where == src.name and "kept outputs" in msg and "--output-rate" in msg
    assert f"limit is {budget.human_bytes(limit)}" in msg and "output_rate_hz" in msg, msg
    with pytest.raises(InputFileError, match="its 300 kept outputs \\(and 3e\\+03 made at a time"):
        run(src, "ekf", output_rate_hz=1.0)
    out = run(src, "ekf", output_rate_hz=1.0, chunk_samples=500)
    assert out.metrics["completed"] == 1.0 and out.result.time_s.size <= 301


@pytest.fixture(scope="module")
def car_drive(tmp_path_factory):
    """A synthetic car drive of 26 401 IMU lines (the rtklib format, 264 s)."""
    from fuzzynav.sim.segments import Segment
    from tests.realdata.rtklib_files import DRIVE_SEGMENTS, write_drive

    d = tmp_path_factory.mktemp("drive")
    write_drive(d, segments=list(DRIVE_SEGMENTS) + [Segment("cruise", 200.0)])
    return d


@pytest.mark.parametrize("chunk_rows", [None, 1024, 4096])
def test_the_load_estimate_bounds_a_traced_load_of_a_car_recording(car_drive, chunk_rows):
    """The guard's figure (the lines at HELD_BYTES_PER_LINE, the parse block at
    BLOCK_BYTES_PER_LINE) against tracemalloc's peak over the whole load, in one block and
    in blocks much smaller than the file: it must bound it, within 2x (measured 1.35-1.6)."""
    import tracemalloc

    from fuzzynav.realdata.loaders.rtklib import load_rtklib

    n = chunked.count_lines(car_drive / "imu_1.csv")
    load_rtklib(car_drive, chunk_rows=chunk_rows)            # imports and caches first
    tracemalloc.start()
    load_rtklib(car_drive, chunk_rows=chunk_rows)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    need = n * HELD_BYTES_PER_LINE + min(n, chunk_rows or n) * BLOCK_BYTES_PER_LINE
    assert peak <= need <= 2 * peak, (n, peak, need)
