"""The science page's multi-design sections on synthetic scores (answers worked by hand)."""
import numpy as np
import optuna
import pandas as pd
import pytest

from fuzzynav.pages import science_sections as sec
from fuzzynav.pages.scores import best_classical, is_classical


def _scores(values: dict) -> pd.DataFrame:
    """filter -> scenario -> per-seed scores."""
    rows = [{"scenario": sc, "seed": k, "filter": f, "score": v}
            for f, by in values.items() for sc, xs in by.items() for k, v in enumerate(xs)]
    return pd.DataFrame(rows)


SCORES = _scores({
    "fuzzy-a": {"s1": [0.70, 0.72, 0.71, 0.69], "s2": [1.30, 1.32, 1.31, 1.29]},
    "sage-husa-tuned": {"s1": [0.80, 0.83, 0.80, 0.79], "s2": [0.90, 0.91, 0.93, 0.90]},
    "vb-tuned": {"s1": [0.85, 0.86, 0.84, 0.85], "s2": [0.95, 0.96, 0.94, 0.95]},
    "ekf-true": {"s1": [0.10] * 4, "s2": [0.10] * 4},
    "fuzzy-b": {"s1": [0.01] * 4, "s2": [0.01] * 4},
})


def test_the_best_classical_filter_is_never_fuzzy_nor_the_oracle():
    assert not is_classical(pd.Series(["fuzzy-b", "fakf", "ekf-true"])).any()
    assert best_classical(SCORES, "s1") == "sage-husa-tuned"


def test_a_design_is_tallied_against_each_sets_best_classical_filter():
    # s1: fuzzy-a is 0.10 below sage-husa-tuned on every seed (win); s2: 0.40 above (loss)
    assert sec.design_tally(SCORES, ["s1", "s2"], "fuzzy-a") == {
        "wins against": 1, "draws with": 0, "loses to": 1}
    lines = sec.designs_lines(SCORES, ["s1", "s2"], ["fuzzy-a"])
    assert "-0.100" in lines[2] and "**win**" in lines[2] and "loss" in lines[3]


def test_the_spread_between_tunings_is_the_sample_std_of_their_means():
    t0 = _scores({"fuzzy-a": {"s1": [0.7, 0.7]}, "sage-husa-tuned": {"s1": [0.8, 0.8]}})
    t1 = _scores({"fuzzy-a": {"s1": [0.9, 0.9]}, "sage-husa-tuned": {"s1": [0.8, 0.8]}})
    lines = sec.variance_lines({0: t0, 1: t1}, ["fuzzy-a"], ["sage-husa-tuned"], ["s1"])
    row = next(line for line in lines if line.startswith("| `fuzzy-a` | 0.700"))
    assert f"{np.std([0.7, 0.9], ddof=1):.3f}" in row and "0.700 – 0.900" in row
    # per tuning: a win in tuning 0 (0.7 < 0.8 on both seeds), a loss in tuning 1
    assert "| `fuzzy-a` | 1 / 0 / 0 | 0 / 0 / 1 |" in lines


def _points(train, held, name="f"):
    return pd.DataFrame({"filter": name, "trials": [30, 100, 300, 1000], "tuning_seed": 0,
                         "train_score": train, "held_out_score": held, "runs": 56})


def test_budget_sentences_find_overfitting_and_the_best_budget():
    over = sec.budget_sentences(_points([0.9, 0.8, 0.7, 0.6], [0.9, 0.85, 0.88, 0.95]))[0]
    assert "no budget after 100 improves" in over and "100 to 300, 300 to 1000" in over
    assert "overfits" in over
    still = sec.budget_sentences(_points([0.9, 0.8, 0.7, 0.6], [0.9, 0.85, 0.8, 0.7]))[0]
    assert "no budget after" not in still and "still helped" in still


def test_budget_changes_under_the_tolerance_are_flat():
    """A supervisor that never leaves its parent: differences of 1e-5 are no overfitting."""
    flat = sec.budget_sentences(_points([0.816, 0.81599, 0.81598, 0.81597],
                                        [0.785, 0.78501, 0.785, 0.78502]))[0]
    assert "overfits" not in flat and "still helped" not in flat
    assert "no budget after 30 improves" in flat and "nothing better" in flat


def test_a_tiny_difference_with_a_narrow_ci_is_a_draw():
    from fuzzynav.metrics import mean_ci
    from fuzzynav.pages import scores as sr

    tiny = mean_ci(-1e-5 + 1e-7 * np.arange(8))  # CI excludes zero, effect negligible
    assert tiny.hi < 0 and sr.verdict(tiny) == "draws with"
    real = mean_ci(-0.02 + 0.001 * np.arange(8))
    assert sr.verdict(real) == "wins against"
    assert sr.verdict(mean_ci(0.02 + 0.001 * np.arange(8))) == "loses to"


def test_budget_lines_draw_the_figure(tmp_path):
    lines = sec.budget_lines(pd.concat([_points([0.9, 0.8, 0.7, 0.6], [0.9, 0.8, 0.8, 0.8]),
                                        _points([1, 1, 1, 1], [1, 1, 1, 1], "g")]),
                             tmp_path / "b.png", "b.png")
    assert (tmp_path / "b.png").stat().st_size > 1000
    assert lines[0] == "![budget curves](figures/b.png)" and len(lines) == 2 + 2 + 8


def test_best_of_first_n_is_what_a_budget_of_n_would_have_returned():
    from fuzzynav.pages.science_tuning import best_of_first

    study = optuna.create_study()
    for v in (5.0, 3.0, 4.0, 1.0, 2.0):
        study.add_trial(optuna.trial.create_trial(params={}, distributions={}, value=v))
    firsts = best_of_first(study, 3).get_trials()
    assert [t.number for t in firsts] == [0, 1, 2]
    assert min(t.value for t in firsts) == 3.0
    assert best_of_first(study, None) is study


def test_pooled_differences_pair_each_tuning_with_its_own_classical_filter():
    # the fuzzy design is 0.05 below the classical filter in every tuning and seed, while
    # both move together between tunings (+0.2): the pairs cancel the tuning effect
    t0 = _scores({"fuzzy-a": {"s1": [0.70, 0.72, 0.71]},
                  "vb-tuned": {"s1": [0.75, 0.77, 0.76]}})
    t1 = _scores({"fuzzy-a": {"s1": [0.90, 0.92, 0.91]},
                  "vb-tuned": {"s1": [0.95, 0.97, 0.96]}})
    best, est = sec.pooled_differences({0: t0, 1: t1}, "s1", "fuzzy-a")
    assert best == "vb-tuned" and est.n == 6
    assert est.mean == pytest.approx(-0.05) and est.hi - est.lo < 1e-9
    lines, wins = sec.pooled_lines({0: t0, 1: t1}, ["s1"], ["fuzzy-a"])
    assert wins == {"fuzzy-a": 1} and "**win**" in lines[-1]


def test_a_difference_that_flips_between_tunings_is_no_pooled_win():
    # tuning 0: fuzzy 0.1 better on every seed; tuning 1: 0.1 worse -- per tuning one win
    # and one loss, pooled over tunings a draw
    t0 = _scores({"fuzzy-a": {"s1": [0.70, 0.71, 0.72]}, "vb-tuned": {"s1": [0.8, 0.81, 0.82]}})
    t1 = _scores({"fuzzy-a": {"s1": [0.90, 0.91, 0.92]}, "vb-tuned": {"s1": [0.8, 0.81, 0.82]}})
    _, est = sec.pooled_differences({0: t0, 1: t1}, "s1", "fuzzy-a")
    assert est.lo < 0 < est.hi
    assert sec.pooled_lines({0: t0, 1: t1}, ["s1"], ["fuzzy-a"])[1] == {"fuzzy-a": 0}


def test_tuned_values_at_the_end_of_their_search_range_are_flagged():
    from fuzzynav.tuning.baseline_config import SPACES, bound_hits

    lo_b, hi_b, _ = SPACES["sage-husa-tuned"]["b"]
    lo_c, hi_c, _ = SPACES["sage-husa-tuned"]["cap"]   # searched on the log scale
    hits = bound_hits("sage-husa-tuned", {"b": lo_b, "floor": 0.5, "cap": hi_c * 0.995,
                                          "extra": 1.0})
    assert hits == {"b": "lower", "cap": "upper"}
    # 1 % of the log range above the lower end of cap is not 1 % of its linear range
    assert bound_hits("sage-husa-tuned", {"cap": lo_c * (hi_c / lo_c) ** 0.02}) == {}
