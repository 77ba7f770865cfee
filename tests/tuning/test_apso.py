"""Paper 004's APSO driver: config errors, the inertia schedule, convergence on a known bowl."""
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from fuzzynav.errors import InputFileError
from fuzzynav.tuning.apso import ApsoConfig, multipliers, run_apso

ROOT = Path(__file__).resolve().parents[2]


def test_the_shipped_config_parses_with_the_paper_inertia():
    cfg = ApsoConfig.load(ROOT / "studies" / "paper004_apso.toml")
    assert tuple(cfg.pso.inertia) == (0.9, 0.4)
    assert set(cfg.bounds) == {"q_scale_att", "q_scale_vel", "r_scale"}
    assert not set(cfg.train) & set(cfg.test) or all(s >= 100 for _, s in cfg.test)


def test_swarm_finds_a_known_minimum_and_follows_the_schedule():
    cfg = ApsoConfig.load(ROOT / "studies" / "paper004_apso.toml")
    target = {"q_scale_att": 10.0, "q_scale_vel": 0.1, "r_scale": 3.0}

    def bowl(m):  # squared log10 distance to the target multipliers
        return sum((np.log10(m[k]) - np.log10(v)) ** 2 for k, v in target.items())

    cfg = replace(cfg, pso=SimpleNamespace(**{**vars(cfg.pso), "iterations": 30}))
    found = run_apso(cfg, bowl, progress=lambda s: None)
    w = [h["inertia"] for h in found["history"]]
    np.testing.assert_allclose([w[0], w[-1]], [0.9, 0.4])
    assert np.all(np.diff(w) < 0)
    assert found["best_fitness"] < 0.01
    for k, v in target.items():
        assert abs(np.log10(found["best"][k] / v)) < 0.1


@pytest.mark.parametrize("edit,where", [
    (("inertia = [0.9, 0.4]", "inertia = [0.3, 0.6]"), "inertia"),
    (("q_scale_att = [-2.0, 2.0]", "q_att = [-2.0, 2.0]"), "q_att"),
    (("r_scale = [-1.0, 2.0]", "r_scale = [2.0, -1.0]"), "r_scale"),
    (("seeds = [0, 1]", "seeds = [\"a\"]"), "seeds"),
])
def test_bad_configs_name_the_key(tmp_path, edit, where):
    text = (ROOT / "studies" / "paper004_apso.toml").read_text().replace(*edit)
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(InputFileError, match=where) as exc:
        ApsoConfig.load(p)
    assert "bad.toml" in str(exc.value)


def test_multipliers_are_log_uniform_in_the_bounds():
    cfg = ApsoConfig.load(ROOT / "studies" / "paper004_apso.toml")
    lo = multipliers(cfg, [0.0, 0.0, 0.0])
    hi = multipliers(cfg, [1.0, 1.0, 1.0])
    assert lo == pytest.approx({"q_scale_att": 0.01, "q_scale_vel": 0.01, "r_scale": 0.1})
    assert hi == pytest.approx({"q_scale_att": 100.0, "q_scale_vel": 100.0, "r_scale": 100.0})


def test_the_tuned_result_reproduces_its_expected_metrics(tmp_path):
    """The shipped APSO result file re-run on its ``expected`` scenario and seed (the
    mechanism of tests/test_rules_regression.py; the file is not a rule file, so it is not
    in rules/)."""
    from tests.test_rules_regression import check_expected

    check_expected(ROOT / "studies" / "paper004_apso.result.json", tmp_path)
