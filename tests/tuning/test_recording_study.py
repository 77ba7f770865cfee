"""Studies trained on recordings and judged on other recordings (or other time windows).

The recordings are synthetic A-KIT files (``tests/realdata/akit_files.py``) in a data directory
given by ``$FUZZYNAV_DATA``, so these run without the real data.
"""
from __future__ import annotations

import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.realdata.dataspec import DATA_DIR_ENV
from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.evaluate import run_table
from fuzzynav.tuning.objective import Evaluator, score_metrics
from tests.floats import same_metrics
from tests.realdata.akit_files import auv_trajectory, write_akit
from tests.tuning.studies import RULES, study_doc, write_study


def _pieces(monkeypatch, cut: bool) -> list:
    """The ``chunk_samples`` of every streamed study run, recorded; with ``cut`` the held
    runs are cut into chunks whatever their outputs (else these short ones run in one
    piece: :meth:`~fuzzynav.tuning.study_streaming.StudyStreaming.one_piece`)."""
    from fuzzynav.tuning import study_streaming

    seen, real = [], study_streaming.run

    def spy(source, spec, options=None, setup=None, **kw):
        seen.append(kw["chunk_samples"])
        return real(source, spec, options, setup, **kw)

    monkeypatch.setattr(study_streaming, "run", spy)
    if cut:
        monkeypatch.setattr(study_streaming.StudyStreaming, "one_piece", lambda *a: False)
    return seen


DVL_CTRL = {"name": "dvl", "template": str(RULES / "paper004_ror_dvl.json"),
            "partitions": {"ror": [3], "t": [3]}, "window": [3, 10],
            "output_low": [0.5, 0.95], "output_range": [1.05, 2.0]}
NO_ATT = {"weights": {"pos": 1.0, "vel": 1.0, "att": 0.0}, "baseline": "ekf"}


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory):
    """A data directory holding two synthetic A-KIT trajectories (``auv/``)."""
    root = tmp_path_factory.mktemp("data")
    for n in (1, 2):
        write_akit(root / "auv", auv_trajectory(90.0 + 30.0 * n), n=n, lag=1.0)
    return root


@pytest.fixture
def with_data(monkeypatch, data_dir):
    monkeypatch.setenv(DATA_DIR_ENV, str(data_dir))
    return data_dir


def _doc(train, test):
    doc = study_doc(name="rec", controllers=[DVL_CTRL], objective=NO_ATT)
    doc["train"] = {"recordings": train}       # recordings only: no scenarios
    doc["test"] = {"recordings": test, "compare": ["ekf"]}
    return doc


def test_recordings_expand_to_runs_beside_scenarios(tmp_path, with_data):
    doc = _doc(["auv:1"], ["auv:2"])
    doc["train"]["recordings"] = ["akit:auv:1-2@0-50%"]
    doc["train"]["recording_seeds"] = [0, 3]
    doc["test"]["recordings"] = ["akit:auv:1-2@50-100%"]
    doc["test"].update(scenarios=["paper004"], seeds=[100])
    cfg = load_study_config(write_study(tmp_path, doc))
    assert cfg.train == (("akit:auv:1@0-50%", 0), ("akit:auv:1@0-50%", 3),
                         ("akit:auv:2@0-50%", 0), ("akit:auv:2@0-50%", 3))
    assert cfg.test == (("paper004", 100), ("akit:auv:1@50-100%", 0),
                        ("akit:auv:2@50-100%", 0))


@pytest.mark.parametrize("train, test, where, what", [
    (["akit:auv"], ["akit:auv:2"], None, None),        # no session: all eight, 2 among them
    (["akit:auv:1@0-60%"], ["akit:auv:1@50-100%"], "test.recordings", "overlaps"),
    (["akit:auv:1"], ["akit:auv:1"], "test.recordings", "training recording"),
    (["akit:nowhere:1"], ["akit:auv:2"], "train.recordings[0]", DATA_DIR_ENV),
    (["akit:auv:1@9-2"], ["akit:auv:2"], "train.recordings[0]", "A < B"),
    (["kitti:auv:1"], ["akit:auv:2"], "train.recordings[0]", "unknown recording kind"),
    ("akit:auv:1", ["akit:auv:2"], "train.recordings", "non-empty array"),
])
def test_bad_recording_specs_name_the_key(tmp_path, with_data, train, test, where, what):
    path = write_study(tmp_path, _doc(train, test))
    if where is None:
        with pytest.raises(InputFileError, match="training recording"):
            load_study_config(path)
        return
    with pytest.raises(InputFileError, match=what) as err:
        load_study_config(path)
    assert err.value.where == where and str(path) in str(err.value)


@pytest.mark.parametrize("group", ["att", "hdg"])
def test_attitude_weight_is_refused_on_recordings(tmp_path, with_data, group):
    doc = _doc(["akit:auv:1"], ["akit:auv:2"])
    doc["objective"] = {"weights": {"pos": 1.0, "vel": 1.0, "att": 0.0, group: 1.0}}
    with pytest.raises(InputFileError, match="attitude") as err:
        load_study_config(write_study(tmp_path, doc))
    assert err.value.where == f"objective.weights.{group}"


def test_absent_data_is_one_clear_error(tmp_path, monkeypatch):
    monkeypatch.setenv(DATA_DIR_ENV, str(tmp_path / "no-such-dir"))
    with pytest.raises(InputFileError, match="recording directory .* not found"):
        load_study_config(write_study(tmp_path, _doc(["akit:auv:1"], ["akit:auv:2"])))


def test_study_trains_on_one_recording_and_judges_another(tmp_path, with_data):
    cfg = load_study_config(write_study(tmp_path, _doc(["akit:auv:1"], ["akit:auv:2"])))
    ev = Evaluator(cfg)
    base = ev.baseline("akit:auv:1", 0)
    # the synthetic DVL is exact and the start is the reference: the EKF stays within metres
    assert 0.0 < base["rms_pos_h_m"] < 5.0 and base["completed"] == 1.0
    assert "rms_att_deg" not in base      # no attitude is scored on a recording
    from fuzzynav.fuzzy import load_fis

    systems = {"dvl": load_fis(DVL_CTRL["template"])}
    table = run_table(ev, systems, cfg.test, cfg.compare)
    assert set(table["scenario"]) == {"akit:auv:2"}
    ekf = table[table["filter"] == "ekf"].iloc[0]
    # the compared ekf is the baseline itself: every ratio 1 (two runs of the same setup)
    assert ekf["pos_ratio"] == pytest.approx(1.0, rel=1e-9)
    assert np.isnan(ekf["att_ratio"]) and ekf["score"] == pytest.approx(1.0, rel=1e-9)


def test_time_window_scores_only_its_epochs(tmp_path, with_data):
    """The first half runs on no data of the second; the second half is scored only there."""
    doc = _doc(["akit:auv:2@0-50%"], ["akit:auv:2@50-100%"])
    cfg = load_study_config(write_study(tmp_path, doc))
    ev = Evaluator(cfg)
    first, second, whole = (ev.log(n, 0) for n in
                            ("akit:auv:2@0-50%", "akit:auv:2@50-100%", "akit:auv:2"))
    t_end = whole.sensors["dvl"].time_s[-1]
    assert first.sensors["dvl"].time_s[-1] <= 0.5 * t_end + 1e-9
    assert second.sensors["dvl"].time_s[-1] == pytest.approx(t_end)
    # a mean over two halves' squared errors makes the whole run's (up to the shared epoch)
    m = [ev.baseline(n, 0) for n in ("akit:auv:2@0-50%", "akit:auv:2@50-100%", "akit:auv:2")]
    halves = np.array([m[0]["rms_pos_h_m"], m[1]["rms_pos_h_m"]])
    assert min(halves) <= m[2]["rms_pos_h_m"] <= max(halves) + 1e-9


def test_missing_metric_group_with_zero_weight_does_not_count():
    s = score_metrics({"rms_pos_m": 2.0, "rms_vel_mps": 1.0},
                      {"rms_pos_m": 4.0, "rms_vel_mps": 1.0},
                      {"pos": 1.0, "vel": 1.0, "att": 0.0})
    assert s.score == pytest.approx(0.75) and np.isnan(s.ratios["att"])


@pytest.mark.slow  # a 1 050-s simulated run with the exported rules (~35 s here)
def test_export_of_a_recording_study_records_expected_on_the_simulated_run(
        tmp_path, with_data, sim_cache):
    """Trained on a recording, the exported rules' ``expected`` block is taken on the test
    set's simulated run, so the regression test of the file needs no recording."""
    import json

    from fuzzynav.tuning.export import export_rules
    from fuzzynav.tuning.study_run import run_study
    from fuzzynav.tuning.optuna_study import open_study

    doc = _doc(["akit:auv:1"], ["akit:auv:2"])
    doc["study"].update(trials=2)
    doc["test"].update(scenarios=["paper004"], seeds=[100])
    cfg = load_study_config(write_study(tmp_path, doc))
    run_study(cfg, cache_dir=sim_cache, progress=False)
    out = tmp_path / "dvl.json"
    export_rules(cfg, open_study(cfg), out, cache_dir=sim_cache)
    saved = json.loads(out.read_text())
    assert (saved["expected"]["scenario"], saved["expected"]["seed"]) == ("paper004", 100)
    assert saved["provenance"]["train"] == [["akit:auv:1", 0]]
    assert "att" not in saved["provenance"]["objective"]["ratios_to_ekf"]   # NaN left out


@pytest.mark.parametrize("window", ["@500-900", "@110-115", "@99.5-100%"])
def test_a_window_with_nothing_to_score_is_refused_naming_the_study_entry(tmp_path, with_data,
                                                                          window):
    """A window past the end crashed with ZeroDivisionError in the A-KIT score (or ran every
    trial on penalty scores and ended in "diverged"); now one line before any trial, naming
    the study file, the group and the recording."""
    from fuzzynav.errors import FuzzynavError

    path = write_study(tmp_path, _doc([f"akit:auv:1{window}"], ["akit:auv:2"]))
    ev = Evaluator(load_study_config(path))
    with pytest.raises(FuzzynavError, match=rf"{path}: train\.recordings \(akit:auv:1"
                                            rf"{window}\): .*MIN_SCORED_S"):
        ev.baseline(f"akit:auv:1{window}", 0)


@pytest.mark.parametrize("t_start", [1e6, 5.0])
def test_t_start_is_refused_in_a_study_with_recordings(tmp_path, with_data, t_start):
    """A recording is scored in its window and ignored t_start_s (1e6 was accepted)."""
    doc = _doc(["akit:auv:1"], ["akit:auv:2"])
    doc["objective"] = {**doc["objective"], "t_start_s": t_start}
    with pytest.raises(InputFileError, match=r"objective\.t_start_s: .*applies to simulated "
                                             r"runs only"):
        load_study_config(write_study(tmp_path, doc))


@pytest.mark.parametrize("cut", [False, True])
def test_a_streamed_study_on_recordings_scores_their_whole_runs_to_the_bit(tmp_path,
                                                                          with_data,
                                                                          monkeypatch, cut):
    """With ``[streaming]`` a recording is filtered in one piece or (``cut``) over chunks of
    ``chunk_s``, with its output kept at ``output_rate_hz`` and scored chunk by chunk
    against its reference: each reference epoch is interpolated from the same two rows as
    in the whole run, so the baseline's, a candidate's and the test table's metrics are the
    whole study's (to the last bit here; held to 1e-12 as two paths)."""
    from fuzzynav.fuzzy import load_fis

    pieces = _pieces(monkeypatch, cut)

    runs = ["akit:auv:1", "akit:auv:2@20-100%"]
    whole = Evaluator(load_study_config(write_study(tmp_path, _doc(runs[:1], runs[1:]),
                                                    file_name="whole.toml")))
    doc = _doc(runs[:1], runs[1:])
    doc["streaming"] = {"chunk_s": 7.3, "output_rate_hz": 1.0}
    cfg = load_study_config(write_study(tmp_path, doc, file_name="streamed.toml"))
    assert cfg.streaming is not None and cfg.streaming.chunk_s == 7.3
    streamed = Evaluator(cfg)
    systems = {"dvl": load_fis(DVL_CTRL["template"])}
    for run in [(runs[0], 0), (runs[1], 0)]:
        same_metrics(streamed.baseline(*run), whole.baseline(*run))
        got = streamed.run_systems(systems, *run)
        same_metrics(got.metrics, whole.run_systems(systems, *run).metrics)
        # the kept solution is 1 Hz (the filter records at the IMU's 100 Hz)
        step = np.diff(got.result.time_s)
        assert np.allclose(step, 1.0, atol=1e-9) and got.result.time_s.size < 200
    tables = [run_table(ev, systems, cfg.test, cfg.compare) for ev in (streamed, whole)]
    assert list(tables[0]["filter"]) == list(tables[1]["filter"])
    cols = [c for c in tables[0] if c not in ("filter", "scenario")]
    np.testing.assert_allclose(tables[0][cols].to_numpy(float), tables[1][cols].to_numpy(float),
                               rtol=1e-12, atol=0.0)
    assert pieces and set(pieces) == ({730} if cut else {None})  # 7.3 s at 100 Hz


def test_a_streamed_study_refuses_an_output_rate_the_filter_cannot_keep(tmp_path, with_data):
    """The recording's filter records at 100 Hz: 0.3 Hz does not divide it."""
    doc = _doc(["akit:auv:1"], ["akit:auv:2"])
    doc["streaming"] = {"output_rate_hz": 0.3}
    ev = Evaluator(load_study_config(write_study(tmp_path, doc)))
    from fuzzynav.errors import FuzzynavError

    with pytest.raises(FuzzynavError, match=r"\[streaming\] output_rate_hz = 0\.3 Hz "
                                            r"\(filter ekf\)"):
        ev.baseline("akit:auv:1", 0)


@pytest.fixture
def car_data(monkeypatch, tmp_path_factory):
    """A data directory holding the synthetic car drive (``car/``, 4-Hz RTK fixes)."""
    from tests.realdata.rtklib_files import write_drive

    root = tmp_path_factory.mktemp("cardata")
    (root / "car").mkdir()
    write_drive(root / "car")
    monkeypatch.setenv(DATA_DIR_ENV, str(root))
    return root


@pytest.mark.parametrize("cut", [False, True])
def test_a_streamed_gnss_study_scores_the_whole_runs_to_the_bit(tmp_path, car_data,
                                                                monkeypatch, cut):
    """A GNSS recording's study runs (the validation protocol's noisy fixes, scored against
    the RTK fixes) streamed, in one piece or cut: the baseline's and another filter's
    metrics are the whole run's (held to 1e-12 as two paths), for two seeds of the fed
    noise."""
    pieces = _pieces(monkeypatch, cut)
    runs = ["rtklib:car@0-60%", "rtklib:car@60-100%"]
    docs = [_doc(runs[:1], runs[1:]) for _ in range(2)]
    docs[1]["streaming"] = {"chunk_s": 5.3, "output_rate_hz": 2.0}
    whole, streamed = (Evaluator(load_study_config(write_study(tmp_path, doc,
                                                               file_name=f"{i}.toml")))
                       for i, doc in enumerate(docs))
    for seed in (0, 1):
        base = streamed.baseline(runs[0], seed)
        same_metrics(base, whole.baseline(runs[0], seed))   # the outage figures: NaN both
        assert np.isfinite(base["rms_pos_h_m"])
        got, ref = (ev.run(runs[0], seed, "sage-husa") for ev in (streamed, whole))
        same_metrics(got.metrics, ref.metrics)
        assert np.allclose(np.diff(got.result.time_s), 0.5, atol=1e-9)
    assert pieces and (None not in pieces if cut else set(pieces) == {None})
