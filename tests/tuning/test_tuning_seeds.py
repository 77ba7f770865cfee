"""Tuning variance (:mod:`fuzzynav.tuning.tuning_seeds`): one study file tuned with several
sampler seeds -- the seed is what changes, the same seed reproduces the same trials, and the
spread between tunings is computed as a direct computation gives it."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from fuzzynav.cli import main
from fuzzynav.tuning.kinds import load_plan
from fuzzynav.tuning.study_run import run_plan
from fuzzynav.tuning.tuning_seeds import seeded_plan, study_seeds, tuning_spread
from tests.tuning.studies import write_study
from tests.tuning.test_baselines import TINY as TINY_BASELINES

# 4 trials of TPE (its seeded start-up sampling) on the tiny scenario
TPE = {"sampler": "tpe", "seed": 5, "trials": 4}


def _params(directory, cache, seed, doc_changes=None):
    directory.mkdir()
    path = write_study(directory, study=TPE, **(doc_changes or {}))
    plan = seeded_plan(load_plan(path, cache), seed)
    studies, _ = run_plan(plan, 4, progress=False)
    return plan, [[t.params for t in s.trials] for s in studies.values()]


def test_the_same_sampler_seed_reproduces_the_trials_another_changes_them(tmp_path,
                                                                         sim_cache):
    plan, a = _params(tmp_path / "a", sim_cache, 5)
    _, b = _params(tmp_path / "b", sim_cache, 5)
    _, c = _params(tmp_path / "c", sim_cache, 6)
    assert plan.name == "tiny-seed5" and plan.cfg.seed == 5
    assert (tmp_path / "a" / "tiny-seed5.journal").is_file()
    assert len(a[0]) == 4 and a == b
    assert a != c


def test_a_baseline_study_is_seeded_into_its_own_parameter_file(tmp_path, sim_cache):
    p = tmp_path / "b.toml"
    p.write_text(TINY_BASELINES.format(tune='["huber-tuned"]'))
    plans = [seeded_plan(load_plan(p, sim_cache), s) for s in (3, 3, 4)]
    found = []
    for plan in plans:
        studies, _ = run_plan(plan, 2, progress=False)
        found.append([t.params for t in studies["huber-tuned"].trials])
    assert plans[0].bcfg.out == tmp_path / "tuned-seed3.json"
    assert plans[0].config("huber-tuned").name == "tiny_baselines-seed3.huber-tuned"
    assert (tmp_path / "tuned-seed3.json").is_file() and (tmp_path / "tuned-seed4.json").is_file()
    assert found[0] == found[1] and found[0] != found[2]


def test_study_seeds_count_up_from_the_files_seed(tmp_path):
    plan = load_plan(write_study(tmp_path, study={"seed": 7}))
    assert study_seeds(plan, 3) == [7, 8, 9]


def test_the_spread_between_tunings_is_that_of_their_held_out_means():
    rng = np.random.default_rng(0)
    tables = {s: pd.DataFrame({"scenario": "x", "seed": range(5), "filter": "tuned",
                               "score": 0.9 + 0.1 * s + 0.02 * rng.standard_normal(5)})
              for s in (0, 1, 2)}
    per, across = tuning_spread(tables, ["tuned"])
    means = np.array([tables[s]["score"].mean() for s in (0, 1, 2)])
    assert per["score"].to_numpy() == pytest.approx(means)
    assert list(per["runs"]) == [5, 5, 5]
    # each tuning's paired change against the baseline (score 1 on every run)
    assert per["change_pct"].to_numpy() == pytest.approx(100 * (1 - means))
    assert (per["change_lo"] <= per["change_pct"]).all()
    assert (per["change_pct"] <= per["change_hi"]).all()
    r = across.iloc[0]
    assert (r["tunings"], r["mean"], r["min"], r["max"]) == \
        (3, pytest.approx(means.mean()), pytest.approx(means.min()), pytest.approx(means.max()))
    assert r["std"] == pytest.approx(np.std(means, ddof=1))


def test_cli_runs_and_reports_each_tuning(capsys, tmp_path, sim_cache):
    cfg = write_study(tmp_path, study={"trials": 2})
    code = main(["study", "run", str(cfg), "--study-seeds", "2", "--no-summary",
                 "--cache", str(sim_cache)])
    out = capsys.readouterr().out
    assert code == 0 and "study tiny-seed0: 2 trials" in out and "study tiny-seed1" in out
    code = main(["study", "report", str(cfg), "--study-seeds", "2", "--out",
                 str(tmp_path / "rep"), "--cache", str(sim_cache)])
    assert code == 0
    text = (tmp_path / "rep" / "tunings.md").read_text()
    assert "| 0 | tuned | 1 |" in text and "| 1 | tuned | 1 |" in text
    assert (tmp_path / "rep" / "seed1" / "report.md").is_file()
    assert "## Per scenario or recording" in (tmp_path / "rep" / "seed0" / "report.md").read_text()
    assert main(["study", "run", str(cfg), "--study-seeds", "0"]) == 2


def test_a_started_worker_runs_the_tuning_it_is_given(tmp_path, sim_cache):
    """Workers started as new interpreters (not forked) load the file and get the seed."""
    from fuzzynav.tuning.optuna_study import open_study
    from fuzzynav.tuning.study_run import worker_command
    from fuzzynav.tuning.worker import main as worker_main

    path = write_study(tmp_path, study=TPE)
    plan = seeded_plan(load_plan(path, sim_cache), 5)
    cmd = worker_command(plan.cfg, 2, None, 0, sim_cache, study_seed=5)
    assert cmd[-2:] == ["--study-seed", "5"]
    open_study(plan.cfg, None, create=True)
    assert worker_main(cmd[3:]) == 0
    assert len(open_study(plan.cfg, None).trials) == 2
    assert not (tmp_path / "tiny.journal").exists()  # the file's unseeded study untouched
