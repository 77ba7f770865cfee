"""The train/test tables of a study refuse diverged runs (exit 3) instead of printing them.

A diverged run's ratios become ``FAILED_RATIO`` (10) in the objective, which a table would
print as a plain, confident number.
"""
from __future__ import annotations

import math
from dataclasses import replace
from types import SimpleNamespace

import pytest

import fuzzynav.tuning.evaluate as evaluate
from fuzzynav.cli import main
from fuzzynav.errors import RunDivergedError
from fuzzynav.tuning.objective import Evaluator
from tests.tuning.studies import write_study

GOOD = {"rms_pos_m": 2.0, "rms_vel_mps": 0.2, "rms_att_deg": 0.5, "max_pos_h_m": 4.0,
        "completed": 1.0}


class FakeEvaluator:
    """Evaluator stand-in: metrics per (filter, seed) from a table, no simulation."""

    config = SimpleNamespace(baseline="ekf", t_start_s=0.0,
                             weights={"pos": 1.0, "vel": 1.0, "att": 1.0})

    def __init__(self, bad=()):
        self.bad = set(bad)  # (filter, seed) whose metrics are NaN

    def _metrics(self, name, seed):
        nan = (name, seed) in self.bad
        return {k: (math.nan if nan and k.startswith("rms_pos") else v) for k, v in GOOD.items()}

    def log(self, scenario, seed):
        return seed

    def source(self, scenario, seed):  # a simulated run's rule: every RMS and maximum
        return SimpleNamespace(required=lambda m: [k for k in m if k.startswith(("rms_",
                                                                                 "max_"))])

    def baseline(self, scenario, seed):
        return self._metrics("ekf", seed)

    def run_systems(self, systems, scenario, seed):
        return SimpleNamespace(metrics=self._metrics("tuned", seed))

    judge = Evaluator.judge


@pytest.fixture
def compared(monkeypatch):
    """``Evaluator.run`` of the compared filters: fakf NaN on seed 2, 'broken' cannot run."""
    def run(self, scenario, seed, name, options=None, setup=None):
        if name == "broken":
            raise RuntimeError("needs a magnetometer")
        return SimpleNamespace(metrics=FakeEvaluator({("fakf", 2)})._metrics(name, seed))
    monkeypatch.setattr(FakeEvaluator, "run", run, raising=False)


RUNS = [("s", 1), ("s", 2)]


def test_finite_runs_give_the_table_and_a_filter_that_cannot_run_is_recorded(compared):
    df = evaluate.run_table(FakeEvaluator(), {"gps": None}, RUNS[:1], ("broken",))
    assert list(df["filter"]) == ["tuned", "broken"]
    assert df["error"].iloc[1] == "needs a magnetometer"
    assert df["pos_ratio"].iloc[0] == pytest.approx(1.0, abs=1e-12)  # same metrics as the EKF


@pytest.mark.parametrize("bad, compare, named", [
    ({("tuned", 2)}, (), "filter tuned diverged on scenario s seed 2"),
    ({("ekf", 1)}, (), "filter ekf diverged on scenario s seed 1"),   # the baseline
    (set(), ("fakf",), "filter fakf diverged on scenario s seed 2"),  # a compared filter
])
def test_a_diverged_run_is_refused_naming_filter_scenario_and_seed(compared, bad, compare,
                                                                   named):
    with pytest.raises(RunDivergedError, match=named + r".*rms_pos_m = nan"):
        evaluate.run_table(FakeEvaluator(bad), {"gps": None}, RUNS, compare)


def _nan_candidate(run_systems):
    def run(self, systems, scenario, seed):
        out = run_systems(self, systems, scenario, seed)
        return replace(out, metrics={**out.metrics, "rms_pos_m": math.nan}) if seed == 100 \
            else out
    return run


def test_study_summary_and_report_exit_3_without_a_table(capsys, tmp_path, sim_cache,
                                                         monkeypatch):
    """The tuned rules diverge on the held-out run (seed 100): ``study run`` prints no
    train/test table and exits 3; ``study report`` writes no report.md."""
    monkeypatch.setattr(Evaluator, "run_systems", _nan_candidate(Evaluator.run_systems))
    cfg = write_study(tmp_path)
    code = main(["study", "run", str(cfg), "--trials", "1", "--cache", str(sim_cache)])
    out, err = capsys.readouterr()
    assert code == 3, err
    last = err.strip().splitlines()[-1]  # after the trials' progress bar
    assert last.startswith("fuzzynav: error: filter tuned diverged on scenario ")
    assert "seed 100: rms_pos_m = nan" in last and "Traceback" not in err
    assert "mean ratio" not in out and not any(line.startswith(("tuned", "fakf"))
                                               for line in out.splitlines())  # no table
    code = main(["study", "report", str(cfg), "--cache", str(sim_cache)])
    _, err = capsys.readouterr()
    assert code == 3 and "filter tuned diverged" in err
    assert not (tmp_path / "tiny_report" / "report.md").exists()
