"""Paper 004's APSO as a baseline study on the PSO sampler (``fuzzynav study run``):
config, swarm, result file."""
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import optuna
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.experiment import run_on_log
from fuzzynav.realdata.dataspec import DATA_DIR_ENV
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.tuning.baseline_config import SPACES, load_baseline_config, sub_config
from fuzzynav.tuning.pso import PsoSampler, history
from tests.tuning.studies import TINY

ROOT = Path(__file__).resolve().parents[2]
CONFIGS = (ROOT / "studies" / "paper004_apso.toml", ROOT / "studies" / "paper004_apso_rev.toml")


@pytest.fixture
def fake_data(monkeypatch, tmp_path):
    """A data directory with an (empty) akit/: loading a config only checks it exists."""
    (tmp_path / "akit").mkdir()
    monkeypatch.setenv(DATA_DIR_ENV, str(tmp_path))


@pytest.mark.parametrize("path", CONFIGS, ids=[p.name for p in CONFIGS])
def test_shipped_configs_are_pso_studies_held_out_on_other_trajectories(path, fake_data):
    bcfg = load_baseline_config(path)
    cfg = bcfg.study
    assert bcfg.tune == ("apso",) and cfg.sampler == "pso"
    assert tuple(cfg.pso.inertia) == (0.9, 0.4)
    assert cfg.trials == cfg.pso.particles * cfg.pso.iterations
    train = {n for n, _ in cfg.train}
    test = {n for n, _ in cfg.test}
    assert len(train) == len(test) == 4 and not train & test
    assert {n.split(":")[0] for n in train | test} == {"akit"}


def _bowl_study(iterations=25):
    """A PSO study over the apso space whose objective is a bowl with a known minimum."""
    from fuzzynav.tuning.study_config import PsoConfig, study_config_from_dict

    doc = {"study": {"sampler": "pso", "seed": 3, "trials": 8 * iterations},
           "objective": {"weights": {"pos": 1.0, "vel": 0.0, "att": 0.0}},
           "train": {"scenarios": [str(TINY)], "seeds": [0]},
           "test": {"scenarios": [str(TINY)], "seeds": [1], "compare": ["ekf"]}}
    cfg = study_config_from_dict(doc, need_controllers=False)
    cfg = replace(cfg, pso=PsoConfig(particles=8, iterations=iterations, inertia=(0.9, 0.4)))
    return sub_config(cfg, "apso", SPACES["apso"])


def test_swarm_over_the_apso_space_finds_a_known_minimum_on_the_schedule():
    cfg = _bowl_study()
    target = {"q_att": 10.0, "q_vel": 0.1, "r_all": 3.0}
    space = SPACES["apso"]

    def bowl(trial):  # squared log10 distance to the target multipliers
        p = {k: trial.suggest_float(k, lo, hi, log=True) for k, (lo, hi, _) in space.items()}
        return sum((np.log10(p[k]) - np.log10(v)) ** 2 for k, v in target.items())

    study = optuna.create_study(sampler=PsoSampler(cfg, cfg.seed))
    study.optimize(bowl, n_trials=cfg.trials)
    hist = history(study, cfg)
    w = [h["inertia"] for h in hist]
    np.testing.assert_allclose([w[0], w[-1]], [0.9, 0.4])
    assert len(w) == cfg.pso.iterations and np.all(np.diff(w) < 0)
    assert np.all(np.diff([h["best"] for h in hist]) <= 0)      # best so far never worsens
    assert study.best_value < 0.01
    for k, v in target.items():
        assert abs(np.log10(study.best_params[k] / v)) < 0.1
        lo, hi, _ = space[k]
        assert all(lo <= t.params[k] <= hi for t in study.trials)   # inside the bounds


def test_apso_reads_its_parameter_file_like_the_options(tmp_path, sim_cache):
    mult = {"q_att": 4.0, "q_vel": 0.5, "r_all": 2.5}
    path = tmp_path / "apso.json"
    path.write_text(json.dumps({"format": "fuzzynav-baselines", "filters": {"apso": mult}}))
    log = simulate(load_scenario(str(TINY)), 0, sim_cache)
    from_file = run_on_log(log, "apso", {"rules": [str(path)]}).metrics
    from_options = run_on_log(log, "apso", mult).metrics
    plain = run_on_log(log, "ekf").metrics
    assert from_file["rms_pos_m"] == pytest.approx(from_options["rms_pos_m"], rel=1e-12)
    # the multipliers do act: not the plain EKF
    assert abs(from_file["rms_pos_m"] - plain["rms_pos_m"]) > 1e-6 * plain["rms_pos_m"]


def test_a_parameter_file_without_apso_names_the_field(tmp_path):
    from fuzzynav.filters.baselines import params_of
    from fuzzynav.filters.named import FilterContext

    def read_apso(p):
        return params_of(FilterContext(options={"params": str(p)}), "apso")

    path = tmp_path / "other.json"
    path.write_text(json.dumps({"format": "fuzzynav-baselines",
                                "filters": {"ekf-tuned": {"q_att": 1.0}}}))
    with pytest.raises(InputFileError, match=r"\$\.filters\.apso: missing \(this file tunes: "
                                             r"ekf-tuned\)"):
        read_apso(path)
    path.write_text(json.dumps({"filters": {"apso": {"r_all": 1.0}}}))  # not a study's file
    with pytest.raises(InputFileError, match=r"\$\.format: must be 'fuzzynav-baselines'"):
        read_apso(path)
