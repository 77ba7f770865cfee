"""Recording splits of the science and paper-004 pages on synthetic rows (answers by hand)."""
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from fuzzynav.pages import science_splits as ss
from fuzzynav.papers.paper004 import page_heldout as ph

SPLIT = ss.Split("held", "fuzzy-x", "studies/s.toml", "rules/r.json", "studies/p.json",
                 apso="studies/a.json",
                 supervisors=(("fuzzy-vb-tuned", "fuzzy-vb", "rules/sup.json"),))


def test_pairs_are_seeds_on_one_recording_and_sessions_on_several():
    assert ss.pair_ids([("rtklib:rtklib-drive@50-100%", s) for s in (100, 101)]) == [100, 101]
    assert ss.pair_ids([(f"akit:akit:{t}", 0) for t in (5, 6, 7, 8)]) == [5, 6, 7, 8]
    with pytest.raises(ValueError, match="several sessions and seeds"):
        ss.pair_ids([("akit:akit:5", 0), ("akit:akit:6", 1)])


def test_more_noise_seeds_replace_the_seeds_of_a_single_held_out_recording():
    one = SimpleNamespace(test=(("rtklib:rtklib-drive@50-100%", 100), ("paper004", 100)))
    assert ss.held_out_runs(one, range(100, 103)) == [
        ("rtklib:rtklib-drive@50-100%", s) for s in (100, 101, 102)]
    many = SimpleNamespace(test=(("akit:akit:5", 0), ("akit:akit:6", 0)))
    assert ss.held_out_runs(many, range(100, 103)) == list(many.test)  # pairs: trajectories


def test_every_filter_of_a_split_is_run_once_with_its_own_file(tmp_path):
    specs = ss.split_specs(SPLIT, ["ekf-tuned", "huber-tuned"], tmp_path)
    assert specs["fuzzy-x"] == f"fakf@{tmp_path / 'rules/r.json'}"
    assert specs["fuzzy-vb-tuned"] == f"fuzzy-vb@{tmp_path / 'rules/sup.json'}"
    assert specs["huber-tuned"] == f"huber-tuned@{tmp_path / 'studies/p.json'}"
    assert specs["huber"] == "huber" and specs["apso"] == f"apso@{tmp_path / 'studies/a.json'}"
    assert len(set(specs.values())) == len(specs)


def test_missing_files_are_named_and_an_absent_supervisor_is_dropped(tmp_path):
    assert "`rules/r.json`" in ss.missing_note([SPLIT], tmp_path)[0]
    for f in SPLIT.files():
        (tmp_path / f).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / f).write_text("{}")
    assert SPLIT.missing(tmp_path) == []
    assert SPLIT.available(tmp_path).designs() == ["fuzzy-x"]
    assert "`fuzzy-vb-tuned` is not judged" in ss.missing_note([SPLIT], tmp_path)[0]


def _scores(values: dict, scenario="held") -> pd.DataFrame:
    return pd.DataFrame([{"scenario": scenario, "seed": 5 + k, "filter": f, "score": v}
                         for f, xs in values.items() for k, v in enumerate(xs)])


def test_the_fuzzy_design_is_paired_against_the_best_classical_filter_of_its_set():
    fuzzy = [0.80, 1.00, 0.70, 0.99]
    best = [0.95, 0.92, 0.90, 0.99]   # sage-husa-tuned: lower mean than vb and ekf-tuned
    scores = _scores({"fuzzy-x": fuzzy, "fuzzy-vb-tuned": [0.5] * 4, "ekf-tuned": [1.0] * 4,
                      "sage-husa-tuned": best, "vb-tuned": [0.97, 0.96, 0.99, 1.01],
                      "ekf-true": [0.1] * 4})
    split = ss.Split("held", "fuzzy-x", "s", "r", "p")
    rows, text = ss.comparison(scores, [split], "trajectories")
    d = np.subtract(fuzzy, best)
    half = stats.t.ppf(0.975, len(d) - 1) * d.std(ddof=1) / np.sqrt(len(d))
    assert "| sage-husa-tuned |" in rows[2]          # neither fuzzy nor the oracle
    assert f"{d.mean():+.3f} [{d.mean() - half:+.3f}, {d.mean() + half:+.3f}]" in rows[2]
    # the CI of 4 pairs reaches above zero: a draw, whatever the mean says
    assert d.mean() + half > 0 and "draws with" in rows[2]
    assert "4 trajectories" in text[0]


def _fold_rows(fold, trajectories, values: dict) -> pd.DataFrame:
    """filter -> per trajectory (rms_pos_m, rms_vel_mps, rms_pos_h_m)."""
    return pd.DataFrame([{"fold": fold, "trajectory": t, "scenario": fold, "seed": t,
                          "filter": f, "rms_pos_m": p, "rms_vel_mps": v, "rms_pos_h_m": h}
                         for f, xs in values.items() for t, (p, v, h) in zip(trajectories, xs)])


def test_the_best_equally_tuned_filter_is_chosen_per_fold_and_paired_per_trajectory():
    a = _fold_rows("a", [5, 6], {"ekf-tuned": [(1, 1, 1), (2, 1, 2)],
                                 "huber-tuned": [(0.5, 1, 0.5), (1, 1, 1)],
                                 "huber": [(0.1, 0.1, 0.1)] * 2,   # untuned: not in the pool
                                 ph.TUNED_LABEL: [(0.7, 1, 0.7), (0.9, 1, 0.9)]})
    b = _fold_rows("b", [1, 2], {"ekf-tuned": [(1, 1, 1), (1, 1, 1)],
                                 "huber-tuned": [(3, 1, 3), (3, 1, 3)],
                                 ph.TUNED_LABEL: [(1.2, 1, 1.2), (1.1, 1, 1.1)]})
    df, best = ph.with_best(pd.concat([a, b], ignore_index=True))
    assert best == {"a": "huber-tuned", "b": "ekf-tuned"}
    rows = ph.paired_best(df)
    # fold a: 0.7 - 0.5, 0.9 - 1.0; fold b: 1.2 - 1, 1.1 - 1; both: the four together
    d = np.array([0.2, -0.1, 0.2, 0.1])
    assert rows[0][2].startswith("+0.050 [") and rows[1][2].startswith("+0.150 [")
    assert rows[2][2].startswith(f"{d.mean():+.3f} [") and rows[2][4] == "4"
