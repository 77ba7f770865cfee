"""Train and held-out test tables: tuned rules beside the EKF, the paper's rules and baselines.

Every filter runs on the same (scenario, seed) logs with the same initial error; per run the
RMS position, velocity and attitude errors are divided by the baseline's (EKF), and the
table shows the mean ratio per group with a 95 % confidence interval over the runs.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from fuzzynav.filters.named import parse_filter_spec
from fuzzynav.metrics import mean_ci
from fuzzynav.runpath import RunOutcome, check_outcomes, nonfinite
from fuzzynav.tuning.study_config import GROUP_METRICS
from fuzzynav.tuning.objective import CANDIDATE

__all__ = ["run_table", "summary", "format_summary", "format_scenarios",
           "scenario_section"]


def run_table(evaluator, systems: dict, runs, compare=()) -> pd.DataFrame:
    """One row per (run, filter): metrics and ratios to the baseline.

    ``systems`` (controller -> FuzzySystem) is run as filter ``"tuned"``
    (:data:`~fuzzynav.tuning.objective.CANDIDATE`); ``compare`` are named filters run beside
    it (a filter that cannot run is recorded with an ``error``).  Every row is scored by
    :func:`~fuzzynav.tuning.objective.score_metrics`, like the study's trials.

    Raises
    ------
    RunDivergedError
        When the baseline, the tuned rules or a compared filter gives non-finite metrics on
        a run: the ratios would turn it into a plain number (``FAILED_RATIO``) and the table
        would read as a result.
    """
    rows, checked = [], []
    for scenario, seed in runs:
        base = evaluator.baseline(scenario, seed)
        outcomes = {}
        if systems:
            outcomes[CANDIDATE] = evaluator.run_systems(systems, scenario, seed).metrics
        for name in compare:
            try:
                base_name, own = parse_filter_spec(name)  # NAME@FILE: tuned parameters
                kw = {"options": own} if own else {}
                outcomes[name] = evaluator.run(scenario, seed, base_name, **kw).metrics
            except Exception as exc:  # a baseline that cannot run here is reported, not fatal
                outcomes[name] = {"error": str(exc)}
        source = evaluator.source(scenario, seed)
        checked += [RunOutcome(name, scenario, seed, None, m, nonfinite(source, m))
                    for name, m in [(evaluator.config.baseline, base), *outcomes.items()]
                    if "error" not in m]
        rows += [_row(evaluator, scenario, seed, name, m) for name, m in outcomes.items()]
    check_outcomes(checked)  # the baseline's runs too: every ratio divides by them
    return pd.DataFrame(rows)


def _row(evaluator, scenario, seed, name, metrics) -> dict:
    """A table row: the filter's metrics, its ratios to the baseline and its score."""
    row = {"scenario": scenario, "seed": seed, "filter": name}
    if "error" in metrics:
        return {**row, "error": metrics["error"]}
    scored = evaluator.judge(metrics, scenario, seed)
    return {**row, **metrics, **{f"{g}_ratio": scored.ratios[g] for g in GROUP_METRICS},
            "score": scored.score}


def summary(df: pd.DataFrame, by=("filter",)) -> pd.DataFrame:
    """Mean ratio (95 % CI half width) per group and filter (optionally per scenario)."""
    cols = [f"{g}_ratio" for g in GROUP_METRICS] + ["score"]
    out = []
    for key, sub in df.groupby(list(by), sort=False):
        key = key if isinstance(key, tuple) else (key,)
        row = dict(zip(by, key))
        for c in cols:
            if c in sub:
                est = mean_ci(sub[c].to_numpy(dtype=float))
                row[c] = est.mean
                row[c + "_ci"] = est.half_width if est.n >= 2 else np.nan  # no CI from 1 run
        row["runs"] = len(sub)
        out.append(row)
    return pd.DataFrame(out)


def format_summary(train: pd.DataFrame, test: pd.DataFrame) -> str:
    """Plain-text train/test table (ratios to the EKF: < 1 is better than the EKF)."""
    from fuzzynav.report import render

    header = ["filter", "set", "pos ratio", "vel ratio", "att ratio", "score", "runs"]
    rows = []
    for label, df in (("train", train), ("test", test)):
        if df is None or df.empty:
            continue
        for _, r in summary(df).iterrows():
            rows.append([r["filter"], label] + [
                f"{r[c]:.3f} ± {r[c + '_ci']:.3f}" if np.isfinite(r.get(c + "_ci", np.nan))
                else f"{r.get(c, np.nan):.3f}"
                for c in ("pos_ratio", "vel_ratio", "att_ratio", "score")] + [int(r["runs"])])
    return render(header, rows)


def format_scenarios(train: pd.DataFrame, test: pd.DataFrame, candidates, ref: str = "ekf",
                     markdown: bool = True) -> str:
    """The per-scenario table: one row per (set, scenario or recording, candidate).

    Each row gives the candidate's mean score (ratio to ``ref``) with its Student-t 95 % CI
    over that scenario's seeds, and its paired change against ``ref`` and against every
    other filter of the table on the same seeds (:func:`fuzzynav.report.scenario_rows`,
    positive = the candidate's error is smaller, bootstrap 95 % interval).
    """
    from fuzzynav.report import render, scenario_rows

    frames = [(label, df) for label, df in (("train", train), ("test", test))
              if df is not None and not df.empty and "score" in df]
    others = list(dict.fromkeys(f for _, df in frames for f in df["filter"]))
    # one tuned filter is not compared with itself; several (a baseline study) are
    others = [f for f in others if f != ref and (len(candidates) > 1 or f not in candidates)]
    rows = [[label, _short(r[0]), *r[1:]] for label, df in frames
            for r in scenario_rows(df, candidates, others)]
    header = ["set", "scenario", "filter", "runs", "score", f"vs {ref}",
              *(f"vs {o}" for o in others)]
    return render(header, rows, markdown=markdown)


def _short(scenario: str) -> str:
    """A scenario file's name without its directory (built-in names and recordings as they are)."""
    return Path(scenario).name if scenario.endswith(".toml") else scenario


def scenario_section(train, test, candidates, ref) -> list:
    """The report's lines of the per-scenario table (:func:`format_scenarios`): the
    pooled train/test table hides which scenario a filter wins or loses on."""
    return ["## Per scenario or recording", "",
            f"Score (ratio to {ref}; mean ± 95 % CI over the scenario's seeds) and the "
            "paired change of the score against each filter on the same seeds (positive: "
            "smaller error; bootstrap 95 % interval).", "",
            format_scenarios(train, test, candidates, ref), ""]

