"""The A-KIT loader's array steps made in blocks: the same recording whatever the block.

The clock estimate (attitude track, earth rate, misfit search and its refinement), the
increments and the pitch check work through a recording a block at a time so that a long
file's temporaries are a block's (``akit_timing.BLOCK_ELEMENTS``).  Every number they make
is its own sample's or (shift, epoch) pair's, or a mean over a whole row, so any block size
must give the arrays of the whole-array computation to the last bit; these tests load the
same files with blocks of a few elements and compare, and check the window means and the
row parser against plain references written here.
"""
import numpy as np
import pytest

from fuzzynav import units
from fuzzynav.nav import attitude
from fuzzynav.errors import InputFileError
from fuzzynav.realdata.loaders import akit_checks, akit_recording, akit_timing
from fuzzynav.realdata.loaders.akit_recording import load_trajectory, read_table
from tests.realdata.akit_files import auv_trajectory, write_akit


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("akit-blocks")
    # turns and a climb: the clock and the pitch check both have something to see
    write_akit(d, auv_trajectory(), n=1, lag=0.6, rate=1.0025, lever_y=1.5)
    return d


def _arrays(rec):
    return {"imu.time_s": rec.imu.time_s, "imu.dtheta_b": rec.imu.dtheta_b,
            "imu.dv_b": rec.imu.dv_b, "dvl.time_s": rec.dvl.time_s, "dvl.z": rec.dvl.z,
            "ref.time_s": rec.reference.time_s, "ref.lla": rec.reference.lla,
            "ref.vel_n": rec.reference.vel_n, "ref.q_bn": rec.reference.q_bn,
            "offset_b": rec.reference_offset_b,
            "clock": np.array([rec.clock.offset_s, rec.clock.rate, rec.clock.dvl_offset_s])}


@pytest.mark.parametrize("block", [1, 7, 401 * 3 + 5])
def test_any_block_size_loads_the_same_recording_to_the_bit(files, monkeypatch, block):
    whole = _arrays(load_trajectory(files, 1))
    # blocks of one element up to a few misfit columns: the steps' every boundary case
    for mod in (akit_timing, akit_recording):
        monkeypatch.setattr(mod, "BLOCK_ELEMENTS", block)
    blocked = _arrays(load_trajectory(files, 1))
    for name, a in whole.items():
        assert np.array_equal(a, blocked[name]), name


def test_the_load_recovers_the_clock_whatever_the_block(files, monkeypatch):
    """Not only the same numbers: the right ones (the files were written 0.6 s late with a
    clock 0.25 % fast)."""
    monkeypatch.setattr(akit_timing, "BLOCK_ELEMENTS", 5)
    clock = load_trajectory(files, 1).clock
    assert abs(clock.rate - 1.0025) < 2e-4
    assert abs(clock.offset_s - 0.6) < 0.02


def _masked_means(t, v, edges):
    """The window means by a mask per window (the check's former, quadratic form)."""
    return np.array([v[(t >= a) & (t < b)].mean() if np.any((t >= a) & (t < b)) else np.nan
                     for a, b in zip(edges[:-1], edges[1:])])


def test_window_means_are_the_masked_means_to_the_bit():
    rng = np.random.default_rng(4)
    t = np.cumsum(rng.uniform(0.005, 0.015, 20_000))
    t = np.concatenate([t[:5000], t[9000:] + 30.0])  # a 30-s stretch without samples
    v = rng.standard_normal(t.size)
    edges = np.arange(t[0], t[-1] + 1e-9, 10.0)
    got = akit_checks._window_means(t, v, edges)
    want = _masked_means(t, v, edges)
    assert np.isnan(got).sum() >= 2  # the empty windows are NaN, not a neighbour's value
    assert np.array_equal(np.isnan(got), np.isnan(want))
    # a slice and a masked copy are two code paths of numpy's sum: within rounding
    np.testing.assert_allclose(got[~np.isnan(got)], want[~np.isnan(want)], rtol=1e-12,
                               atol=1e-15)


def test_the_pitch_correlation_is_the_masked_one(files):
    imu = read_table(files / "IMU_trajectory1.csv", "IMU")
    gt = read_table(files / "corrected" / "GT_trajectory1.csv", "GT")
    lo, hi = max(imu[0, 0], gt[0, 0]), min(imu[-1, 0], gt[-1, 0])
    edges = np.arange(lo, hi + 1e-9, akit_checks.PITCH_WINDOW_S)
    f = _masked_means(imu[:, 0], imu[:, 1], edges)
    p = _masked_means(gt[:, 0], units.G0 * np.sin(gt[:, 8]), edges)
    ok = np.isfinite(f) & np.isfinite(p)
    want = float(np.corrcoef(f[ok], p[ok])[0, 1])
    assert want > 0.5  # the climb: the forward force follows g sin(pitch)
    assert abs(akit_checks.pitch_correlation(imu, gt) - want) < 1e-12


def test_the_gyro_track_in_windows_is_the_whole_chain(files):
    """Windows of the piecewise track against a plain cumulative product of the whole
    track (quaternion by quaternion here, not the loader's scalar loop)."""
    rec = load_trajectory(files, 1)
    t, dth = rec.imu.time_s, rec.imu.dtheta_b
    t_ref, q_ref = rec.reference.time_s, rec.reference.q_bn
    gyro = akit_timing.without_earth_rate(t, dth, t_ref, q_ref, rec.reference.lla[0, 0])
    inc = attitude.rotvec_to_quat(gyro)
    whole = np.empty((t.size, 4))
    whole[0] = 1.0, 0.0, 0.0, 0.0
    for k in range(inc.shape[0]):
        whole[k + 1] = attitude.quat_multiply(whole[k], inc[k])
    track = akit_timing.GyroTrack(t, dth, t_ref, q_ref, rec.reference.lla[0, 0])
    for lo, hi in ((0, 5), (3, 900), (900, 901), (2000, 7000), (t.size - 50, t.size - 1)):
        q, g = track.window(lo, hi)
        np.testing.assert_allclose(q, whole[lo:hi + 1], rtol=0, atol=1e-12)
        np.testing.assert_allclose(g, gyro[lo:min(hi, dth.shape[0] - 1) + 1], rtol=0, atol=0)
    with pytest.raises(ValueError, match="forward only"):
        track.window(10, 20)


def _python_rows(lines, ncol):
    """The rows as Python's ``float`` reads them, row by row."""
    return np.array([[float(x) for x in line.split(",")] for line in lines]).reshape(-1, ncol)


def test_the_fast_row_parse_gives_pythons_floats(files):
    lines = (files / "IMU_trajectory1.csv").read_text().splitlines()[1:]
    fast = akit_recording._parsed_at_once(lines, 7)
    assert fast is not None  # plain rows: numpy's reader
    assert np.array_equal(fast, _python_rows(lines, 7))
    # digits near the double rounding boundary, exponents, signs, surrounding blanks
    odd = ["0.1,1e-300,2.2250738585072014e-308,-0.0", " 1.5 ,+2,3.0000000000000004,7e22",
           "9007199254740993,0.30000000000000004,-1E+2,1.7976931348623157e308"]
    assert np.array_equal(akit_recording._parsed_at_once(odd, 4), _python_rows(odd, 4))


@pytest.mark.parametrize("row", ["1_0,2,3,4", "١,2,3,4"])
def test_a_spelling_only_python_reads_falls_back_to_it(row):
    """numpy's reader refuses digit separators and non-ASCII digits that ``float`` takes:
    those rows are read row by row, as before."""
    lines = ["1,2,3,4", row]
    assert akit_recording._parsed_at_once(lines, 4) is None
    assert np.array_equal(akit_recording._parse_rows("f.csv", lines, 2, 4),
                          _python_rows(lines, 4))


@pytest.mark.parametrize("bad,where", [("1,2,3", "line 3"), ("", "line 3"),
                                       ("1,2,x,4", "line 3"), ("1,inf,3,4", "line 3")])
def test_a_bad_row_is_named_by_the_row_by_row_parse(bad, where):
    lines = ["1,2,3,4", bad, "5,6,7,8"]
    assert akit_recording._parsed_at_once(lines, 4) is None
    with pytest.raises(InputFileError, match=where):
        akit_recording._parse_rows("f.csv", lines, 2, 4)
