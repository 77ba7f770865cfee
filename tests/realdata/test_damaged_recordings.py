"""A corpus of damaged recordings through ``fuzzynav run --data``: one clear line, exit 2.

Each case copies the synthetic drive (:func:`tests.realdata.rtklib_files.write_drive`, which the
whole protocol accepts: first test), applies ONE damage to one file and runs the CLI in
process.  It must exit with code 2, print one line on stderr naming the file and the field
(column, line, record) at fault and nothing on stdout (no results table), and no traceback.
"""
import contextlib
import io
import shutil
import struct

import numpy as np
import pytest

from fuzzynav.cli import main
from tests.realdata.rtklib_files import START, tag_bytes, write_drive

CSV, TAG, POS = "imu_1.csv", "imu_1.csv.tag", "gnss_1_sf.pos"
#: a short protocol: one 10-s outage 20 s after the filter starts
ARGS = ("--filter", "ekf", "--outage-period", "30", "--outage-duration", "10",
        "--first-outage", "20")
WEEK_S = 7 * 86400


def run_cli(directory, *extra):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["run", "--data", f"rtklib:{directory}", *ARGS, *extra])
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    d = tmp_path_factory.mktemp("drive")
    write_drive(d)
    return d


# -- damages: each edits one file of the directory ------------------------------------------
def _lines(d, name):
    return (d / name).read_text().split("\n")


def _write(d, name, lines):
    (d / name).write_text("\n".join(lines))


def _edit_fields(d, name, line_no, column, value):
    """Put ``value`` into field ``column`` of 1-based line ``line_no`` (CSV: commas)."""
    lines = _lines(d, name)
    sep = "," if name == CSV else None
    fields = lines[line_no - 1].split(sep)
    fields[column] = value
    lines[line_no - 1] = (sep or " ").join(fields)
    _write(d, name, lines)


def _map_csv_named(d, name, fn):
    """Apply ``fn`` to the float fields of every CSV line (a cut one is left alone)."""
    out = []
    for line in _lines(d, name):
        if line.count(",") == 6 and not line.endswith(","):
            v = fn(np.array(line.split(","), dtype=float))
            line = ",".join(f"{x:.6f}" for x in v[:6]) + f",{v[6]:.10g}"
        out.append(line)
    _write(d, name, out)


def _map_csv(d, fn):
    _map_csv_named(d, CSV, fn)


def _cut(d, name, fraction=None, size=None):
    raw = (d / name).read_bytes()
    (d / name).write_bytes(raw[:size if size is not None else int(len(raw) * fraction)])


def _shift_pos(d, seconds):
    from fuzzynav.realdata.loaders.rtkpos import read_pos
    from tests.realdata.rtklib_files import write_pos

    p = read_pos(d / POS)
    c = p.columns
    write_pos(d / POS, p.time_int_s + p.time_frac_s + seconds,
              np.column_stack([c["lat_deg"], c["lon_deg"], c["h_m"]]),
              np.column_stack([c["vel_e"], c["vel_n"], c["vel_u"]]), c["q"])


def _keep_pos_epochs(d, keep):
    lines = _lines(d, POS)
    head = [x for x in lines if x.startswith("%")]
    body = [x for x in lines if x and not x.startswith("%")]
    _write(d, POS, head + [b for b in body[keep]] + [""])


def _tag_records(d, fn):
    raw = (d / TAG).read_bytes()
    n = (len(raw) - 76) // 8
    rec = np.frombuffer(raw, dtype="<u4", count=2 * n, offset=76).reshape(n, 2)
    start = struct.unpack_from("<Id", raw, 64)
    recs, start = fn(rec.astype(np.int64), start)
    (d / TAG).write_bytes(tag_bytes(recs, start=start))


def _swap(v):
    return np.concatenate([v[3:6], v[0:3], v[6:]])


# (id, damage, file named, field named)
CASES = [
    ("csv-cut-mid-file", lambda d: _cut(d, CSV, 0.6), CSV, "end of file"),
    ("csv-two-lines", lambda d: _write(d, CSV, _lines(d, CSV)[:3] + [""]), CSV, "lines"),
    ("csv-nan-row", lambda d: _edit_fields(d, CSV, 500, 1, "nan"), CSV, "line 500, column acc y"),
    ("csv-inf", lambda d: _edit_fields(d, CSV, 700, 5, "inf"), CSV, "line 700, column gyro z"),
    ("csv-non-numeric", lambda d: _edit_fields(d, CSV, 800, 6, "12a"), CSV,
     "line 800, column tick"),
    ("csv-six-fields", lambda d: _write(d, CSV, [x.rsplit(",", 1)[0] if i == 899 else x
                                                for i, x in enumerate(_lines(d, CSV))]),
     CSV, "line 900"),
    ("csv-duplicate-tick", lambda d: _edit_fields(d, CSV, 1000, 6,
                                                  _lines(d, CSV)[998].split(",")[6]),
     CSV, "line 1000, column tick"),
    ("csv-tick-backwards", lambda d: _edit_fields(d, CSV, 1200, 6, "5"), CSV,
     "line 1200, column tick"),
    ("csv-tick-jumps-a-day", lambda d: _map_csv(
        d, lambda v: v + np.r_[np.zeros(6), 86_400_000.0 * (v[6] > 30_000)]), CSV, "column tick"),
    ("csv-ticks-in-seconds", lambda d: _map_csv(d, lambda v: v / np.r_[np.ones(6), 1000.0]),
     CSV, "column tick"),
    ("csv-ticks-in-microseconds", lambda d: _map_csv(d, lambda v: v * np.r_[np.ones(6), 1000.0]),
     CSV, "column tick"),
    ("csv-acc-gyro-swapped", lambda d: _map_csv(d, _swap), CSV, "columns acc x,y,z"),
    ("csv-acc-in-mps2", lambda d: _map_csv(d, lambda v: v * np.r_[[9.80665] * 3, np.ones(4)]),
     CSV, "columns acc x,y,z"),
    ("csv-gyro-in-mdps", lambda d: _map_csv(d, lambda v: v * np.r_[np.ones(3), [1e3] * 3, 1.0]),
     CSV, "columns gyro x,y,z"),
    ("csv-gyro-in-rad-s", lambda d: _map_csv(d, lambda v: v * np.r_[np.ones(3),
                                                                  [np.pi / 180] * 3, 1.0]),
     CSV, "columns gyro x,y,z"),
    ("csv-gyro-offset-10-dps", lambda d: _map_csv(d, lambda v: v + np.r_[np.zeros(3), 10.0,
                                                                       np.zeros(3)]),
     CSV, "columns gyro x,y,z"),
    ("csv-acc-spike", lambda d: _edit_fields(d, CSV, 3000, 2, "80.0"), CSV,
     "line 3000, columns acc x,y,z"),
    ("csv-empty", lambda d: (d / CSV).write_bytes(b""), CSV, "lines"),
    ("csv-binary-garbage", lambda d: (d / CSV).write_bytes(bytes(range(256)) * 40), CSV,
     "line 2"),
    ("csv-is-a-directory", lambda d: ((d / CSV).unlink(), (d / CSV).mkdir()), CSV,
     "not a regular file"),
    ("tag-empty", lambda d: (d / TAG).write_bytes(b""), TAG, "header"),
    ("tag-cut-in-header", lambda d: _cut(d, TAG, size=70), TAG, "header"),
    ("tag-cut-at-half", lambda d: _cut(d, TAG, 0.5), TAG, "record"),
    ("tag-not-a-tag", lambda d: (d / TAG).write_bytes(b"NOTATAG" + (d / TAG).read_bytes()[7:]),
     TAG, "header"),
    ("tag-tick-decreases", lambda d: _tag_records(
        d, lambda r, s: (np.vstack([r[:9], r[10:11], r[9:10], r[11:]]), s)), TAG, "record"),
    ("tag-from-another-week", lambda d: _tag_records(
        d, lambda r, s: (r, (s[0] - WEEK_S, s[1]))), POS, "column GPST"),
    ("pos-from-another-week", lambda d: _shift_pos(d, WEEK_S), POS, "column GPST"),
    ("pos-no-fixed-epochs", lambda d: _write(d, POS, [x.replace(" 1 20 ", " 2 20 ")
                                                     for x in _lines(d, POS)]), POS, "column Q"),
    ("pos-five-seconds-only", lambda d: _keep_pos_epochs(d, slice(100, 120)), POS,
     "column GPST"),
    ("pos-nan-latitude", lambda d: _edit_fields(d, POS, 50, 2, "nan"), POS,
     "line 50, column latitude(deg)"),
    ("pos-quality-7", lambda d: _edit_fields(d, POS, 60, 5, "7"), POS, "line 60, column Q"),
    ("pos-negative-sigma", lambda d: _edit_fields(d, POS, 70, 7, "-0.010"), POS,
     "line 70, column sdn(m)"),
    ("pos-cut-mid-line", lambda d: _cut(d, POS, 0.5), POS, "line"),
    ("pos-epochs-out-of-order", lambda d: _write(d, POS, (lambda x: x[:40] + [x[41], x[40]]
                                                         + x[42:])(_lines(d, POS))),
     POS, "line 42"),
    ("pos-empty", lambda d: (d / POS).write_bytes(b""), POS, "lines"),
    ("pos-is-a-directory", lambda d: ((d / POS).unlink(), (d / POS).mkdir()), POS,
     "not a regular file"),
    ("pos-day-38", lambda d: _edit_fields(d, POS, 50, 0, _lines(d, POS)[49].split()[0][:8]
                                          + "38"), POS, "line 50"),
    ("pos-month-13", lambda d: _edit_fields(d, POS, 50, 0, _lines(d, POS)[49].split()[0][:5]
                                            + "13" + _lines(d, POS)[49].split()[0][7:]),
     POS, "line 50"),
    ("pos-hour-25", lambda d: _edit_fields(d, POS, 50, 1, "25"
                                           + _lines(d, POS)[49].split()[1][2:]), POS, "line 50"),
    ("pos-second-60", lambda d: _edit_fields(d, POS, 50, 1, _lines(d, POS)[49].split()[1][:6]
                                             + "60.000"), POS, "line 50"),
    ("pos-second-inf", lambda d: _edit_fields(d, POS, 50, 1, _lines(d, POS)[49].split()[1][:6]
                                              + "inf"), POS, "line 50"),
    ("pos-no-header", lambda d: _write(d, POS, [x for x in _lines(d, POS)
                                               if not x.startswith("%")]), POS, "header"),
]


def test_the_undamaged_drive_runs(drive):
    """The original of every case loads and prints a table (so the damage is what fails)."""
    code, out, err = run_cli(drive)
    assert code == 0, err
    assert "horizontal position RMS (m)" in out


@pytest.mark.parametrize("damage, name, field", [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_damaged_recording_is_refused_in_one_line(drive, tmp_path, damage, name, field):
    d = tmp_path / "rec"
    shutil.copytree(drive, d)
    damage(d)
    code, out, err = run_cli(d)
    assert code == 2, (out[-300:], err)
    assert out == "", out[-300:]
    assert err.count("\n") == 1 and err.startswith("fuzzynav: error: ") and \
        "Traceback" not in err, err
    assert str(d / name) in err and field in err, err


_IMU_CASES = [c for c in CASES if c[2] in (CSV, TAG)]


@pytest.mark.parametrize("damage", [c[1] for c in _IMU_CASES], ids=[c[0] for c in _IMU_CASES])
def test_a_damaged_imu_read_from_its_file_is_refused_as_the_held_load(drive, tmp_path, damage):
    """``--output-rate`` reads the IMU streamed (its rows read again per use,
    :mod:`fuzzynav.realdata.loaders.imu_file`): the same checks, the same one line."""
    d = tmp_path / "rec"
    shutil.copytree(drive, d)
    damage(d)
    held = run_cli(d)
    assert run_cli(d, "--output-rate", "1") == held
    assert held[0] == 2


# -- what is repaired, not refused ------------------------------------------------------------
def _load(d, **kw):
    from fuzzynav.realdata.loaders.rtklib import load_rtklib

    return load_rtklib(d, mounting=None, **kw)


def test_blank_and_comment_lines_are_skipped(drive, tmp_path):
    d = tmp_path / "rec"
    shutil.copytree(drive, d)
    lines = _lines(d, CSV)
    for at, extra in ((3000, ""), (2000, "# logger restarted"), (1000, "  "), (10, "\r")):
        lines.insert(at, extra)
    _write(d, CSV, lines)
    rec, ref = _load(d, resample_hz=None), _load(drive, resample_hz=None)
    # the same samples; the skipped bytes (26, counted as logged) move the later lines past
    # the record that covered them (records fall on line ends here): at most one record
    # interval (15.5 ms) later
    assert rec.timing.method == "tag-fit"
    shift = rec.imu.time_s - ref.imu.time_s
    assert np.all((shift > -1e-3) & (shift < 0.0155))
    np.testing.assert_allclose(rec.imu.dv_b, ref.imu.dv_b, rtol=1e-3, atol=1e-6)


def test_logging_stopped_inside_a_line_and_a_tag_record(drive, tmp_path):
    """The tag's last record cut (as an interrupted write leaves it), the CSV cut 20 bytes
    after the last line that record counted: both cut pieces are dropped, the rest kept."""
    from fuzzynav.realdata.loaders.timetag import read_timetag

    d = tmp_path / "rec"
    shutil.copytree(drive, d)
    _cut(d, TAG, size=(d / TAG).stat().st_size - 5)
    logged = int(read_timetag(d / TAG).fpos[-1])         # CR LF line ends, as logged
    n_lines = int(np.searchsorted(np.cumsum([len(x) + 2 for x in _lines(d, CSV)]), logged)) + 1
    _cut(d, CSV, size=logged - n_lines + 20)
    rec, ref = _load(d, resample_hz=None), _load(drive, resample_hz=None)
    assert rec.timing.method == "tag-fit"
    # samples = complete lines less the first (always dropped)
    assert rec.imu.time_s.size == n_lines - 1 and ref.imu.time_s.size > n_lines
    np.testing.assert_allclose(rec.imu.time_s, ref.imu.time_s[:n_lines - 1], atol=1e-3)


def test_limits_can_be_widened_for_an_unusual_sensor(drive, tmp_path):
    from fuzzynav.errors import InputFileError
    from fuzzynav.realdata.loaders.checks import Limits

    d = tmp_path / "rec"
    shutil.copytree(drive, d)
    _map_csv(d, lambda v: v + np.r_[np.zeros(3), 10.0, np.zeros(3)])   # a 10-deg/s bias
    with pytest.raises(InputFileError, match="gyro_rest_max_rps"):
        _load(d)
    assert _load(d, limits=Limits(gyro_rest_max_rps=0.2)).imu.n_samples > 0


# -- a copy of the real drive ------------------------------------------------------------------
REAL = ("imu_1934.csv", "imu_1934.csv.tag", "gnss_1934_sf.pos")


@pytest.mark.parametrize("damage, name, field", [
    (lambda d: _cut(d, "imu_1934.csv", 0.5), "imu_1934.csv", "end of file"),
    (lambda d: _cut(d, "imu_1934.csv.tag", 0.7), "imu_1934.csv.tag", "record"),
    (lambda d: _map_csv_named(d, "imu_1934.csv", _swap), "imu_1934.csv", "swapped"),
], ids=["csv-cut-at-half", "tag-cut", "acc-gyro-swapped"])
def test_damaged_copy_of_the_real_drive(rtklib_drive, tmp_path, damage, name, field):
    for f in REAL:
        shutil.copy(rtklib_drive / f, tmp_path / f)
    damage(tmp_path)
    code, out, err = run_cli(tmp_path)
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert str(tmp_path / name) in err and field in err, err


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_an_absurd_value_is_named_with_no_numpy_warning_before_the_line(drive, tmp_path):
    """1e300 overflows to inf in the physics check, which names it; numpy's overflow
    warnings came before that line on stderr (here: turned into errors)."""
    d = tmp_path / "rec"
    shutil.copytree(drive, d)
    _edit_fields(d, CSV, 3000, 0, "1e300")
    code, out, err = run_cli(d)
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert "line 3000, columns acc x,y,z: magnitude inf" in err
