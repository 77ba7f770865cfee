"""Paper 004's APSO over three tunings (issue 25): the shipped study files and outputs of
every tuning (seeds, the fuzzy study's budget), and the page's APSO-vs-EKF table on
hand-made frames."""
import json
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fuzzynav.metrics import crossed_ci, mean_ci
from fuzzynav.pages import science_split_tunings as st
from fuzzynav.pages.science_splits import AKIT_FOLDS, Split
from fuzzynav.papers.paper004.page_heldout import apso_vs_ekf_lines
from fuzzynav.report import diff_cell

ROOT = Path(__file__).resolve().parents[2]
CASES = [(fold, k) for fold in AKIT_FOLDS for k in range(st.N_TUNINGS)]


def _toml(path):
    return tomllib.loads((ROOT / path).read_text())


@pytest.mark.parametrize("fold,k", CASES, ids=[f"{f.apso}-t{k}" for f, k in CASES])
def test_every_tuning_ships_with_the_fuzzy_studys_seed_and_budget(fold, k):
    study = Path(fold.apso).with_suffix(".toml").as_posix()
    apso = _toml(st.tuning_file(study, k))
    fuzzy = _toml(st.tuning_file(fold.study, k))
    assert apso["study"]["seed"] == fuzzy["study"]["seed"]  # 4, 104, 204 as the others
    pso = apso["study"]["pso"]
    assert apso["study"]["trials"] == pso["particles"] * pso["iterations"] \
        == fuzzy["study"]["trials"]
    assert apso["train"] == fuzzy["train"] and apso["test"]["recordings"] == \
        fuzzy["test"]["recordings"]
    out = json.loads((ROOT / st.tuning_file(fold.apso, k)).read_text())
    assert apso["baselines"]["out"] == Path(st.tuning_file(fold.apso, k)).name
    assert out["study"] == apso["name"]  # the output is this study file's, not another's
    assert out["trials"] == {"apso": apso["study"]["trials"]}
    assert len(out["history"]["apso"]) == pso["iterations"]
    assert set(out["filters"]["apso"]) == {"q_att", "q_vel", "r_all"}


def test_the_tunings_seeds_differ():
    for fold in AKIT_FOLDS:
        study = Path(fold.apso).with_suffix(".toml").as_posix()
        seeds = st.sampler_seeds(study, range(st.N_TUNINGS))
        assert len(set(seeds)) == st.N_TUNINGS


def _frame(label, diff):
    """One tuning's held-out rows: ``ekf-tuned`` and ``ekf`` at RMS 1, ``apso`` at
    1 + diff[j] on trajectory j (both metrics), so its score minus the EKF's is diff[j]."""
    rows = []
    for j, d in enumerate(diff):
        for f, v in (("ekf-tuned", 1.0), ("ekf", 1.0), ("apso", 1.0 + d)):
            rows.append({"scenario": label, "seed": j + 1, "filter": f, "rms_pos_m": v,
                         "rms_vel_mps": v})
    return pd.DataFrame(rows)


FOLDS = (Split("A", "fz", "a.toml", "a.json", "ap.json", "apso_a.json"),
         Split("B", "fz", "b.toml", "b.json", "bp.json", "apso_b.json"))


def _row(lines, label):
    return next(x for x in lines if x.startswith(f"| `{label}` |"))


def test_apso_vs_ekf_pairs_every_tuning_and_pools_them_crossed():
    diff_a = np.array([[0.1, 0.2, 0.3, 0.1], [0.1, 0.1, 0.2, 0.2], [0.3, 0.1, 0.2, 0.2]])
    diff_b = np.array([[-0.2, -0.1, -0.3, -0.2], [-0.1, -0.2, -0.2, -0.3],
                       [-0.2, -0.2, -0.1, -0.1]])
    frames = {"A": {k: _frame("A", d) for k, d in enumerate(diff_a)},
              "B": {k: _frame("B", d) for k, d in enumerate(diff_b)}}
    lines = apso_vs_ekf_lines(FOLDS, frames)
    assert "| set | design | compared with | tuning 0 | tuning 1 | tuning 2 |" in lines[2]
    for label, diff in (("A", diff_a), ("B", diff_b)):
        row = _row(lines, label)
        assert "| apso | ekf |" in row
        for k in range(3):
            assert diff_cell(mean_ci(diff[k])) in row
        assert diff_cell(crossed_ci(diff)) in row
    # pooled A: 0.175 +- 0.059 (above 0: APSO worse); B: every difference below 0
    assert "**loses to**" in _row(lines, "A") and "**wins against**" in _row(lines, "B")
    assert lines[-2].endswith("(wins / draws / losses of the 2 set(s)): 1 / 0 / 1.")


def test_apso_vs_ekf_uses_only_the_tunings_every_fold_has():
    d = [0.1, 0.2, 0.0, 0.1]
    frames = {"A": {k: _frame("A", d) for k in range(3)},
              "B": {k: _frame("B", d) for k in range(2)}}
    lines = apso_vs_ekf_lines(FOLDS, frames)
    assert "tuning 1 |" in lines[2] and "tuning 2" not in lines[2]
    assert apso_vs_ekf_lines(FOLDS, {"A": {0: _frame("A", d)}, "B": {0: _frame("B", d)}}) \
        == []
