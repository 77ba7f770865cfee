"""Per-scenario reporting (:func:`fuzzynav.report.scenario_rows`,
:func:`fuzzynav.tuning.evaluate.format_scenarios`): one row per scenario, its mean and
Student-t CI over that scenario's seeds only, checked against a direct computation."""
import numpy as np
import pandas as pd
import pytest
from scipy import stats

from fuzzynav.report import scenario_rows
from fuzzynav.tuning.evaluate import format_scenarios


def _table():
    """Two test scenarios x 4 seeds, the tuned filter and one compared filter."""
    rng = np.random.default_rng(3)
    rows = []
    for sc, level in (("straight", 0.8), ("turns", 1.3)):
        for seed in range(4):
            for f, shift in (("tuned", 0.0), ("fakf", 0.1)):
                rows.append({"scenario": sc, "seed": seed, "filter": f,
                             "score": level + shift + 0.05 * rng.standard_normal()})
    return pd.DataFrame(rows)


def _parse(cell):
    mean, half = cell.split(" ± ")
    return float(mean), float(half)


def test_two_scenarios_give_two_rows_each_its_own_mean_and_t_interval():
    df = _table()
    rows = scenario_rows(df, ["tuned"], ["fakf"])
    assert [r[0] for r in rows] == ["straight", "turns"]
    for r in rows:
        x = df[(df.scenario == r[0]) & (df["filter"] == "tuned")]["score"].to_numpy()
        mean, half = _parse(r[3])
        assert r[2] == 4
        assert mean == pytest.approx(x.mean(), abs=5e-4)
        h = stats.t.ppf(0.975, x.size - 1) * x.std(ddof=1) / np.sqrt(x.size)
        assert half == pytest.approx(h, abs=5e-4)
        # against the EKF (score 1 on every run): 100 (1 - mean)
        assert float(r[4].split(" %")[0]) == pytest.approx(100 * (1 - x.mean()), abs=0.05)
        y = df[(df.scenario == r[0]) & (df["filter"] == "fakf")]["score"].to_numpy()
        assert float(r[5].split(" %")[0]) == pytest.approx(100 * (1 - x.mean() / y.mean()),
                                                           abs=0.05)
    # the two scenarios differ: a pooled row would have hidden it
    assert _parse(rows[0][3])[0] < 1 < _parse(rows[1][3])[0]


def test_the_markdown_table_has_one_row_per_set_and_scenario():
    df = _table()
    text = format_scenarios(df.iloc[:8], df.iloc[8:], ["tuned"], "ekf")
    lines = text.splitlines()
    assert lines[0] == "| set | scenario | filter | runs | score | vs ekf | vs fakf |"
    body = lines[2:]
    assert [ln.split(" | ")[:3] for ln in body] == [["| train", "straight", "tuned"],
                                                     ["| test", "turns", "tuned"]]
    # several tuned filters (a baseline study) are compared with each other, not themselves
    two = format_scenarios(None, df, ["tuned", "fakf"], "ekf").splitlines()
    assert two[0].endswith("| vs tuned | vs fakf |")
    assert [ln.endswith("| — |") for ln in two[2:]] == [False, True, False, True]
