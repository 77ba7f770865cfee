"""The objective: ratios to the EKF on the same runs, failures, weights, pruning."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import optuna
import pytest

from fuzzynav.experiment import run_on_log
from fuzzynav.fuzzy import load_fis
from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.errors import FuzzynavError
from fuzzynav.tuning.objective import FAILED_RATIO, Evaluator, Objective, score_metrics
from fuzzynav.tuning.space import ControllerSpace, build_all
from tests.tuning.studies import ATT, ATT_CONTROLLER, BASE, GPS, TINY, write_study

optuna.logging.set_verbosity(optuna.logging.ERROR)
BOTH = [dict(BASE["controllers"][0], rule_weights=True), dict(ATT_CONTROLLER, rule_weights=True)]


@pytest.fixture
def cfg(tmp_path):
    return load_study_config(write_study(tmp_path, controllers=BOTH,
                                         train={"seeds": [0, 1, 2, 3]}))


def random_params(cfg, seed=0) -> dict:
    """The parameters of one random trial of the config's space."""
    spaces = [ControllerSpace.from_config(c) for c in cfg.controllers]
    trial = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=seed)).ask()
    build_all(spaces, trial)
    return dict(trial.params)


def test_a_candidate_equal_to_the_ekf_scores_exactly_one(cfg, sim_cache):
    """Every rule weight 0: no rule fires, alpha = its default 1 -> the EKF's own update."""
    params = {k: (0.0 if ".weight." in k else v) for k, v in random_params(cfg).items()}
    trial = optuna.trial.FixedTrial(params)
    value = Objective(cfg, sim_cache)(trial)
    assert abs(value - 1.0) < 1e-12
    assert trial.user_attrs["n_runs"] == len(cfg.train) == 4
    for g, r in trial.user_attrs["ratios"].items():
        assert abs(r - 1.0) < 1e-12, g


def test_ratios_are_the_named_filters_metrics_divided(cfg, sim_cache):
    """The paper's own rule files as the candidate: the ratios equal ``fakf`` / ``ekf`` from
    the experiment runner (an independent path: rule files bound by name, not in memory)."""
    ev = Evaluator(cfg, sim_cache)
    systems = {"gps": load_fis(GPS), "att": load_fis(ATT)}
    for scenario, seed in cfg.train[:2]:
        r = ev.score_systems(systems, scenario, seed).ratios
        log = ev.log(scenario, seed)
        fakf = run_on_log(log, "fakf", {"rules": [str(GPS), str(ATT)]}).metrics
        ekf = run_on_log(log, "ekf").metrics
        for g, key in (("pos", "rms_pos_m"), ("vel", "rms_vel_mps"), ("att", "rms_att_deg")):
            assert r[g] == pytest.approx(fakf[key] / ekf[key], rel=1e-12)
            assert r[g] != pytest.approx(1.0, abs=1e-3)  # the paper's rules do act here


def test_a_run_that_loses_its_covariance_scores_the_failed_ratio(cfg, sim_cache):
    """alpha ~ 1e10 inflates P- until the update loses positive definiteness."""
    params = random_params(cfg, seed=1)
    for k in params:
        if k.startswith("gps.") and ".weight." in k:
            params[k] = 1.0
        if k.startswith("gps.rule."):
            params[k] = int(k.split(">")[1].split(".")[0]) - 1  # the top output term
    params["gps.out_hi"] = 1e10
    # a study file may not ask for such a range (controller_config.MAX_OUTPUT_FACTOR): set it in code
    gps = dataclasses.replace(cfg.controllers[0], output_range=(1e9, 1e10))
    cfg_wide = dataclasses.replace(cfg, controllers=(gps, cfg.controllers[1]))
    obj = Objective(cfg_wide, sim_cache)
    systems = build_all(obj.spaces, optuna.trial.FixedTrial(params))
    out = obj.evaluator.run_systems(systems, str(TINY), 0)
    assert not out.result.ok and "covariance" in out.result.status
    scored = obj.evaluator.judge(out.metrics, str(TINY), 0)
    assert scored.ratios == {"pos": FAILED_RATIO, "vel": FAILED_RATIO, "att": FAILED_RATIO}
    assert scored.score == FAILED_RATIO


def test_ratio_guards(cfg, sim_cache):
    ev = Evaluator(cfg, sim_cache)
    scenario, seed = cfg.train[0]
    base = ev.baseline(scenario, seed)
    ok = {k: 2.0 * base[k] for k in ("rms_pos_m", "rms_vel_mps", "rms_att_deg")}
    def ratios(metrics):
        return ev.judge(metrics, scenario, seed).ratios

    assert ratios(dict(ok, completed=1.0)) == \
        {"pos": pytest.approx(2.0), "vel": pytest.approx(2.0), "att": pytest.approx(2.0)}
    assert set(ratios(dict(ok, completed=0.0)).values()) == {FAILED_RATIO}
    nan = dict(ok, rms_vel_mps=math.nan)
    assert ratios(nan)["vel"] == FAILED_RATIO
    assert ratios(nan)["pos"] == pytest.approx(2.0)


def test_the_score_is_the_weighted_mean_of_the_ratios(tmp_path, sim_cache):
    cfg = load_study_config(write_study(tmp_path, objective={
        "weights": {"pos": 2.0, "vel": 0.0, "att": 1.0}}))
    scenario, seed = cfg.train[0]
    base = Evaluator(cfg, sim_cache).baseline(scenario, seed)
    metrics = {"rms_pos_m": 0.5 * base["rms_pos_m"], "rms_vel_mps": 100 * base["rms_vel_mps"],
               "rms_att_deg": 2.0 * base["rms_att_deg"]}
    assert score_metrics(metrics, base, cfg.weights).score == pytest.approx((2 * 0.5 + 2.0) / 3)


def test_heading_and_horizontal_groups_enter_the_score_when_weighted(tmp_path, sim_cache):
    """Paper 003's study weights heading and the horizontal channels: a candidate whose
    3-D figures equal the baseline's but whose heading is 3 times worse must score worse."""
    cfg = load_study_config(write_study(tmp_path, objective={
        "weights": {"pos": 0.0, "vel": 0.0, "att": 0.0, "hdg": 2.0, "vel_h": 1.0,
                    "pos_h": 1.0}}))
    assert cfg.weights == {"pos": 0.0, "vel": 0.0, "att": 0.0, "hdg": 2.0, "vel_h": 1.0,
                           "pos_h": 1.0}
    scenario, seed = cfg.train[0]
    base = Evaluator(cfg, sim_cache).baseline(scenario, seed)
    metrics = dict(base, rms_heading_deg=3.0 * base["rms_heading_deg"],
                   rms_pos_h_m=0.5 * base["rms_pos_h_m"])
    scored = score_metrics(metrics, base, cfg.weights)
    assert scored.ratios["hdg"] == pytest.approx(3.0) and scored.ratios["att"] == 1.0
    assert scored.score == pytest.approx((2 * 3.0 + 1.0 + 0.5) / 4)


def test_a_weighted_group_the_run_does_not_measure_is_refused():
    # r_use on a run without a simulated magnetometer (or attitude on a recording) would
    # make every score NaN; weighted 0 it is simply not scored
    base = {"rms_pos_m": 2.0, "rms_vel_mps": 1.0, "rms_att_deg": 0.5}
    weights = {"pos": 1.0, "vel": 1.0, "att": 1.0, "r_use": 0.1}
    with pytest.raises(FuzzynavError, match="'r_use' has weight 0.1.*no r_use_dev_calm"):
        score_metrics(dict(base), base, weights)
    assert score_metrics(dict(base), base, dict(weights, r_use=0.0)).score == 1.0


class PruneAfter(optuna.pruners.BasePruner):
    """Prunes every trial once it has reported ``k`` runs."""

    def __init__(self, k):
        self.k = k

    def prune(self, study, trial):
        return len(trial.intermediate_values) >= self.k


def test_a_pruned_trial_returns_the_mean_of_its_runs_and_records_how_many(cfg, sim_cache):
    study = optuna.create_study(pruner=PruneAfter(2),
                                sampler=optuna.samplers.RandomSampler(seed=4))
    objective = Objective(cfg, sim_cache)
    study.optimize(objective, n_trials=3)
    ev = Evaluator(cfg, sim_cache)
    spaces = objective.spaces
    seen_orders = set()
    for t in study.trials:
        assert t.state == optuna.trial.TrialState.COMPLETE  # returned, not raised
        assert t.user_attrs["n_runs"] == 2 == len(t.intermediate_values)
        systems = build_all(spaces, optuna.trial.FixedTrial(t.params))
        scores = []
        for step, value in t.intermediate_values.items():
            scenario, seed = cfg.train[step]  # the step id names the training run
            scores.append(ev.score_systems(systems, scenario, seed).score)
            assert value == pytest.approx(scores[-1], rel=1e-12)
        assert t.value == pytest.approx(np.mean(scores), rel=1e-12)
        seen_orders.add(tuple(t.intermediate_values))
    assert len(seen_orders) > 1  # the run order is shuffled per trial


def test_an_unpruned_trial_reports_every_run_once(cfg, sim_cache):
    study = optuna.create_study(sampler=optuna.samplers.RandomSampler(seed=5))
    study.optimize(Objective(cfg, sim_cache), n_trials=1)
    t = study.trials[0]
    assert sorted(t.intermediate_values) == list(range(len(cfg.train)))
    assert t.value == pytest.approx(np.mean(list(t.intermediate_values.values())), rel=1e-12)
    assert t.user_attrs["n_runs"] == len(cfg.train)


def test_multi_objective_returns_the_three_mean_ratios(tmp_path, sim_cache):
    cfg = load_study_config(write_study(tmp_path, study={"objective": "multi"}))
    study = optuna.create_study(directions=cfg.directions,
                                sampler=optuna.samplers.RandomSampler(seed=6))
    study.optimize(Objective(cfg, sim_cache), n_trials=1)
    t = study.trials[0]
    assert t.values == pytest.approx([t.user_attrs["ratios"][g] for g in ("pos", "vel", "att")])
    assert not t.intermediate_values and t.user_attrs["n_runs"] == len(cfg.train)
