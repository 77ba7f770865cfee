"""The recording loaders read their files a block of lines at a time (``chunk_rows``).

Every block size must give the arrays of the whole read (``chunk_rows=None``) to the last
bit, and the same error for a defect wherever it falls -- in particular exactly on a block
boundary, where the check needs the previous block's last row.  The numbers themselves
are checked against what the test wrote (parsed independently by Python's ``float``).
"""
import dataclasses

import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.realdata.loaders import checks
from fuzzynav.realdata.loaders.akit_recording import load_trajectory, read_table
from fuzzynav.realdata.loaders.imu_csv import read_imu_csv
from fuzzynav.realdata.loaders.rtklib import load_rtklib
from tests.conftest import datasets_dir
from tests.realdata.akit_files import auv_trajectory, write_akit
from tests.realdata.rtklib_files import write_drive

SIZES = (1, 2, 3, 7, 64)


def _imu_lines(n, tick0=1000, step=10):
    rng = np.random.default_rng(5)
    vals = rng.normal(0.0, 1.0, (n, 6))
    return [",".join(f"{x:.6f}" for x in row) + f",{tick0 + step * k}"
            for k, row in enumerate(vals)]


def _write_csv(path, lines, head="0.12,", tail="0.5,0.1"):
    # a cut first line, blank and comment lines inside, a cut last line (no newline)
    body = lines[:5] + [""] + lines[5:9] + ["# resumed"] + lines[9:]
    path.write_bytes((head + "\n" + "\n".join(body) + "\n" + tail).encode())


def _same(a, b):
    return all(np.array_equal(x, y) and x.dtype == y.dtype for x, y in zip(a[:3], b[:3])) \
        and a[3] == b[3]


def test_rtklib_csv_blocks_give_the_whole_read_and_the_written_numbers(tmp_path):
    lines = _imu_lines(40)
    path = tmp_path / "imu_1.csv"
    _write_csv(path, lines)
    whole = read_imu_csv(path, None)
    expected = np.array([[float(f) for f in line.split(",")] for line in lines])
    np.testing.assert_array_equal(whole[0], expected)
    # 0-based file lines of the rows: after the cut line 0, skipping the blank and comment
    np.testing.assert_array_equal(whole[1], [*range(1, 6), *range(7, 11), *range(12, 43)])
    assert whole[2].size == 44 and whole[3] == path.stat().st_size
    for rows in SIZES:
        assert _same(read_imu_csv(path, rows), whole), rows


def _error(fn, *args):
    with pytest.raises(InputFileError) as exc:
        fn(*args)
    return str(exc.value)


@pytest.mark.parametrize("defect", ["backwards", "repeat"])
def test_rtklib_tick_defect_on_a_block_boundary(tmp_path, defect):
    """The first line of the second block (file line 8 with 7-line blocks, 0-based 7) holds
    a tick that does not increase on the first block's last row."""
    lines = _imu_lines(30)
    path = tmp_path / "imu_1.csv"
    path.write_bytes(("cut\n" + "\n".join(lines) + "\n").encode())
    # file line k (0-based) holds sample k - 1; line 7 opens the second 7-line block
    prev = 1000 + 10 * 5
    bad = lines[6].rsplit(",", 1)[0] + f",{prev - 3 if defect == 'backwards' else prev}"
    path.write_bytes(("cut\n" + "\n".join(lines[:6] + [bad] + lines[7:]) + "\n").encode())
    whole = _error(read_imu_csv, path, None)
    assert str(path) in whole and "line 8, column tick" in whole
    assert ("repeats the previous tick 1050" if defect == "repeat" else "1047 after 1050") in whole
    for rows in (7, *SIZES):
        assert _error(read_imu_csv, path, rows) == whole, rows


def test_rtklib_bad_field_after_a_tick_defect_is_reported_as_a_whole_read_does(tmp_path):
    """A whole read refuses a field that is not a number before any tick order: blocks
    that meet the tick defect first must still report the field."""
    lines = _imu_lines(30)
    lines[3] = lines[3].rsplit(",", 1)[0] + ",900"         # tick backwards, block 1
    lines[25] = lines[25].replace(",", ",x", 1)           # not a number, a later block
    path = tmp_path / "imu_1.csv"
    path.write_bytes(("cut\n" + "\n".join(lines) + "\n").encode())
    whole = _error(read_imu_csv, path, None)
    assert "line 27, column acc y" in whole and "is not a number" in whole
    for rows in SIZES:
        assert _error(read_imu_csv, path, rows) == whole, rows


def test_rtklib_gap_straddling_a_block_boundary(tmp_path):
    """A 3-s tick gap between the last row of one block and the first of the next is
    refused by the loader's tick check, with the same message as a whole read."""
    write_drive(tmp_path)
    path = tmp_path / "imu_1.csv"
    text = path.read_bytes().split(b"\n")
    k = 1000  # 0-based file line: the first of the second block of 1000 lines
    for i in range(k, len(text)):
        fields = text[i].split(b",")
        if len(fields) == 7:
            fields[6] = str(int(fields[6]) + 3000).encode()
            text[i] = b",".join(fields)
    path.write_bytes(b"\n".join(text))
    data, kept, _, _ = read_imu_csv(path, 1000)
    whole = _error(lambda: load_rtklib(tmp_path, chunk_rows=None))
    assert f"line {k + 1}, column tick" in whole and "jumps by 3.01 s" in whole
    assert _error(lambda: load_rtklib(tmp_path, chunk_rows=1000)) == whole
    # the check itself on the block-read columns, independently of the loader
    assert _error(checks.imu_ticks, path, data[:, 6], kept + 1) == whole


def test_rtklib_synthetic_recording_is_the_same_in_blocks(tmp_path):
    write_drive(tmp_path)
    whole = load_rtklib(tmp_path, chunk_rows=None)
    for rows in (977, 4096):
        rec = load_rtklib(tmp_path, chunk_rows=rows)
        _assert_same_recording(rec, whole)


def _assert_same_recording(rec, whole):
    for name in ("time_s", "dtheta_b", "dv_b"):
        np.testing.assert_array_equal(getattr(rec.imu, name), getattr(whole.imu, name), name)
    for stream in ("gnss", "reference"):
        a, b = getattr(rec, stream), getattr(whole, stream)
        for name in ("time_s", "z", "sigma"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    a, b = rec.timing, whole.timing
    assert dataclasses.replace(a, clock=None) == dataclasses.replace(b, clock=None)
    np.testing.assert_array_equal(a.clock.time_ms, b.clock.time_ms)
    assert rec.epoch_gpst_s == whole.epoch_gpst_s


def _akit_rows(n):
    t = np.arange(n) * 0.01
    rng = np.random.default_rng(2)
    return np.column_stack([t, rng.normal(0, 1, (n, 6))])


def _write_table(path, rows, header="Time [s],a,b,c,d,e,f"):
    path.write_text(header + "\n" + "\n".join(",".join(repr(float(x)) for x in r)
                                             for r in rows) + "\n")


def test_akit_table_blocks_give_the_whole_read(tmp_path):
    rows = _akit_rows(300)
    path = tmp_path / "IMU_trajectory1.csv"
    _write_table(path, rows)
    whole = read_table(path, "IMU", None)
    np.testing.assert_array_equal(whole, rows)  # repr round-trips every float
    for size in SIZES:
        got = read_table(path, "IMU", size)
        assert got.dtype == whole.dtype and np.array_equal(got, whole), size


@pytest.mark.parametrize("size", [7, 8])
def test_akit_time_backwards_on_a_block_boundary(tmp_path, size):
    """Block 1 holds the header and rows of lines 2..size; line size + 1 opens block 2."""
    rows = _akit_rows(300)
    k = size - 1  # 0-based row on file line size + 1
    rows[k, 0] = rows[k - 1, 0] - 0.001
    path = tmp_path / "IMU_trajectory1.csv"
    _write_table(path, rows)
    whole = _error(read_table, path, "IMU", None)
    assert str(path) in whole and f"line {size + 1}, column Time [s]" in whole
    assert "time does not increase" in whole
    for n in (size, *SIZES):
        assert _error(read_table, path, "IMU", n) == whole, n


def test_akit_gap_straddling_a_block_boundary(tmp_path):
    rows = _akit_rows(300)
    rows[64:, 0] += 2.5  # between the rows on lines 65 and 66
    path = tmp_path / "IMU_trajectory1.csv"
    _write_table(path, rows)
    whole = _error(read_table, path, "IMU", None)
    assert "line 66, column Time [s]" in whole and "a gap of 2.51 s after 0.63 s" in whole
    for n in (65, *SIZES):
        assert _error(read_table, path, "IMU", n) == whole, n


def test_akit_bad_row_after_a_time_defect_is_reported_as_a_whole_read_does(tmp_path):
    rows = _akit_rows(300)
    rows[3, 0] = 0.0
    path = tmp_path / "IMU_trajectory1.csv"
    _write_table(path, rows)
    text = path.read_text().split("\n")
    text[200] = text[200] + ",1.0"  # a row with an extra column in a later block
    path.write_text("\n".join(text))
    whole = _error(read_table, path, "IMU", None)
    assert "line 201" in whole and "has 8 columns, expected 7" in whole
    for n in SIZES:
        assert _error(read_table, path, "IMU", n) == whole, n


def test_akit_synthetic_trajectory_is_the_same_in_blocks(tmp_path):
    write_akit(tmp_path, auv_trajectory(), n=1, lag=0.4)
    whole = load_trajectory(tmp_path, 1, chunk_rows=None)
    rec = load_trajectory(tmp_path, 1, chunk_rows=1001)
    for name in ("time_s", "dtheta_b", "dv_b"):
        np.testing.assert_array_equal(getattr(rec.imu, name), getattr(whole.imu, name))
    np.testing.assert_array_equal(rec.dvl.z, whole.dvl.z)
    np.testing.assert_array_equal(rec.reference.lla, whole.reference.lla)
    assert rec.clock == whole.clock


def test_block_size_must_be_a_positive_whole_number(tmp_path):
    path = tmp_path / "imu_1.csv"
    _write_csv(path, _imu_lines(10))
    for bad in (0, -3, 2.5):
        with pytest.raises(ValueError, match="chunk_rows"):
            read_imu_csv(path, bad)


# -- the real recordings -------------------------------------------------------------------
DRIVE = datasets_dir() / "rtklib-drive"
AKIT = datasets_dir() / "akit"


@pytest.mark.skipif(not (DRIVE / "imu_1934.csv").is_file(),
                    reason=f"real recording not found: {DRIVE} (set FUZZYNAV_DATA)")
def test_real_drive_is_the_same_in_blocks():
    whole = load_rtklib(DRIVE, chunk_rows=None)
    for rows in (1000, 4096, 1 << 16):  # the drive has 54 900 lines: 55, 14 and 1 blocks
        _assert_same_recording(load_rtklib(DRIVE, chunk_rows=rows), whole)


@pytest.mark.skipif(not (AKIT / "IMU_trajectory1.csv").is_file(),
                    reason=f"real recording not found: {AKIT} (set FUZZYNAV_DATA)")
@pytest.mark.parametrize("n", range(1, 9))
def test_real_akit_tables_are_the_same_in_blocks(n):
    for path, kind in ((AKIT / f"IMU_trajectory{n}.csv", "IMU"),
                       (AKIT / "corrected" / f"DVL_trajectory{n}.csv", "DVL"),
                       (AKIT / "corrected" / f"GT_trajectory{n}.csv", "GT")):
        whole = read_table(path, kind, None)
        for rows in (97, 4096):
            assert np.array_equal(read_table(path, kind, rows), whole), (path, rows)


def test_increments_in_blocks_are_the_whole_integrals_to_the_bit():
    """The running integral carried across blocks of samples gives every increment of the
    one-block integration exactly (zero rates and their signs included), and the
    increments of a piecewise-linear rate are its exact integrals (the trapezoid is exact)."""
    from fuzzynav.realdata.loaders.increments import integrate_rates

    rng = np.random.default_rng(1)
    t = np.cumsum(rng.uniform(0.009, 0.011, 3000))
    w = rng.normal(0, 1, (3000, 6))
    w[100:200] = 0.0
    w[150] = -0.0
    grids = (np.arange(np.ceil(t[0] * 100), np.floor(t[-1] * 100) + 1) / 100, t[3:],
             np.linspace(t[0], t[-1], 7))
    for bounds in grids:
        whole = integrate_rates(t, w, bounds)
        for block in (1, 2, 17, 1000, 2999, 10**6):
            got = integrate_rates(t, lambda a, b: w[a:b], bounds, block)
            assert np.array_equal(got, whole) and np.array_equal(np.signbit(got),
                                                                 np.signbit(whole)), block
    # at the sample instants: the trapezoid of each interval, by its definition
    np.testing.assert_allclose(integrate_rates(t, w, t, 7),
                               0.5 * (w[1:] + w[:-1]) * np.diff(t)[:, None], rtol=1e-9,
                               atol=1e-12)


@pytest.mark.parametrize("text", [b"", b"a", b"a\n", b"a\nb", b"\n\n", b"a\r\nb\r\n"])
def test_count_lines_is_what_the_blocks_yield(tmp_path, text):
    from fuzzynav.realdata.loaders.chunked import count_lines, line_blocks

    path = tmp_path / "f"
    path.write_bytes(text)
    with open(path, "rb") as f:
        assert count_lines(path) == sum(len(b) for _, b in line_blocks(f, 1)) \
            == len(text.splitlines(keepends=True))
