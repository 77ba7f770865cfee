"""``objective = "robust"``: accuracy (mean training score) against robustness (worst training
scenario), and the Pareto front that ``study report`` prints and draws."""
from __future__ import annotations

import matplotlib.image
import numpy as np
import optuna
import pytest

from fuzzynav.tuning.export import choose_trial
from fuzzynav.tuning.study_report import write_report
from fuzzynav.tuning.optuna_study import best_trials
from tests.tuning.studies import BASE, TINY, finished_study

optuna.logging.set_verbosity(optuna.logging.ERROR)


@pytest.fixture(scope="module")
def robust(tmp_path_factory, sim_cache):
    d = tmp_path_factory.mktemp("robust")
    # a second training scenario: the same flight with a longer, larger GPS noise burst
    heavy = d / "tiny_heavy.toml"
    heavy.write_text(TINY.read_text().replace('name = "tiny"', 'name = "tiny_heavy"')
                     .replace("end_s = 40.0, scale = 5.0", "end_s = 50.0, scale = 10.0"))
    train = {"scenarios": [str(TINY), str(heavy)], "seeds": [0, 1]}
    return finished_study(d, sim_cache, trials=6, train=train,
                          study={**BASE["study"], "objective": "robust"}) + (d,)


def _done(study):
    return [t for t in study.trials if t.values is not None]


def test_values_are_the_mean_and_the_worst_scenario(robust):
    cfg, study, _ = robust
    assert cfg.multi_objective and cfg.directions == ["minimize", "minimize"]
    done = _done(study)
    assert len(done) == 6
    for t in done:
        per = t.user_attrs["scenario_scores"]
        assert set(per) == {"tiny", "tiny_heavy"}
        # two seeds per scenario: the mean of all four runs is the mean of the two means
        assert t.values[0] == pytest.approx(np.mean(list(per.values())), rel=1e-12)
        assert t.values[1] == pytest.approx(max(per.values()), rel=1e-12)
        assert t.values[1] >= t.values[0]


def test_the_front_is_exactly_the_undominated_trials(robust):
    cfg, study, _ = robust
    vals = {t.number: np.array(t.values) for t in _done(study)}
    front = {t.number for t in best_trials(study, cfg)}
    assert front

    def dominated(v):
        return any(np.all(w <= v) and np.any(w < v) for w in vals.values())

    for n, v in vals.items():
        assert (n in front) == (not dominated(v))


def test_report_prints_and_draws_the_front(robust):
    cfg, study, d = robust
    md = write_report(cfg, study, d / "rep", evaluate=False)
    text = md.read_text()
    assert "## Pareto front" in text and "robustness (worst scenario)" in text
    front = sorted(best_trials(study, cfg), key=lambda t: tuple(t.values))
    rows = [line for line in text.splitlines() if line.startswith("| ") and
            line.split("|")[1].strip().isdigit()]
    assert [int(r.split("|")[1]) for r in rows] == [t.number for t in front]
    # row 0 has the best accuracy, and it is the one `study export --pareto 0` takes
    assert front[0].values[0] == min(t.values[0] for t in _done(study))
    assert choose_trial(study, cfg, pareto_index=0).number == front[0].number
    img = matplotlib.image.imread(md.parent / "pareto.png")
    assert img.ndim == 3 and img.shape[0] > 100
