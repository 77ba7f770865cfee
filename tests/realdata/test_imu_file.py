"""Recordings read from their file chunk by chunk (``load_rtklib(streamed=True)``,
:mod:`fuzzynav.realdata.loaders.imu_file`).

The streamed load keeps the rows' timing numbers only and makes the increments again from
the file when asked; each row's time is the held load's elementwise arithmetic and the
running integral is summed in the held load's order, so without a mounting (no matrix
product) the increments, the start and the protocol's metrics must be the held load's to
the last bit, whatever the blocks.  With a mounting the rotation is a matrix product over
blocks of other sizes (BLAS may group rows differently on another machine): compared
within 1e-13 relative there.
"""
import dataclasses
import os
import tracemalloc

import numpy as np
import pytest

from fuzzynav.errors import FuzzynavError, InputFileError
from fuzzynav.filters.runner import InitialState, run_filter
from fuzzynav.realdata import coarse_align
from fuzzynav.realdata.loaders.imu_file import SCAN_BYTES_PER_LINE, ImuCut, ImuFile, _joined
from fuzzynav.realdata.loaders.rtklib import load_rtklib
from fuzzynav.realdata.session import start_from
from fuzzynav.realdata.sources import MOUNTINGS_DIR
from fuzzynav.realdata.start_options import StartOptions
from fuzzynav.realdata.validate import validate
from fuzzynav.sim.segments import Segment
from tests.realdata.rtklib_files import DRIVE_SEGMENTS, write_drive

FIELDS = ("time_s", "dtheta_b", "dv_b")


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    d = tmp_path_factory.mktemp("drive")
    write_drive(d)
    return d


@pytest.fixture(scope="module")
def long_drive(tmp_path_factory):
    d = tmp_path_factory.mktemp("long-drive")
    write_drive(d, segments=list(DRIVE_SEGMENTS) + [Segment("cruise", 200.0)])
    return d


def _same(a, b):
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), f)


@pytest.mark.parametrize("kw", [{}, {"resample_hz": None}, {"span_s": (3.0, 50.0)},
                                {"resample_hz": 50.0}, {"imu_delay_s": 0.3}],
                         ids=["grid", "samples", "span", "50hz", "delay"])
@pytest.mark.parametrize("rows", [977, None])
def test_the_increments_read_again_are_the_held_loads_to_the_bit(drive, kw, rows):
    held = load_rtklib(drive, chunk_rows=rows, mounting=None, **kw)
    rec = load_rtklib(drive, chunk_rows=rows, mounting=None, streamed=True, **kw)
    assert isinstance(rec.imu, ImuFile)
    _same(_joined(list(rec.imu.pieces()), {}), held.imu)
    assert (rec.imu.n_samples, rec.imu.span_s, rec.imu.rate_hz) == \
        (held.imu.n_samples, held.imu.span_s, held.imu.rate_hz)
    assert rec.imu.meta == held.imu.meta
    last = held.imu.n_samples - 8
    for n, start in ((613, 17), (1, last), (10**6, 0)):  # chunks: inside, at the end, one
        got = list(rec.imu.chunks(n, start))
        assert all(c.n_samples == n for c in got[:-1]) and 0 < got[-1].n_samples <= n
        whole = _joined(got, {})
        for f in FIELDS:
            np.testing.assert_array_equal(getattr(whole, f), getattr(held.imu, f)[start:])
    win = rec.imu.window(10.0, 20.0)
    sel = np.flatnonzero((held.imu.time_s[:-1] >= 10.0) & (held.imu.time_s[:-1] <= 20.0))
    np.testing.assert_array_equal(win.dtheta_b, held.imu.dtheta_b[sel])
    np.testing.assert_array_equal(win.time_s, held.imu.time_s[sel[0]:sel[-1] + 2])
    for stream in ("gnss", "reference"):
        np.testing.assert_array_equal(getattr(rec, stream).z, getattr(held, stream).z)
    assert rec.epoch_gpst_s == held.epoch_gpst_s
    assert dataclasses.replace(rec.timing, clock=None) == \
        dataclasses.replace(held.timing, clock=None)


def test_with_a_mounting_the_increments_agree_within_rounding(drive):
    m = MOUNTINGS_DIR / "rtklib-drive.toml"
    held = load_rtklib(drive, mounting=m, chunk_rows=977)
    got = _joined(list(load_rtklib(drive, mounting=m, chunk_rows=977,
                                   streamed=True).imu.pieces()), {})
    np.testing.assert_array_equal(got.time_s, held.imu.time_s)
    for f in FIELDS[1:]:
        np.testing.assert_allclose(getattr(got, f), getattr(held.imu, f), rtol=1e-13,
                                   atol=1e-13 * np.abs(getattr(held.imu, f)).max())


@pytest.mark.parametrize("options", [None, StartOptions(window_s=80.0, heading="track")],
                         ids=["default", "options"])
def test_the_start_holds_the_opening_and_cuts_as_the_held_start(long_drive, options):
    held = load_rtklib(long_drive, mounting=None)
    rec = load_rtklib(long_drive, mounting=None, streamed=True)
    until = coarse_align.reads_until_s(rec.imu.span_s, rec.gnss, options)
    assert until < rec.imu.span_s[1] - 5.0  # the drive moves: not all of it is held
    a, b = (start_from(r.imu, r.gnss, False, options=options) for r in (held, rec))
    assert isinstance(b.imu, ImuCut) and b.imu.span_s == a.imu.span_s
    assert b.imu.n_samples == a.imu.n_samples
    assert a.init.time_s == b.init.time_s
    for f in ("lla", "vel_n", "q_bn"):
        np.testing.assert_array_equal(getattr(a.init, f), getattr(b.init, f))
    _same(_joined(list(b.imu.chunks(500)), {}), a.imu)


def test_the_protocol_on_the_file_is_the_held_runs(drive):
    held = load_rtklib(drive, mounting=None)
    rec = load_rtklib(drive, mounting=None, streamed=True)
    kw = dict(chunk_samples=613, output_rate_hz=1.0)
    a, b = validate(held, "fakf", **kw), validate(rec, "fakf", **kw)
    for feed, run in a.runs.items():
        got = b.runs[feed]
        assert got.metrics.keys() == run.metrics.keys()
        for k, v in run.metrics.items():
            assert got.metrics[k] == v or (np.isnan(v) and np.isnan(got.metrics[k])), k
        assert got.drifts == run.drifts
        np.testing.assert_array_equal(got.errors.pos_m, run.errors.pos_m)
        np.testing.assert_array_equal(got.result.lla, run.result.lla)
    # without a chunk length the run path takes its default chunk: the same metrics still
    c = validate(rec, "ekf")
    d = validate(held, "ekf")
    assert c.runs["gnss"].metrics["rms_pos_h_m"] == pytest.approx(
        d.runs["gnss"].metrics["rms_pos_h_m"], rel=1e-12)


def test_a_file_changed_after_loading_is_refused(drive, tmp_path):
    import shutil

    d = tmp_path / "rec"
    shutil.copytree(drive, d)
    rec = load_rtklib(d, mounting=None, streamed=True)
    path = d / "imu_1.csv"
    with open(path, "ab") as f:
        f.write(b"1.0,0,0,0,0,0,999999999\n")
    with pytest.raises(InputFileError, match="changed since the recording was loaded") as e:
        next(rec.imu.pieces())
    assert str(path) in str(e.value)
    os.utime(path, ns=(0, 0))  # the same bytes at another time is a change too
    with pytest.raises(InputFileError, match="changed since"):
        rec.imu.window(0.0, 1.0)


def test_increments_made_chunk_by_chunk_need_a_chunk_length(drive):
    rec = load_rtklib(drive, mounting=None, streamed=True)
    cut = ImuCut(rec.imu, 0, np.zeros(3), rec.imu.span_s[0])
    init = InitialState(cut.span_s[0], np.array([0.5, 0.2, 10.0]), np.zeros(3),
                        np.array([1.0, 0.0, 0.0, 0.0]))
    with pytest.raises(FuzzynavError, match="chunk_samples"):
        run_filter(cut, {}, init)


def _traced(fn):
    fn()  # imports, caches
    tracemalloc.start()
    out = fn()
    cur, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return out, cur, peak


def test_a_streamed_load_holds_no_imu_rows(tmp_path):
    """The memory a streamed load keeps grows with the recording only by its 4-Hz GNSS
    streams (fixes and reference, ~20 B an IMU line at 100 Hz), not by its IMU (the held
    load keeps 56 B of increments a line and more); its peak by the timing's arrays, within
    SCAN_BYTES_PER_LINE a line: the slopes between a drive and a drive three times longer."""
    sizes = {}
    for name, extra in (("short", 100.0), ("long", 400.0)):
        d = tmp_path / name
        d.mkdir()
        write_drive(d, segments=list(DRIVE_SEGMENTS) + [Segment("cruise", extra)])
        n = sum(1 for _ in open(d / "imu_1.csv", "rb"))
        for streamed in (False, True):
            # blocks of 4096 lines: the block's text is the same in both drives
            _, cur, peak = _traced(lambda: load_rtklib(d, mounting=None, streamed=streamed,
                                                       chunk_rows=4096))
            sizes[name, streamed] = (n, cur, peak)
    for streamed, held_max in ((False, 120.0), (True, 30.0)):
        (n0, c0, p0), (n1, c1, p1) = sizes["short", streamed], sizes["long", streamed]
        held = (c1 - c0) / (n1 - n0)
        assert held < held_max, (streamed, held)
        if streamed:
            assert held < 0.5 * (sizes["long", False][1] - sizes["short", False][1]) / (n1 - n0)
            assert (p1 - p0) / (n1 - n0) < SCAN_BYTES_PER_LINE, (p1 - p0) / (n1 - n0)
        else:
            assert held > 56.0  # the check can tell: the held load does keep its rows


def test_a_recording_too_long_to_hold_is_refused_with_how_to_stream_it(drive, monkeypatch):
    from fuzzynav.realdata.loaders.chunked import count_lines
    from fuzzynav.realdata.loaders.imu_csv import BLOCK_BYTES_PER_LINE, HELD_BYTES_PER_LINE
    from fuzzynav.sim import budget

    n = count_lines(drive / "imu_1.csv")
    streamed = n * SCAN_BYTES_PER_LINE + n * BLOCK_BYTES_PER_LINE
    held = n * HELD_BYTES_PER_LINE + n * BLOCK_BYTES_PER_LINE
    assert streamed < held
    monkeypatch.setenv(budget.ENV_VAR, str(0.5 * (streamed + held) / 2**30))
    with pytest.raises(InputFileError, match="load it streamed") as exc:
        load_rtklib(drive, mounting=None, chunk_rows=None)
    assert budget.human_bytes(held) in str(exc.value)
    rec = load_rtklib(drive, mounting=None, chunk_rows=None, streamed=True)
    assert rec.imu.n_samples > 6000


def test_a_study_told_of_a_recording_too_long_to_hold_is_told_what_a_study_can_do(
        drive, tmp_path, monkeypatch):
    """A study holds its recordings (every trial runs them again): its refusal says so,
    not how the command line streams one."""
    import shutil

    from fuzzynav.realdata.loaders.chunked import count_lines
    from fuzzynav.realdata.loaders.imu_csv import BLOCK_BYTES_PER_LINE, HELD_BYTES_PER_LINE
    from fuzzynav.realdata.studyruns import STUDY_HINT, recording_run
    from fuzzynav.sim import budget

    d = tmp_path / "drive"  # not a directory a study of another test loaded (kept loaded)
    shutil.copytree(drive, d)
    n = count_lines(d / "imu_1.csv")
    monkeypatch.setenv(budget.ENV_VAR, str(0.5 * n * HELD_BYTES_PER_LINE / 2**30))
    with pytest.raises(InputFileError) as exc:
        recording_run(f"rtklib:{d}", 0)
    msg = str(exc.value)
    assert msg.startswith(str(d / "imu_1.csv")) and msg.endswith(STUDY_HINT), msg
    assert "--output-rate" not in msg and "streamed=True" not in msg
    assert budget.human_bytes(n * (HELD_BYTES_PER_LINE + BLOCK_BYTES_PER_LINE)) in msg


def test_the_command_line_reads_an_rtklib_imu_from_its_file_when_streamed(drive, monkeypatch):
    """``run --data rtklib:...`` loads streamed with ``--output-rate`` or ``--chunk`` (and
    only then): the JSON of the streamed run equals the held run's, seen in
    tests/realdata/test_streamed_recordings.py."""
    import fuzzynav.realdata.loaders.rtklib as rtk
    from tests.realdata.test_cli_errors import _run

    seen = []
    real = rtk.load_rtklib
    monkeypatch.setattr(rtk, "load_rtklib",
                        lambda *a, **kw: seen.append(kw.get("streamed")) or real(*a, **kw))
    for extra, want in (((), False), (("--output-rate", "1"), True), (("--chunk", "9"), True)):
        code, out, err = _run("run", "--data", f"rtklib:{drive}", "--filter", "ekf", "--json",
                              *extra)
        assert code == 0, err
        assert seen[-1] is want, extra


def _chunk_files(directory):
    files = sorted(directory.glob("chunk-*.npz"))
    assert [f.name for f in files] == [f"chunk-{i:06d}.npz" for i in range(len(files))]
    return [dict(np.load(f)) for f in files]


def test_a_run_on_the_file_gets_its_epochs_chunk_by_chunk_and_writes_them(drive, tmp_path):
    """Read from its file, a run is given the fixes' and constraints' epochs a chunk at a
    time (runpath's EpochsByChunk): its event logs are not held, and the chunk files of
    ``output_dir`` hold, chunk after chunk, the held run's every kept row and every event
    to the bit (each epoch in exactly one chunk, in order)."""
    held = load_rtklib(drive, mounting=None)
    rec = load_rtklib(drive, mounting=None, streamed=True)
    from fuzzynav.realdata.protocol import ProtocolSettings

    nhc = ProtocolSettings(nhc_sigma_mps=0.1)  # a second stream: constraints at 10 Hz
    whole = validate(held, "fakf", nhc, chunk_samples=613)
    got = validate(rec, "fakf", nhc, chunk_samples=613, output_dir=tmp_path / "out")

    def n_chunks(t):  # 613 increments of 10 ms each from the start
        return -(-int(round((t[-1] - t[0]) * rec.imu.rate_hz)) // 613)
    for feed, run in whole.runs.items():
        assert got.runs[feed].result.events == {}  # written, not held
        m = got.runs[feed].metrics
        assert m.keys() == run.metrics.keys()
        assert all(m[k] == v or (np.isnan(v) and np.isnan(m[k])) for k, v in run.metrics.items())
        parts = _chunk_files(tmp_path / "out" / feed)
        assert len(parts) == n_chunks(run.result.time_s)
        for f in ("time_s", "lla", "vel_n", "q_bn", "sigma"):
            np.testing.assert_array_equal(np.concatenate([p[f] for p in parts]),
                                          getattr(run.result, f), err_msg=f)
        assert set(run.result.events) == {"gnss", "nhc"}
        for nm, ev in run.result.events.items():
            for f in ("time_s", "residual", "S_diag", "nis", "flag", "diag"):
                np.testing.assert_array_equal(
                    np.concatenate([p[f"events.{nm}.{f}"] for p in parts]), getattr(ev, f),
                    err_msg=f"{feed} {nm}.{f}")
            # a chunk's epochs are its own: none after its last kept output
            for p in parts[:-1]:
                assert p[f"events.{nm}.time_s"].max(initial=-np.inf) <= p["time_s"][-1] + 0.1


def test_the_command_line_writes_a_recordings_chunks_per_filter_seed_and_feed(drive,
                                                                              tmp_path):
    from fuzzynav.filters.chunk_files import read_chunks
    from tests.realdata.test_cli_errors import _run

    out = tmp_path / "out"
    code, _, err = _run("run", "--data", f"rtklib:{drive}", "--filter", "ekf", "--mc", "2",
                        "--output-rate", "1", "--output-dir", str(out))
    assert code == 0, err
    for seed in (0, 1):
        for feed in ("gnss", "outages"):
            parts = _chunk_files(out / f"ekf-seed{seed}" / feed)
            t = np.concatenate([p["time_s"] for p in parts])
            assert len(parts) >= 1 and np.all(np.diff(t) > 0.999) and np.all(np.diff(t) < 1.001)
            np.testing.assert_array_equal(read_chunks(out / f"ekf-seed{seed}" / feed).time_s, t)
    with pytest.raises(InputFileError, match="its directories gnss, outages do"):
        read_chunks(out / "ekf-seed0")


def test_the_output_check_counts_a_chunks_epochs_when_they_come_chunk_by_chunk(drive,
                                                                               monkeypatch):
    """Read from its file, a run's event logs are a chunk's at a time: the size check
    counts that chunk's share of the epochs (not all of them, as for the held run), beside
    the same kept rows and the held streams' bytes."""
    import fuzzynav.runpath as runpath

    seen = []
    monkeypatch.setattr(runpath, "check_run_outputs", lambda *a, **kw: seen.append(a))
    kw = dict(chunk_samples=613, output_rate_hz=1.0)
    validate(load_rtklib(drive, mounting=None), "ekf", **kw)
    validate(load_rtklib(drive, mounting=None, streamed=True), "ekf", **kw)
    assert len(seen) == 4  # two feeds each; the GNSS-throughout feeds compared
    (_, h_bytes, h_rows, h_epochs), (_, s_bytes, s_rows, s_epochs) = seen[0], seen[2]
    n = load_rtklib(drive, mounting=None).imu.n_samples  # the whole recording's increments
    assert s_rows == pytest.approx(h_rows, rel=1e-12) and h_epochs > 100
    # the run starts after the rest: a chunk's share of fewer than n increments
    assert 614 / n * h_epochs < s_epochs < 614 / (0.5 * n) * h_epochs
    assert s_bytes < h_bytes  # one chunk of increments held, not all
