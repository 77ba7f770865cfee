"""The RTKLIB loader on a synthetic recording whose true timing and rates are known."""
import math

import numpy as np
import pytest

from fuzzynav.errors import DataMissingError, InputFileError
from fuzzynav.realdata.loaders import rtklib, timetag
from tests.realdata.rtklib_files import csv_lines, write_imu, write_pos

START_INT, START_FRAC = 1_700_000_000, 0.25     # GPST of the tag file (seconds since 1970)
TICK0, N = 5000, 3001                          # IMU tick of the first line, lines
PC_RATE = 1.0005                               # PC ms per IMU ms (a poor clock)
LATENCY_MS = 100.0                             # fixed part of sample -> arrival
CHUNK_MS = 15.5
#: mean of what the logger adds to LATENCY_MS: uniform 0-10 ms buffering, then chunking
EXTRA_S = (5.0 + CHUNK_MS / 2) / 1000.0


def rates(t):
    """True gyro [deg/s] and accelerometer [g] at IMU-clock seconds ``t``."""
    w = np.column_stack([0.5 * np.sin(2 * np.pi * 0.2 * t), np.full_like(t, 1.0),
                         -0.3 + 0.1 * t])
    f = np.column_stack([np.full_like(t, 0.01), 0.02 * np.cos(t), np.full_like(t, 1.0)])
    return w, f


def build(tmp_path, crlf_stripped=True, tag_ok=True):
    """Write imu_1.csv(.tag) and gnss_1.pos; return the true sample GPST [s after START_INT],
    the IMU-clock sample instants [s] and the ticks."""
    rng = np.random.default_rng(0)
    n = np.arange(N)
    t_imu = n * 0.010                                          # true sample instants, IMU clock
    ticks = TICK0 + np.floor(n * 10.0 + rng.uniform(0, 1.9, N)).astype(int)  # jittered
    w, f = rates(t_imu)
    # arrival on the PC clock, ms since tag start
    sample_pc_ms = PC_RATE * t_imu * 1000.0
    # lines arrive in order, after a fixed latency and a random buffering delay
    arrival = np.maximum.accumulate(LATENCY_MS + sample_pc_ms + rng.uniform(0.0, 10.0, N))
    write_imu(tmp_path, csv_lines(f, w, ticks), arrival, start=(START_INT, START_FRAC),
              crlf_stripped=crlf_stripped, chunk_ms=CHUNK_MS, fpos_scale=1.0 if tag_ok else 0.5)
    write_static_pos(tmp_path / "gnss_1_sf.pos", START_INT - 2, 40)
    return START_FRAC + sample_pc_ms / 1000.0, t_imu, ticks


def write_static_pos(path, first_int, seconds):
    """4-Hz fixes jittering by 1e-7 deg about one point, every tenth a float (Q = 2)."""
    k = np.arange(seconds * 4)
    lla = np.column_stack([40.0 + (k % 10) * 1e-7, np.full(k.size, -105.0),
                           np.full(k.size, 1600.0)])
    vel = np.tile([2.0, 1.0, 0.1], (k.size, 1))
    write_pos(path, first_int + k * 0.25, lla, vel, np.where(k % 10 == 0, 2, 1))


def test_gps_time_of_the_pos_writer():
    # 1_700_000_000 s after 1970 is 2023-11-14 22:13:20 in the same (leap-free) count
    assert (1_700_000_000 // 60) % 60 == 13


@pytest.mark.parametrize("crlf_stripped", [True, False])
def test_time_alignment_recovers_the_true_clock(tmp_path, crlf_stripped):
    t_true, _, _ = build(tmp_path, crlf_stripped=crlf_stripped)
    rec = rtklib.load_rtklib(tmp_path, imu_delay_s=LATENCY_MS / 1000.0 + EXTRA_S,
                             resample_hz=None)
    assert rec.timing.method == "tag-fit" and rec.timing.crlf_restored == crlf_stripped
    # 30 s of +-5 ms arrival noise determine the rate to about 1e-5
    assert rec.timing.clock_rate == pytest.approx(PC_RATE, abs=4e-5)
    assert rec.timing.clock.regular and rec.timing.clock.n_missing == 0
    # native grid: the kept samples are lines 1 .. N-1 (the first is always dropped)
    t_loaded = rec.imu.time_s + (rec.epoch_gpst_s - START_INT)
    err = t_loaded - t_true[1:]
    assert np.ptp(err) < 0.003
    assert abs(np.mean(err)) < 0.004


def test_increments_integrate_the_true_rates(tmp_path):
    t_true, t_imu, _ = build(tmp_path)
    rec = rtklib.load_rtklib(tmp_path, mounting=None, imu_delay_s=LATENCY_MS / 1000 + EXTRA_S)
    assert np.allclose(np.diff(rec.imu.time_s), 0.01, atol=1e-9)      # GPST 100-Hz grid
    assert np.allclose(rec.imu.time_s * 100, np.round(rec.imu.time_s * 100), atol=1e-6)
    # the grid instants on the IMU clock (the loader's own clock model, whose accuracy the
    # previous test checks), then the exact integral of the true rates over GPST time:
    # d(GPST) = PC_RATE d(IMU clock)
    slope, icpt = np.polyfit(t_true[1:], t_imu[1:], 1)
    t_grid_imu = icpt + slope * (rec.imu.time_s + (rec.epoch_gpst_s - START_INT))
    fine = np.linspace(t_grid_imu[0], t_grid_imu[-1], 200001)
    wf, _ = rates(fine)
    cum = np.concatenate([np.zeros((1, 3)), np.cumsum(0.5 * (wf[1:] + wf[:-1])
                                                      * np.diff(fine)[:, None], 0)])
    exact = PC_RATE * np.diff(np.column_stack([np.interp(t_grid_imu, fine, cum[:, j])
                                               for j in range(3)]), axis=0)
    # piecewise-linear interpolation of a 0.2-Hz sine sampled at 100 Hz errs by ~1e-10 rad;
    # the recovered timing (+-1.5 ms) by up to 0.011 rad/s^2 x 1.5 ms x 10 ms = 1.6e-7 rad
    np.testing.assert_allclose(rec.imu.dtheta_b, np.deg2rad(exact), atol=3e-7)
    np.testing.assert_allclose(rec.imu.dv_b[:, 2], 9.80665 * 0.01, rtol=1e-12)


def test_fallback_when_the_tag_does_not_describe_the_file(tmp_path):
    build(tmp_path, tag_ok=False)
    rec = rtklib.load_rtklib(tmp_path, resample_hz=None, imu_delay_s=0.0)
    assert rec.timing.method == "endpoints"
    tag = timetag.read_timetag(tmp_path / "imu_1.csv.tag")
    # the sample clock is stretched onto [start, start + last tick]
    span = rec.imu.time_s[-1] - rec.imu.time_s[0]
    assert span == pytest.approx(tag.tick_ms[-1] / 1000.0, abs=1e-9)


def test_gnss_fixes_and_reference(tmp_path):
    build(tmp_path)
    rec = rtklib.load_rtklib(tmp_path)
    g, ref = rec.gnss, rec.reference
    assert g.kind == "gnss" and np.all((g.time_s >= rec.imu.time_s[0])
                                       & (g.time_s <= rec.imu.time_s[-1]))
    assert np.all(ref.meta["q"] == 1) and np.any(g.meta["q"] == 2)
    np.testing.assert_allclose(g.z[0, 3:], [2.0, 1.0, 0.1])        # ve, vn, vu
    np.testing.assert_allclose(g.sigma[0], [0.011, 0.010, 0.02, 0.06, 0.05, 0.07])
    assert np.all(np.diff(g.time_s) > 0)
    np.testing.assert_allclose(np.diff(g.time_s), 0.25, atol=1e-9)


def test_missing_files_name_the_path(tmp_path):
    with pytest.raises(DataMissingError, match="not found"):
        rtklib.load_rtklib(tmp_path / "nope")
    with pytest.raises(DataMissingError, match="imu_"):
        rtklib.load_rtklib(tmp_path)
    build(tmp_path)
    (tmp_path / "gnss_1_sf.pos").unlink()
    with pytest.raises(DataMissingError, match=r"gnss_1\*\.pos"):
        rtklib.load_rtklib(tmp_path)


def test_malformed_csv_line_is_named(tmp_path):
    build(tmp_path)
    p = tmp_path / "imu_1.csv"
    lines = p.read_bytes().split(b"\n")
    lines[100] = b"0.1,0.2,oops,0,0,0,6000"
    p.write_bytes(b"\n".join(lines))
    with pytest.raises(InputFileError) as exc:
        rtklib.load_rtklib(tmp_path)
    assert exc.value.where == "line 101, column acc z" and exc.value.path == str(p)


def test_span_outside_the_data(tmp_path):
    build(tmp_path)
    with pytest.raises(InputFileError, match="leaves no IMU data") as exc:
        rtklib.load_rtklib(tmp_path, span_s=(100.0, 200.0))
    assert exc.value.where == "span_s"


def test_malformed_tag_and_pos(tmp_path):
    build(tmp_path)
    tag = tmp_path / "imu_1.csv.tag"
    tag.write_bytes(b"NOTATAG" + tag.read_bytes()[7:])
    with pytest.raises(InputFileError, match="TIMETAG"):
        rtklib.load_rtklib(tmp_path)
    build(tmp_path)
    pos = tmp_path / "gnss_1_sf.pos"
    pos.write_text(pos.read_text().replace("latitude(deg)", "x-ecef(m)"))
    with pytest.raises(InputFileError, match="lat_deg") as exc:
        rtklib.load_rtklib(tmp_path)
    assert exc.value.where == "header"


def test_mounting_file_beside_the_data_is_used(tmp_path):
    build(tmp_path)
    (tmp_path / "mounting.toml").write_text("imu_rpy_frd_deg = [180.0, 0.0, 180.0]\n"
                                            "gnss_lever_arm_b_m = [-0.05, 0.0, 0.0]\n")
    plain = rtklib.load_rtklib(tmp_path, mounting=None)
    mounted = rtklib.load_rtklib(tmp_path)
    assert mounted.files["mounting"].name == "mounting.toml"
    # IMU (back, right, up) -> body RFU: x_b = y_imu, y_b = -x_imu, z_b = z_imu
    np.testing.assert_allclose(mounted.imu.dv_b[:, 0], plain.imu.dv_b[:, 1], atol=1e-15)
    np.testing.assert_allclose(mounted.imu.dv_b[:, 1], -plain.imu.dv_b[:, 0], atol=1e-15)
    np.testing.assert_allclose(mounted.gnss.meta["lever_arm_b"], [-0.05, 0.0, 0.0])
    assert math.isclose(mounted.imu.dv_b[:, 2].sum(), plain.imu.dv_b[:, 2].sum())
