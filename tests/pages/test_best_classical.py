"""The papers' "best equally tuned classical filter" table on hand-made frames (answers
worked by hand: per-seed differences, Student-t intervals from scipy)."""
import json

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from fuzzynav.errors import InputFileError
from fuzzynav.pages import scores as sr
from fuzzynav.pages.best_classical import further_runs, labelled, paper_lines, provenance_score
from fuzzynav.pages.science_sections import designs_lines


def _scores(values: dict, scenario="s1") -> pd.DataFrame:
    return pd.DataFrame([{"scenario": scenario, "seed": k, "filter": f, "score": v}
                         for f, xs in values.items() for k, v in enumerate(xs)])


FUZZY = [0.70, 0.72, 0.71, 0.69]
CHOSEN = [0.80, 0.83, 0.80, 0.79]     # picked on the training runs
BETTER = [0.60, 0.61, 0.62, 0.60]     # better on these runs: a choice on the test data
SCORES = _scores({"fz": FUZZY, "a-tuned": CHOSEN, "b-tuned": BETTER, "ekf-true": [0.1] * 4,
                  "sage-husa": [0.2] * 4})


def _t_interval(d):
    d = np.asarray(d, float)
    half = stats.t.ppf(0.975, d.size - 1) * d.std(ddof=1) / np.sqrt(d.size)
    return d.mean(), d.mean() - half, d.mean() + half


def test_a_best_chosen_beforehand_is_used_even_where_another_does_better():
    m, lo, hi = _t_interval(np.subtract(FUZZY, CHOSEN))
    assert hi < 0  # the hand numbers are a clear win
    lines = designs_lines(SCORES, ["s1"], ["fz"], best="a-tuned", labels={"fz": "fuzzy"})
    assert lines[0] == "| scenario | best classical | fuzzy − best |"
    assert lines[2] == f"| `s1` | a-tuned | {m:+.3f} [{lo:+.3f}, {hi:+.3f}] **win** |"
    assert "| fuzzy | 1 | 0 | 0 |" in lines


def test_chosen_on_the_runs_the_best_comes_from_the_pool_only():
    # ekf-true and the untuned sage-husa score lower but are not equally tuned
    m, lo, hi = _t_interval(np.subtract(FUZZY, BETTER))
    lines = designs_lines(SCORES, ["s1"], ["fz"], pool=["a-tuned", "b-tuned"])
    assert lines[2] == f"| `s1` | b-tuned | {m:+.3f} [{lo:+.3f}, {hi:+.3f}] loss |"
    with pytest.raises(ValueError, match="no classical filter"):
        sr.best_classical(SCORES, "s1", pool=["nowhere"])


def test_a_difference_within_the_noise_is_a_draw():
    s = _scores({"fz": [0.80, 0.90, 0.70, 0.85], "a-tuned": [0.85, 0.80, 0.75, 0.80]})
    assert designs_lines(s, ["s1"], ["fz"], best="a-tuned")[2].endswith(" draw |")


def test_weighted_scores_are_the_weighted_mean_of_ratios():
    df = pd.DataFrame([
        {"scenario": "s", "seed": 0, "filter": "ekf", "h": 2.0, "v": 4.0},
        {"scenario": "s", "seed": 0, "filter": "f", "h": 1.0, "v": 4.0}])
    out = sr.scores_to(df, "ekf", ("h", "v"), (2.0, 1.0)).set_index("filter")["score"]
    assert out["f"] == pytest.approx((2 * 0.5 + 1 * 1.0) / 3) and out["ekf"] == 1.0
    assert sr.scores_to(df, "ekf", ("h", "v")).set_index("filter")["score"]["f"] == 0.75
    with pytest.raises(ValueError, match="weights"):
        sr.scores_to(df, "ekf", ("h", "v"), (1.0,))


def test_the_best_on_training_reads_the_baseline_studys_scores(tmp_path):
    path = tmp_path / "b.json"
    path.write_text(json.dumps({"train_score": {"a-tuned": 0.9, "b-tuned": 0.8, "c": 0.1}}))
    best, train = sr.best_on_training(path, ["a-tuned@x.json", "b-tuned@x.json"])
    assert best == "b-tuned@x.json" and train == {"a-tuned@x.json": 0.9, "b-tuned@x.json": 0.8}
    with pytest.raises(InputFileError, match=r"\$\.train_score.*d-tuned"):
        sr.best_on_training(path, ["a-tuned", "d-tuned"])


def test_paper_lines_compare_each_design_with_the_training_choice(tmp_path):
    params = tmp_path / "b.json"
    params.write_text(json.dumps({"train_score": {"a-tuned": 0.85, "b-tuned": 0.95}}))
    rule = tmp_path / "r.json"
    rule.write_text(json.dumps({"provenance": {"objective": {"value": 0.8}}}))
    # raw metrics: the EKF at 1 m, so each filter's score is its own value
    rows = [{"scenario": "s1", "seed": k, "filter": f, "rms_m": v}
            for f, xs in {"ekf": [1.0] * 4, "fz": FUZZY, "a-tuned": CHOSEN,
                          "b-tuned": BETTER}.items() for k, v in enumerate(xs)]
    lines = paper_lines({"s1": pd.DataFrame(rows)}, designs=["fz"],
                        pool=["a-tuned", "b-tuned"], params=params, metrics=("rms_m",),
                        labels={"fz": "fuzzy"}, design_train={"fz": provenance_score(rule)})
    text = "\n".join(lines)
    assert lines[0].startswith("Training scores") and "fuzzy 0.800" in lines[0]
    assert "a-tuned (0.850)" in text
    m, lo, hi = _t_interval(np.subtract(FUZZY, CHOSEN))
    assert f"| `s1` | a-tuned | {m:+.3f} [{lo:+.3f}, {hi:+.3f}] **win** |" in lines
    m, lo, hi = _t_interval(np.subtract(FUZZY, BETTER))
    assert f"| `s1` | b-tuned | {m:+.3f} [{lo:+.3f}, {hi:+.3f}] loss |" in lines
    with pytest.raises(InputFileError, match="provenance"):
        provenance_score(params)


def test_labelled_names_the_specs_and_keeps_other_filters():
    df = pd.DataFrame({"filter": ["ekf", "fakf@r.json", "vb"], "seed": [0, 0, 0]})
    out = labelled(df, {"EKF": "ekf", "FAKF, tuned": "fakf@r.json"})
    assert list(out["filter"]) == ["EKF", "FAKF, tuned", "vb"]
    assert list(df["filter"]) == ["ekf", "fakf@r.json", "vb"]  # a copy


def test_further_runs_runs_each_scenario_on_its_seeds_under_the_labels(monkeypatch):
    import fuzzynav.experiment as ex

    calls = []

    def fake(scenario, filters, seeds, cache_dir=None):
        calls.append((scenario, list(filters), list(seeds), cache_dir))
        return pd.DataFrame([{"filter": f, "seed": s} for f in filters for s in seeds])

    monkeypatch.setattr(ex, "monte_carlo", fake)
    run = further_runs({"b": [3, 4], "a": range(7, 8)}, "CACHE")
    out = run({"tuned k": "ekf-tuned@p_t1.json"})
    assert list(out) == ["b", "a"]  # the page's order
    assert calls == [("b", ["ekf-tuned@p_t1.json"], [3, 4], "CACHE"),
                     ("a", ["ekf-tuned@p_t1.json"], [7], "CACHE")]
    assert list(out["b"]["filter"]) == ["tuned k", "tuned k"]
