"""[baselines.ranges]: a study file's own search ranges for the tuned filters -- read and
checked, searched, written into the parameter file and used to judge values at an end."""
import json

import optuna
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.filters.params_file import read_params_file
from fuzzynav.tuning.baseline_config import SPACES, bound_hits, load_baseline_config
from fuzzynav.tuning.kinds.baseline_studies import BaselinePlan
from fuzzynav.tuning.optuna_study import make_storage
from fuzzynav.tuning.study_run import run_plan
from tests.tuning.studies import TINY

STUDY = f"""
name = "ranged"
[study]
sampler = "random"
seed = 0
trials = 6
pruner = "none"
[train]
scenarios = ["{TINY}"]
seeds = [0]
[test]
scenarios = ["{TINY}"]
seeds = [100]
compare = ["ekf"]
[baselines]
tune = {{tune}}
out = "tuned.json"
{{ranges}}
"""


def _config(tmp_path, tune='["huber-tuned", "apso"]', ranges=""):
    p = tmp_path / "ranged.toml"
    p.write_text(STUDY.format(tune=tune, ranges=ranges))
    return load_baseline_config(p)


def test_ranges_are_read_with_the_default_scale_and_the_rest_left_as_they_are(tmp_path,
                                                                             sim_cache):
    bcfg = _config(tmp_path, ranges="[baselines.ranges]\n"
                                    "apso = { q_att = [1e-4, 100], r_all = [0.001, 10] }\n"
                                    "huber-tuned = { gamma = [1, 3] }")
    assert bcfg.ranges == {"apso": {"q_att": (1e-4, 100.0), "r_all": (0.001, 10.0)},
                           "huber-tuned": {"gamma": (1.0, 3.0)}}
    plan = BaselinePlan(bcfg, sim_cache)
    assert plan.space("apso") == {"q_att": (1e-4, 100.0, True),
                                  "q_vel": SPACES["apso"]["q_vel"],
                                  "r_all": (0.001, 10.0, True)}
    assert plan.space("huber-tuned") == {"gamma": (1.0, 3.0, True)}
    assert _config(tmp_path).ranges == {}  # no table: the defaults


@pytest.mark.parametrize("ranges, key, message", [
    ("vb-tuned = { rho = [0.9, 0.99] }", "baselines.ranges.vb-tuned",
     "not a searched filter"),
    ("apso = { q_acc = [0.1, 1] }", "baselines.ranges.apso.q_acc",
     "not a searched parameter of apso"),
    ("apso = { q_att = [10, 1] }", "baselines.ranges.apso.q_att", "low must be below high"),
    ("apso = { q_att = [1, 2, 3] }", "baselines.ranges.apso.q_att", r"must be \[low, high\]"),
    ("apso = { q_att = [1e-9, 1] }", "baselines.ranges.apso.q_att",
     "low end must be a number in"),
    ("huber-tuned = { gamma = [0.5, 1000] }", "baselines.ranges.huber-tuned.gamma",
     "high end must be a number in"),
    ("apso = 3", "baselines.ranges.apso", "must be a table"),
])
def test_a_bad_range_is_refused_naming_the_file_and_the_key(tmp_path, ranges, key, message):
    with pytest.raises(InputFileError, match=message) as err:
        _config(tmp_path, ranges=f"[baselines.ranges]\n{ranges}")
    assert "ranged.toml" in str(err.value) and key in str(err.value)


def test_an_integer_range_must_be_whole(tmp_path):
    with pytest.raises(InputFileError, match="low end must be an integer in"):
        _config(tmp_path, tune='["vb-tuned"]',
                ranges="[baselines.ranges]\nvb-tuned = { iterations = [1.5, 4] }")


def test_a_channel_the_training_runs_lack_is_refused_when_the_space_is_made(tmp_path,
                                                                          sim_cache):
    bcfg = _config(tmp_path, tune='["ekf-tuned"]',
                   ranges="[baselines.ranges]\nekf-tuned = { r_field = [0.5, 2] }")
    with pytest.raises(InputFileError, match="baselines.ranges.ekf-tuned.r_field.*no such "
                                             "parameter"):
        BaselinePlan(bcfg, sim_cache).space("ekf-tuned")  # the tiny runs: no magnetometer


def test_the_study_searches_the_ranges_and_the_file_records_them(tmp_path, sim_cache):
    bcfg = _config(tmp_path, ranges="[baselines.ranges]\n"
                                    "apso = { q_att = [1e-4, 1e-3] }\n"
                                    "huber-tuned = { gamma = [2, 2.5] }")
    run_plan(BaselinePlan(bcfg, sim_cache), progress=False)
    def trials(part):  # each filter's study, in its journal beside the study file
        storage = make_storage(f"journal:{tmp_path / f'ranged.{part}.journal'}",
                               heartbeat=False)
        return optuna.load_study(study_name=f"ranged.{part}", storage=storage).trials

    drawn = trials("apso")
    assert len(drawn) == 6 and all(1e-4 <= t.params["q_att"] <= 1e-3 for t in drawn)
    drawn = trials("huber-tuned")
    assert all(2.0 <= t.params["gamma"] <= 2.5 for t in drawn)
    doc = json.loads(bcfg.out.read_text())
    assert doc["space"]["apso"]["q_att"] == [1e-4, 1e-3]
    assert doc["space"]["apso"]["r_all"] == list(SPACES["apso"]["r_all"][:2])
    assert doc["space"]["huber-tuned"] == {"gamma": [2.0, 2.5]}
    assert read_params_file(bcfg.out)["apso"] == doc["filters"]["apso"]  # the filters read it


def test_an_end_is_judged_against_the_range_searched():
    params = {"q_att": 0.01, "q_vel": 1.0, "r_all": 0.1}
    assert bound_hits("apso", params) == {"q_att": "lower", "r_all": "lower"}  # the defaults
    wide = {"space": {"apso": {"q_att": [1e-4, 100.0], "q_vel": [0.01, 100.0],
                               "r_all": [1e-3, 100.0]}}}
    assert bound_hits("apso", params, doc=wide) == {}
    assert bound_hits("apso", {"q_att": 1e-4}, doc=wide) == {"q_att": "lower"}
