"""Report: report.md, trials.csv, runs.csv and the figures, also for multi-objective studies
and for studies with no usable trial yet."""
from __future__ import annotations

import dataclasses
import re

import matplotlib.image
import optuna
import pandas as pd
import pytest
from optuna.trial import TrialState

from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.evaluate import summary
from fuzzynav.tuning.study_report import write_report
from fuzzynav.tuning.optuna_study import open_study
from tests.tuning.studies import ATT_CONTROLLER, BASE, finished_study, write_study

optuna.logging.set_verbosity(optuna.logging.ERROR)


def png_ok(path):
    img = matplotlib.image.imread(path)
    assert img.ndim == 3 and img.shape[0] > 100 and img.shape[1] > 100


def test_report_of_a_tiny_study(tmp_path, sim_cache):
    cfg, study = finished_study(tmp_path, sim_cache, trials=12,
                                controllers=[BASE["controllers"][0], ATT_CONTROLLER])
    md = write_report(cfg, study, tmp_path / "rep", cache_dir=sim_cache)
    out = md.parent
    for name in ("history.png", "importances.png", "mf_gps.png", "mf_att.png"):
        png_ok(out / name)
    assert not (out / "pareto.png").exists()
    trials = pd.read_csv(out / "trials.csv")
    assert len(trials) == 12 and set(trials["state"]) == {"COMPLETE"}
    assert list(trials["number"]) == list(range(12))
    assert trials["value"].tolist() == pytest.approx([t.value for t in study.trials])
    assert trials["pos_ratio"].tolist() == pytest.approx(
        [t.user_attrs["ratios"]["pos"] for t in study.trials])
    assert "gps.n.dom_pos" in trials and "att.window" in trials
    text = md.read_text()
    best = min(study.trials, key=lambda t: t.value)
    assert f"## Best trial: {best.number}" in text
    for fig in ("history.png", "importances.png", "mf_gps.png", "mf_att.png"):
        assert f"({fig})" in text
    # the rule table grid of the tuned gps controller: one row per dom_pos term
    n = best.params["gps.n.dom_pos"]
    assert len(re.findall(r"^\| (N|P|Z)\w* \|", text.split("### Controller `gps`")[1]
                          .split("### Controller")[0], re.M)) == n
    runs = pd.read_csv(out / "runs.csv")
    assert set(runs["filter"]) == {"tuned", "ekf", "fakf"}
    assert len(runs) == 3 * (len(cfg.train) + len(cfg.test))
    ekf = runs[runs["filter"] == "ekf"]
    assert ekf[["pos_ratio", "vel_ratio", "att_ratio"]].to_numpy() == pytest.approx(1.0)
    # the train/test table printed in the report is the summary of runs.csv
    tuned_test = summary(runs[(runs["set"] == "test")]).set_index("filter").loc["tuned"]
    assert f"{tuned_test['pos_ratio']:.3f}" in text


def test_report_of_a_multi_objective_study(tmp_path, sim_cache):
    cfg, study = finished_study(tmp_path, sim_cache, trials=4,
                                study={"objective": "multi", "sampler": "nsga2"})
    md = write_report(cfg, study, tmp_path / "rep", cache_dir=sim_cache, evaluate=False)
    png_ok(md.parent / "pareto.png")
    png_ok(md.parent / "history.png")
    assert "## Best trial:" in md.read_text()
    assert not (md.parent / "runs.csv").exists()


def test_report_with_no_complete_trial_yet(tmp_path):
    cfg = load_study_config(write_study(tmp_path))
    study = open_study(cfg, create=True)
    md = write_report(cfg, study, tmp_path / "empty", evaluate=False)
    assert "No best trial yet" in md.read_text() and "trials: none" in md.read_text()
    for state in (TrialState.FAIL, TrialState.PRUNED):
        kw = {"value": 0.5} if state == TrialState.PRUNED else {}
        study.add_trial(optuna.trial.create_trial(state=state, **kw))
    md = write_report(cfg, study, tmp_path / "rep", evaluate=False)
    text = md.read_text()
    assert "No best trial yet" in text and "FAIL 1" in text and "PRUNED 1" in text
    assert len(pd.read_csv(md.parent / "trials.csv")) == 2


def test_a_single_run_gets_no_confidence_interval(tmp_path, sim_cache):
    """One test run: the table prints the ratio alone, not '± 0.000'."""
    from fuzzynav.tuning.evaluate import format_summary, run_table
    from fuzzynav.tuning.objective import Evaluator

    cfg = load_study_config(write_study(tmp_path))
    ev = Evaluator(dataclasses.replace(cfg), sim_cache)
    test = run_table(ev, {}, cfg.test, ("ekf", "fakf"))
    text = format_summary(test.iloc[:0], test)
    assert "±" not in text and "1.000" in text
