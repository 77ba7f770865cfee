"""Recording specs of studies: parsing, the data directory, time windows, cutting streams."""
import numpy as np
import pytest

from fuzzynav.errors import DataMissingError, FuzzynavError
from fuzzynav.realdata.datasets import data_dirs
from fuzzynav.realdata.dataspec import (DATA_DIR_ENV, Window, expand, is_recording_name,
                                        overlaps, parse_recording_spec, parse_window, resolve,
                                        until, within)
from fuzzynav.sim.imu import ImuData
from fuzzynav.sim.sensors import SensorData


def test_spec_parts_and_round_trip():
    s = parse_recording_spec("rtklib:rtklib-drive@0-50%")
    assert (s.kind, s.directory, s.session) == ("rtklib", "rtklib-drive", None)
    assert s.window == Window(0.0, 50.0, True)
    a = parse_recording_spec("akit:sub/akit:1-4@10-200")
    assert (a.directory, a.session, a.window) == ("sub/akit", "1-4", Window(10.0, 200.0))
    assert str(a) == "akit:sub/akit:1-4@10-200"
    assert parse_recording_spec(str(a)) == a


@pytest.mark.parametrize("text", ["akitt", "nope:dir", "akit::3", "akit:dir:", "akit:d@50-10",
                                  "akit:d@0-120%", "akit:d@half", 3])
def test_bad_specs_are_refused(text):
    with pytest.raises(FuzzynavError):
        parse_recording_spec(text)


def test_recording_names_tell_scenarios_apart():
    assert is_recording_name("akit:akit:3")
    assert not is_recording_name("paper004")
    assert not is_recording_name("scenarios/x.toml")


def test_akit_sessions_expand_one_run_each():
    runs = expand(parse_recording_spec("akit:akit:1-3,6@0-50%"))
    assert [str(r) for r in runs] == ["akit:akit:1@0-50%", "akit:akit:2@0-50%",
                                      "akit:akit:3@0-50%", "akit:akit:6@0-50%"]


def test_window_bounds_in_seconds_and_percent():
    assert parse_window("50-100%").bounds(10.0, 210.0) == pytest.approx((110.0, 210.0))
    # seconds count from the first IMU sample and stop at the last one
    assert parse_window("20-500").bounds(10.0, 210.0) == pytest.approx((30.0, 210.0))


def test_overlap_is_per_session_and_window():
    p = parse_recording_spec
    assert not overlaps(p("rtklib:d@0-50%"), p("rtklib:d@50-100%"))   # touching halves
    assert overlaps(p("rtklib:d@0-60%"), p("rtklib:d@50-100%"))
    assert overlaps(p("rtklib:d"), p("rtklib:d@50-100%"))            # the whole vs a part
    assert not overlaps(p("akit:a:1"), p("akit:a:2"))


def test_overlap_compares_what_is_read_not_the_spelling(monkeypatch, tmp_path):
    """``akit:akit/:9``, ``akit:./akit:9`` and an absolute path were held out from
    ``akit:akit:9`` (the "held-out" score equalled the training one)."""
    p = parse_recording_spec
    monkeypatch.setenv(DATA_DIR_ENV, str(tmp_path))
    (tmp_path / "akit").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "akit")
    train = p("akit:akit:9")
    for test in ("akit:akit/:9", "akit:./akit:9", f"akit:{tmp_path / 'akit'}:9",
                 "akit:link:9", "akit:akit:8-10", "akit:akit:09", "akit:akit:9@0-50%"):
        assert overlaps(p(test), train), test
    for test in ("akit:akit:8", "akit:other:9", "rtklib:akit"):
        assert not overlaps(p(test), train), test


def test_a_study_refuses_a_respelled_training_recording_as_held_out(monkeypatch, tmp_path):
    from fuzzynav.sim.tomltable import Table
    from fuzzynav.tuning.recording_config import check_recordings_held_out

    monkeypatch.setenv(DATA_DIR_ENV, str(tmp_path))
    (tmp_path / "akit").mkdir()
    with pytest.raises(FuzzynavError, match=r"recording akit:\./akit/:9 is also"):
        check_recordings_held_out(Table({}, "test"), (("akit:akit:9", 0),),
                                  (("akit:./akit/:9", 0),))


def test_data_dir_from_environment_and_missing_directory(monkeypatch, tmp_path):
    monkeypatch.setenv(DATA_DIR_ENV, str(tmp_path))
    assert data_dirs()[0] == tmp_path
    (tmp_path / "akit").mkdir()
    assert resolve(parse_recording_spec("akit:akit:2")) == tmp_path / "akit"
    with pytest.raises(DataMissingError, match=DATA_DIR_ENV):
        resolve(parse_recording_spec("akit:elsewhere:2"))


def test_until_cuts_samples_increments_and_meta():
    t = np.arange(0.0, 10.0, 1.0)
    imu = ImuData(time_s=t, dtheta_b=np.ones((9, 3)), dv_b=np.zeros((9, 3)))
    cut = until(imu, 4.5)
    assert cut.time_s.tolist() == [0.0, 1.0, 2.0, 3.0, 4.0]
    assert cut.dtheta_b.shape == (4, 3)       # increments between the kept samples
    s = SensorData("gnss", t, np.zeros((10, 6)), np.ones((10, 6)),
                   {"q": np.arange(10), "lever_arm_b": np.zeros(3)})
    kept = within(s, 2.0, 5.0)
    assert kept.time_s.tolist() == [2.0, 3.0, 4.0, 5.0]
    assert kept.meta["q"].tolist() == [2, 3, 4, 5]
    assert kept.meta["lever_arm_b"].shape == (3,)   # a constant, not a per-epoch array


def test_car_drive_halves_use_and_score_their_own_time(rtklib_drive, monkeypatch):
    """On the real drive (skipped when absent): the first half is cut at the middle, the
    second runs through the whole drive; both complete with finite position scores."""
    from fuzzynav.experiment import run_on_log
    from fuzzynav.realdata.studyruns import recording_run

    monkeypatch.setenv(DATA_DIR_ENV, str(rtklib_drive.parent))
    name = rtklib_drive.name
    first = recording_run(f"rtklib:{name}@0-50%", 1)
    second = recording_run(f"rtklib:{name}@50-100%", 1)
    from fuzzynav.realdata.sources import SOURCES

    imu_t = SOURCES["rtklib"].load(rtklib_drive).imu.time_s
    mid = 0.5 * (imu_t[0] + imu_t[-1])
    t_first = first.sensors["gnss"].time_s
    t_second = second.sensors["gnss"].time_s
    assert mid - 1.0 < t_first[-1] <= mid               # fixes at 4 Hz up to the middle
    assert t_second[-1] > mid + 200.0                   # the drive is 549 s long
    # the second half is scored from the middle to the end
    assert second.duration_s == pytest.approx(imu_t[-1] - mid, abs=1e-6)
    for run in (first, second):
        m = run_on_log(run, "ekf").metrics
        assert m["completed"] == 1.0 and np.isfinite(m["rms_pos_h_m"])
        assert "rms_att_deg" not in m


def test_start_options_ride_with_the_spec_to_the_loader(monkeypatch, tmp_path):
    import dataclasses

    from fuzzynav.realdata import studyruns
    from fuzzynav.realdata.sources import SOURCES

    s = parse_recording_spec("rtklib:walk@0-50%?min_speed=0.5&heading=track")
    assert s.window == Window(0.0, 50.0, True) and s.options == "min_speed=0.5&heading=track"
    assert parse_recording_spec(str(s)) == s
    with pytest.raises(FuzzynavError, match="min_sped"):
        parse_recording_spec("rtklib:walk?min_sped=0.5")

    seen = {}

    class Stop(Exception):
        pass

    def fake_load(directory, session=None, **kw):
        seen.update(kw)
        raise Stop
    monkeypatch.setitem(SOURCES, "rtklib", dataclasses.replace(SOURCES["rtklib"], load=fake_load))
    studyruns._load.cache_clear()
    with pytest.raises(Stop):
        studyruns.recording_run(f"rtklib:{tmp_path}?min_speed=0.5")
    studyruns._load.cache_clear()
    assert seen["options"].min_speed_mps == pytest.approx(0.5)
