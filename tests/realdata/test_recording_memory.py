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
from fuzzynav.realdata.loaders.imu_csv import HELD_BYTES_PER_LINE, read_imu_csv
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
    monkeypatch.setenv(budget.ENV_VAR, str(400 * HELD_BYTES_PER_LINE / 2 / 2**30))
    with pytest.raises(InputFileError) as exc:
        read_imu_csv(path)
    msg = str(exc.value)
    assert msg.startswith(str(path)) and "has 401 lines" in msg
    assert budget.human_bytes(401 * HELD_BYTES_PER_LINE) in msg, msg


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
