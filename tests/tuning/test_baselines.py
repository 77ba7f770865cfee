"""Baseline studies: config, a tiny tuning run, the parameter file the named filters read."""
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from fuzzynav.errors import FuzzynavError, InputFileError
from fuzzynav.filters.baselines import read_params
from fuzzynav.filters.params_file import PARAMS_FORMAT
from fuzzynav.tuning.baseline_config import load_baseline_config, space_of
from fuzzynav.tuning.kinds import kind_of
from fuzzynav.tuning.kinds.baseline_studies import BaselinePlan
from fuzzynav.tuning.study_run import run_plan

STUDY = Path(__file__).resolve().parents[2] / "studies" / "paper000_baselines.toml"

TINY = """
name = "tiny_baselines"
[study]
sampler = "random"
seed = 0
trials = 2
pruner = "none"
[train]
scenarios = ["paper000-steps"]
seeds = [0]
[test]
scenarios = ["paper000"]
seeds = [100]
compare = ["ekf"]
[baselines]
tune = {tune}
out = "tuned.json"
"""


def run_baselines(bcfg, cache_dir):
    """Tune every filter of ``bcfg`` with the one study driver; the parameter file."""
    run_plan(BaselinePlan(bcfg, cache_dir), progress=False)
    return bcfg.out


def test_the_shipped_baseline_study_parses():
    assert kind_of(STUDY).name == "baselines"
    b = load_baseline_config(STUDY)
    assert "ekf-tuned" in b.tune and "als" in b.tune
    assert b.out.name == "paper000_baselines.json"
    assert b.study.trials == 300 and not b.study.controllers


def test_baseline_config_refuses_unknown_filters(tmp_path):
    p = tmp_path / "b.toml"
    p.write_text(TINY.format(tune='["ekf-tuned", "kalman-magic"]'))
    with pytest.raises(InputFileError, match=r"b\.toml.*baselines\.tune"):
        load_baseline_config(p)


def test_ekf_tuned_space_covers_every_channel_and_q_block():
    space = space_of("ekf-tuned", ("pos", "vel", "heading"))
    assert {"r_pos", "r_vel", "r_heading", "q_att", "q_vel"} <= set(space)


def test_a_tiny_baseline_study_writes_parameters_the_filters_read(tmp_path):
    p = tmp_path / "b.toml"
    p.write_text(TINY.format(tune='["huber-tuned", "vb-tuned"]'))
    bcfg = load_baseline_config(p)
    out = run_baselines(bcfg, cache_dir=tmp_path / "cache")
    doc = json.loads(out.read_text())
    assert doc["format"] == PARAMS_FORMAT and doc["trials"] == {"huber-tuned": 2, "vb-tuned": 2}
    assert 0.5 <= doc["filters"]["huber-tuned"]["gamma"] <= 10.0
    assert doc["filters"]["vb-tuned"]["iterations"] in range(1, 6)
    assert read_params(out)["filters"] == doc["filters"]
    assert not list(tmp_path.glob(".tuned*"))  # no temporary file left


def test_als_in_a_baseline_study_gets_its_training_score(tmp_path):
    """ALS is estimated, not searched: its training score is judged like a trial's (mean
    ratio to the EKF over the training runs: positive and finite, near 1 for a constant-R
    EKF on one run)."""
    pytest.importorskip("cvxpy")
    p = tmp_path / "b.toml"
    p.write_text(TINY.format(tune='["als"]'))
    doc = json.loads(run_baselines(load_baseline_config(p),
                                   cache_dir=tmp_path / "cache").read_text())
    assert doc["trials"] == {"als": 0} and set(doc["filters"]["als"]) >= {"r_pos", "r_vel"}
    assert 0.3 < doc["train_score"]["als"] < 3.0


@pytest.mark.slow
def test_als_recovers_the_unreported_gnss_noise_of_a_training_run(tmp_path):
    # paper000-steps: GNSS noise x3 for 150 s and x10 for 80 s of a 755-s run, unreported;
    # the run's mean true/claimed variance ratio is the independent truth ALS should find
    from fuzzynav.sim.sensor_log import simulate
    from fuzzynav.sim.scenario import load_scenario
    from fuzzynav.tuning.als_fit import run_scales

    log = simulate(load_scenario("paper000-steps"), 0, tmp_path)
    gps = log.sensors["gps"]
    truth = np.mean(np.asarray(gps.meta["true_sigma"]) ** 2 / np.asarray(gps.sigma) ** 2)
    got = run_scales(log)
    assert got["pos"] == pytest.approx(truth, rel=0.15)
    assert got["vel"] == pytest.approx(truth, rel=0.15)


def _cli(capsys, *argv):
    from fuzzynav.cli import main

    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_study_run_and_report_accept_a_baseline_study(tmp_path, capsys):
    p = tmp_path / "b.toml"
    p.write_text(TINY.format(tune='["huber-tuned"]'))
    cache = tmp_path / "cache"
    code, out, _ = _cli(capsys, "study", "run", p, "--trials", 1, "--no-summary",
                        "--cache", cache)
    assert code == 0 and (tmp_path / "tuned.json").is_file()
    code, out, _ = _cli(capsys, "study", "report", p, "--cache", cache,
                        "--out", tmp_path / "rep")
    text = (tmp_path / "rep" / "report.md").read_text()
    assert code == 0 and "huber-tuned" in text and "held-out" in text
    # the named filter reads the file written: NAME@FILE on the command line
    code, out, err = _cli(capsys, "run", "paper000", "--filter",
                          f"huber-tuned@{tmp_path / 'tuned.json'}", "--cache", cache)
    assert code == 0, err


def test_a_bad_baseline_study_is_one_line(tmp_path, capsys):
    p = tmp_path / "b.toml"
    p.write_text(TINY.format(tune='["nope"]'))
    code, _, err = _cli(capsys, "study", "run", p)
    assert code == 2 and err.count("\n") == 1 and "baselines.tune" in err


def test_als_on_runs_without_gnss_is_refused_not_written_empty(tmp_path):
    """ALS estimates the GNSS R only: on DVL-only runs it used to write ``"als": {}`` (the
    plain EKF) with a training score of 1.0."""
    pytest.importorskip("cvxpy")
    p = tmp_path / "b.toml"
    p.write_text(TINY.format(tune='["als"]').replace('"paper000-steps"', '"paper004"'))
    with pytest.raises(FuzzynavError, match=r"tune = 'als'.*no GNSS receiver"):
        run_baselines(load_baseline_config(p), cache_dir=tmp_path / "cache")
    assert not (tmp_path / "tuned.json").exists()
