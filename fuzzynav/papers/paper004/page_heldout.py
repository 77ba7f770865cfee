"""Held-out results of the studies trained on A-KIT recordings (docs/paper004.md).

Each fold's study (``studies/paper004_fuzzy.toml``: trained on trajectories 1-4, judged on
5-8; ``paper004_fuzzy_rev.toml``: the reverse) is read from its journal; its best trial's
rules run on the fold's held-out trajectories beside the EKF and Huber.  Over the two folds
every trajectory is held out once, so the eight held-out results pool into one paired
comparison against the EKF (mean relative change over trajectories, 95 % CI, t).
Part of ``fuzzynav docs regenerate paper004`` (needs the studies run and ``$FUZZYNAV_DATA``).
"""
from __future__ import annotations

import pandas as pd

from fuzzynav.pages.common import REPO_ROOT as ROOT
from fuzzynav.realdata.dataspec import is_recording_name, parse_recording_spec
from fuzzynav.report import ci_cell, improvement_cell, render

FOLDS = ("studies/paper004_fuzzy.toml", "studies/paper004_fuzzy_rev.toml")
APSO_FOLDS = ("studies/paper004_apso.toml", "studies/paper004_apso_rev.toml")
COMPARE = ("ekf", "huber")
TUNED_LABEL = "fuzzy R-scaling (tuned on the other four)"
APSO_LABEL = "APSO Q/R (tuned on the other four)"


def fuzzy_fold(path) -> pd.DataFrame:
    """One row per (held-out trajectory, filter) of a fuzzy study's best trial."""
    from fuzzynav.tuning.study_config import load_study_config
    from fuzzynav.tuning.evaluate import run_table
    from fuzzynav.tuning.export import choose_trial, systems_of
    from fuzzynav.tuning.objective import Evaluator
    from fuzzynav.tuning.optuna_study import open_study

    cfg = load_study_config(ROOT / path)
    trial = choose_trial(open_study(cfg), cfg)
    runs = [r for r in cfg.test if is_recording_name(r[0])]
    df = run_table(Evaluator(cfg), systems_of(cfg, trial), runs, COMPARE)
    df["filter"] = df["filter"].replace({"tuned": TUNED_LABEL})
    return _with_trajectory(df, cfg)


def apso_fold(path) -> pd.DataFrame:
    """One row per held-out trajectory of an APSO baseline study's tuned multipliers."""
    from fuzzynav.tuning.baseline_config import load_baseline_config
    from fuzzynav.tuning.evaluate import run_table
    from fuzzynav.tuning.objective import Evaluator

    bcfg = load_baseline_config(ROOT / path)
    spec = f"apso@{bcfg.out}"
    df = run_table(Evaluator(bcfg.study), {}, bcfg.study.test, (spec,))
    return _with_trajectory(df.replace({"filter": {spec: APSO_LABEL}}), bcfg.study)


def _with_trajectory(df, cfg) -> pd.DataFrame:
    train = sorted({parse_recording_spec(n).session for n, _ in cfg.train})
    return df.assign(trajectory=[int(parse_recording_spec(n).session) for n in df["scenario"]],
                     fold="trained on " + ",".join(train))


def _cell(values) -> str:
    return ci_cell(values, ".2f")


_imp = improvement_cell


def heldout_table(df: pd.DataFrame, key: str = "rms_pos_h_m", filters=None) -> str:
    """Per held-out trajectory, pooled over the eight (mean ± CI) and without 6, with the
    paired change against the EKF on the same trajectories (positive = smaller error)."""
    piv = df.pivot_table(index="trajectory", columns="filter", values=key)
    filters = filters or list(dict.fromkeys(df["filter"]))
    keep = piv.index != 6
    head = ["filter"] + [str(t) for t in piv.index] + [
        f"all {len(piv)}", "vs EKF (all)", "without 6", "vs EKF (without 6)"]
    rows = []
    for f in filters:
        col = piv[f]
        rows.append([f] + [f"{v:.2f}" for v in col] + [
            _cell(col), "" if f == "ekf" else _imp(piv["ekf"], col),
            _cell(col[keep]), "" if f == "ekf" else _imp(piv["ekf"][keep], col[keep])])
    return render(head, rows, markdown=True)


def fold_table(df: pd.DataFrame, key: str = "rms_pos_h_m") -> str:
    """Per fold: the paired change of every filter against the EKF on its four trajectories."""
    rows = []
    for fold, sub in df.groupby("fold", sort=False):
        piv = sub.pivot_table(index="trajectory", columns="filter", values=key)
        for f in piv.columns:
            if f != "ekf":
                rows.append([fold, ",".join(map(str, piv.index)), f, _imp(piv["ekf"], piv[f])])
    return render(["fold", "held out", "filter", "vs EKF"], rows, markdown=True)


def heldout_frame(folds=FOLDS, apso_folds=APSO_FOLDS) -> pd.DataFrame:
    """Both folds' held-out rows of the fuzzy and the APSO studies."""
    return pd.concat([fuzzy_fold(p) for p in folds] + [apso_fold(p) for p in apso_folds],
                     ignore_index=True)


def section(df: pd.DataFrame) -> list:
    """The markdown lines of the held-out section."""
    filters = ["ekf", "huber", TUNED_LABEL, APSO_LABEL]
    return ["### Trained on four A-KIT trajectories, judged on the other four", "",
            "The fuzzy DVL R-scaling study (`studies/paper004_fuzzy.toml`, trained on "
            "trajectories 1–4; `paper004_fuzzy_rev.toml`, trained on 5–8; 150 TPE trials "
            "each) and the APSO of the Q/R multipliers (`studies/paper004_apso.toml` / "
            "`_rev`: 8 particles × 8 iterations, inertia 0.9 → 0.4) run with what they "
            "found on the trajectories they did not see. Horizontal RMS (m) per held-out "
            "trajectory; pooled over the eight (each held out once); paired change vs the "
            "EKF, positive = smaller error:", "",
            heldout_table(df, filters=filters), "",
            "End error as % of the distance travelled:", "",
            heldout_table(df, "end_pos_h_pct", filters), "",
            "Per fold (horizontal RMS, paired change vs the EKF on the fold's four held-out "
            "trajectories):", "", fold_table(df), ""]
