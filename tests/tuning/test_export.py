"""Export: rule files that load, carry provenance and an expected block, reproduce it; the
trial chosen (best, numbered, Pareto member); nothing half-written."""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import optuna
import pytest
from optuna.trial import TrialState

from fuzzynav import __version__
from fuzzynav.errors import FuzzynavError
from fuzzynav.experiment import run_on_log
from fuzzynav.fuzzy import load_fis
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.tuning import export as export_mod
from fuzzynav.tuning.export import choose_trial, export_rules, systems_of
from fuzzynav.tuning.optuna_study import best_trials, pareto_front
from tests.test_rules_regression import check_expected
from tests.tuning.studies import ATT_CONTROLLER, BASE, finished_study

optuna.logging.set_verbosity(optuna.logging.ERROR)


@pytest.fixture(scope="module")
def done(tmp_path_factory):
    """A finished two-controller study (random sampler, 5 trials) and its cache."""
    d = tmp_path_factory.mktemp("export-study")
    cache = tmp_path_factory.mktemp("export-cache")
    cfg, study = finished_study(d, cache, trials=5,
                                controllers=[BASE["controllers"][0], ATT_CONTROLLER])
    return cfg, study, cache


def test_exported_files_load_carry_provenance_and_reproduce_expected(done, tmp_path):
    cfg, study, cache = done
    paths = export_rules(cfg, study, tmp_path / "out" / "tuned.json", cache_dir=cache)
    assert [p.name for p in paths] == ["tuned_gps.json", "tuned_att.json"]
    full = [t for t in study.trials if t.user_attrs["n_runs"] == len(cfg.train)]
    best = min(full, key=lambda t: t.value)
    rebuilt = systems_of(cfg, best)
    docs = {}
    for name, path in zip(("gps", "att"), paths):
        fis = load_fis(path)
        doc = json.loads(path.read_text())
        docs[name] = doc
        prov = doc["provenance"]
        assert prov["study"] == cfg.name and prov["trial"] == best.number
        assert prov["sampler"] == "random" and prov["controller"] == name
        assert prov["objective"]["value"] == best.value
        assert prov["objective"]["ratios_to_ekf"] == best.user_attrs["ratios"]
        assert prov["train"] == [list(r) for r in cfg.train]
        assert prov["test"] == [list(r) for r in cfg.test]
        assert prov["package_version"] == __version__ and prov["created"]
        # the rules are the trial's (rebuilt from its stored parameters)
        strip = {k: v for k, v in fis.to_dict().items() if k not in ("provenance", "expected")}
        assert strip == {k: v for k, v in rebuilt[name].to_dict().items()
                         if k not in ("provenance", "expected")}
        exp = doc["expected"]
        assert (exp["scenario"], exp["seed"], exp["filter"]) == (*cfg.test[0], "fakf")
        assert exp["with_rules"] == [p.name for p in paths if p != path]
    # re-running fakf with the files (the regression-test mechanism) reproduces expected
    metrics = check_expected(paths[0], cache)
    # and the held-out ratio in the provenance is that run over a fresh EKF run
    scenario, seed = cfg.test[0]
    ekf = run_on_log(simulate(load_scenario(scenario), seed, cache), "ekf").metrics
    held = docs["gps"]["provenance"]["held_out_ratios_to_ekf"]
    assert held["pos_ratio"] == pytest.approx(metrics["rms_pos_m"] / ekf["rms_pos_m"], rel=1e-9)
    assert held["att_ratio"] == pytest.approx(metrics["rms_att_deg"] / ekf["rms_att_deg"],
                                              rel=1e-9)


def test_a_chosen_trial_and_a_single_controller(tmp_path, done):
    cfg, study, cache = done
    one = dataclasses.replace(cfg, controllers=cfg.controllers[:1])
    [path] = export_rules(one, study, tmp_path / "one.json", trial_number=2, cache_dir=cache)
    assert path.name == "one.json"
    doc = json.loads(path.read_text())
    assert doc["provenance"]["trial"] == 2 and doc["expected"]["with_rules"] == []
    check_expected(path, cache)


@pytest.mark.parametrize("number,fragment", [(99, "no trial 99"), (-1, "no trial -1"),
                                              (5, "FAIL, not COMPLETE")])
def test_choosing_a_trial_that_cannot_be_exported(done, number, fragment, tmp_path):
    cfg, study, _ = done
    copy = optuna.create_study(storage=optuna.storages.InMemoryStorage())
    for t in study.trials:
        copy.add_trial(t)
    copy.add_trial(optuna.trial.create_trial(state=TrialState.FAIL))
    with pytest.raises(FuzzynavError, match=fragment):
        choose_trial(copy, cfg, number)


def test_nothing_is_written_when_the_expected_run_fails(done, tmp_path, monkeypatch):
    cfg, study, cache = done

    def broken(*args, **kw):
        raise FuzzynavError("fakf could not run")

    monkeypatch.setattr(export_mod, "run_on_log", broken)
    with pytest.raises(FuzzynavError, match="could not run"):
        export_rules(cfg, study, tmp_path / "tuned.json", cache_dir=cache)
    assert list(tmp_path.iterdir()) == []


def test_the_output_must_be_a_json_file(done, tmp_path):
    cfg, study, cache = done
    with pytest.raises(FuzzynavError, match="must be a .json rule file"):
        export_rules(cfg, study, tmp_path / "tuned.fis", cache_dir=cache)


def test_only_fully_run_trials_are_best(done):
    cfg, study, _ = done
    copy = optuna.create_study(storage=optuna.storages.InMemoryStorage())
    for t in study.trials:
        copy.add_trial(t)
    # a pruned-early trial with a tempting value is never "best"
    copy.add_trial(optuna.trial.create_trial(value=1e-3, user_attrs={"n_runs": 1},
                                             params={}, distributions={}))
    assert best_trials(copy, cfg)[0].value == min(t.value for t in study.trials)
    assert choose_trial(copy, cfg).value > 1e-3


def _mo_study(values, n_runs=2):
    s = optuna.create_study(directions=["minimize"] * 3)
    for v in values:
        s.add_trial(optuna.trial.create_trial(values=list(v), user_attrs={"n_runs": n_runs}))
    return s


def test_the_pareto_front_matches_optuna_and_brute_force():
    rng = np.random.default_rng(0)
    vals = np.round(rng.random((120, 3)), 1)  # rounding makes ties and duplicates
    s = _mo_study(vals)
    ours = sorted(t.number for t in pareto_front(s.trials))
    assert ours == sorted(t.number for t in s.best_trials)  # Optuna's public API
    brute = [i for i, v in enumerate(vals) if not any(
        np.all(w <= v) and np.any(w < v) for w in vals)]
    assert ours == brute
    assert pareto_front([]) == []


def test_export_picks_a_pareto_member(done, tmp_path):
    cfg, _, cache = done
    mo = dataclasses.replace(cfg, multi_objective=True)
    vals = [(1.0, 2.0, 3.0), (2.0, 1.0, 3.0), (3.0, 3.0, 3.0), (0.5, 5.0, 5.0)]
    s = _mo_study(vals, n_runs=len(cfg.train))
    s.add_trial(optuna.trial.create_trial(values=[0.1, 0.1, 0.1], user_attrs={"n_runs": 1}))
    front = best_trials(s, mo)
    assert sorted(t.number for t in front) == [0, 1, 3]  # the partial trial does not count
    assert [tuple(choose_trial(s, mo, pareto_index=k).values) for k in range(3)] == \
        sorted(vals[i] for i in (0, 1, 3))
    with pytest.raises(FuzzynavError, match=r"--pareto must be in 0\.\.2"):
        choose_trial(s, mo, pareto_index=3)


def test_pareto_on_a_single_objective_study_is_refused_not_ignored(done):
    cfg, study, _ = done
    assert not cfg.multi_objective
    with pytest.raises(FuzzynavError, match="--pareto: study .* is single-objective"):
        choose_trial(study, cfg, pareto_index=3)  # exported the best trial silently
    mo = dataclasses.replace(cfg, multi_objective=True)
    with pytest.raises(FuzzynavError, match="give one of them"):
        choose_trial(_mo_study([(1.0, 2.0, 3.0)]), mo, trial_number=0, pareto_index=0)
