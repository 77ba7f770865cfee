"""Held-out results of the studies trained on A-KIT recordings (docs/paper004.md).

Each fold (``studies/paper004_fuzzy.toml``: trained on trajectories 1-4, judged on 5-8;
``paper004_fuzzy_rev.toml``: the reverse) runs what was tuned on its four training
trajectories on the other four: the fuzzy DVL controller as exported
(``rules/paper004_fuzzy_dvl.json``, ``_rev.json``), the classical filters tuned with the
same budget, pruner and objective (``studies/paper004_baselines.json``, ``_rev.json``) and
the APSO multipliers (``studies/paper004_apso.json``, ``_rev.json``), beside the EKF and
Huber (:func:`fuzzynav.pages.science_splits.split_frame`, shared with docs/science.md).
Over the two folds every trajectory is held out once, so the eight held-out results pool
into one paired comparison (mean relative change over trajectories, 95 % CI, t).  The
"best equally tuned classical filter" of a fold is the ``-tuned`` filter with the lowest
mean held-out score (the studies' objective against ``ekf-tuned``; chosen in hindsight,
which favours it).  Part of ``fuzzynav docs regenerate paper004`` (needs those files and
``$FUZZYNAV_DATA``).
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd

from fuzzynav.metrics import mean_ci
from fuzzynav.pages.common import REPO_ROOT as ROOT
from fuzzynav.pages.science_splits import AKIT_FOLDS, SPLIT_METRICS, split_frame
from fuzzynav.realdata.dataspec import parse_recording_spec
from fuzzynav.report import diff_cell, improvement_cell, pooled_rows, render

__all__ = ["TUNED_LABEL", "APSO_LABEL", "BEST_LABEL", "TUNED", "fold_frame", "best_tuned",
           "with_best", "heldout_table", "fold_table", "heldout_frame", "paired_best",
           "tunings_lines", "apso_vs_ekf_lines", "apso_bounds_lines", "section"]

TUNED_LABEL = "fuzzy R-scaling (tuned on the other four)"
APSO_LABEL = "APSO Q/R (tuned on the other four)"
BEST_LABEL = "best equally tuned classical (per fold)"
#: the classical filters tuned with the fuzzy study's budget (the pool of BEST_LABEL)
TUNED = ("ekf-tuned", "sage-husa-tuned", "vb-tuned", "huber-tuned")


def fold_frame(split, cache=None) -> pd.DataFrame:
    """One row per (held-out trajectory, filter) of a fold, with ``trajectory`` and
    ``fold`` (the training trajectories)."""
    from fuzzynav.tuning.study_config import load_study_config

    cfg = load_study_config(ROOT / split.study)
    train = sorted({parse_recording_spec(n).session for n, _ in cfg.train})
    df = split_frame(split, cache)
    return df.assign(trajectory=df["seed"], fold="trained on " + ",".join(train)).replace(
        {"filter": {split.fuzzy: TUNED_LABEL, "apso": APSO_LABEL}})


def best_tuned(df: pd.DataFrame) -> str:
    """The filter of :data:`TUNED` with the lowest mean score on ``df``'s trajectories
    (score: mean of the :data:`SPLIT_METRICS` ratios to ``ekf-tuned``, run by run)."""
    from fuzzynav.pages.scores import scores_to

    sub = df[df["filter"].isin(TUNED)]
    if sub.empty:
        raise ValueError("no equally tuned classical filter in the fold's rows")
    scores = scores_to(sub, "ekf-tuned", SPLIT_METRICS)
    return scores.groupby("filter")["score"].mean().idxmin()


def with_best(df: pd.DataFrame) -> tuple:
    """``df`` with the rows of each fold's best equally tuned classical filter copied
    under :data:`BEST_LABEL`, and fold -> that filter's name."""
    best = {fold: best_tuned(sub) for fold, sub in df.groupby("fold", sort=False)}
    rows = [sub[sub["filter"] == best[fold]].assign(filter=BEST_LABEL)
            for fold, sub in df.groupby("fold", sort=False)]
    return pd.concat([df, *rows], ignore_index=True), best


def heldout_table(df: pd.DataFrame, key: str = "rms_pos_h_m", filters=None) -> str:
    """Per held-out trajectory, pooled over the eight (mean ± CI) and without 6, with the
    paired change against the EKF on the same trajectories (positive = smaller error)."""
    piv = df.pivot_table(index="trajectory", columns="filter", values=key)
    filters = filters or list(dict.fromkeys(df["filter"]))
    head = ["filter"] + [str(t) for t in piv.index] + [
        f"all {len(piv)}", "vs EKF (all)", "without 6", "vs EKF (without 6)"]
    return render(head, pooled_rows(piv, filters, "ekf", piv.index != 6), markdown=True)


def fold_table(df: pd.DataFrame, key: str = "rms_pos_h_m") -> str:
    """Per fold: the paired change of every filter against the EKF on its four trajectories."""
    rows = []
    for fold, sub in df.groupby("fold", sort=False):
        piv = sub.pivot_table(index="trajectory", columns="filter", values=key)
        for f in piv.columns:
            if f != "ekf":
                rows.append([fold, ",".join(map(str, piv.index)), f,
                             improvement_cell(piv["ekf"], piv[f])])
    return render(["fold", "held out", "filter", "vs EKF"], rows, markdown=True)


def heldout_frame(folds=AKIT_FOLDS, cache=None) -> tuple:
    """Both folds' held-out rows (with the best equally tuned classical filter's rows
    under :data:`BEST_LABEL`) and fold -> that filter."""
    return with_best(pd.concat([fold_frame(f, cache) for f in folds], ignore_index=True))


def paired_best(df: pd.DataFrame, key: str = "rms_pos_h_m") -> list:
    """Rows: per fold and over both, the fuzzy controller minus the best equally tuned
    classical filter on the same trajectories (difference in ``key``, 95 % CI over the
    trajectories) and the relative change."""
    rows = []
    groups = [*df.groupby("fold", sort=False), ("both folds", df)]
    for fold, sub in groups:
        piv = sub.pivot_table(index="trajectory", columns="filter", values=key)
        est = mean_ci((piv[TUNED_LABEL] - piv[BEST_LABEL]).to_numpy())
        ci = diff_cell(est) if est.n > 1 else f"{est.mean:+.3f}"
        rows.append([fold, ",".join(map(str, piv.index)), ci,
                     improvement_cell(piv[BEST_LABEL], piv[TUNED_LABEL]), str(est.n)])
    return rows


def tunings_lines(folds=AKIT_FOLDS, cache=None) -> list:
    """Both folds over their three tunings (every tuned filter tuned again with two more
    sampler seeds: :func:`fuzzynav.pages.science_split_tunings.split_tunings_lines`, the
    table of docs/science.md's AUV section)."""
    from fuzzynav.pages import science_split_tunings as st

    frames = {f.label: st.split_frames(f, split_frame(f, cache), st.N_TUNINGS, cache)
              for f in folds}
    return ["### Over three tunings", "",
            "Scores here are the studies' objective (mean of the 3-D position and velocity "
            "RMS ratios), not the horizontal RMS above.", "",
            *st.split_tunings_lines(list(folds), frames, "trajectories"),
            "### APSO over three tunings", "",
            "Paper 004's APSO of the Q/R multipliers, tuned three times per fold with the "
            "fuzzy study's budget (150 evaluations: 10 particles × 15 iterations) and its own "
            "fitness (position RMS ratio to the EKF; `studies/paper004_apso.toml` / `_rev` "
            "and their `_t1`, `_t2`), scored like every filter above by the studies' "
            "objective.", "",
            *apso_bounds_lines(folds),
            *st.split_tunings_lines(list(folds), frames, "trajectories", designs=["apso"],
                                    design_text="APSO", studies=[
                                        Path(f.apso).with_suffix(".toml").as_posix()
                                        for f in folds]),
            *apso_vs_ekf_lines(folds, frames)]


def apso_vs_ekf_lines(folds, frames: dict) -> list:
    """APSO against the untuned ``ekf`` (the reference of its fitness) over the tunings
    every fold has (``frames``: fold label -> tuning -> frame,
    :func:`fuzzynav.pages.science_split_tunings.split_frames`), paired per trajectory and
    pooled as the table against the best classical filter
    (:func:`fuzzynav.pages.science_split_tunings.tunings_lines`), or nothing with fewer
    than two tunings."""
    from fuzzynav.pages import science_split_tunings as st

    ks = sorted(set.intersection(*(set(v) for v in frames.values())))
    if len(ks) < 2:
        return []
    scores = pd.concat([st.split_scores({k: frames[f.label][k] for k in ks}, "ekf-tuned",
                                        SPLIT_METRICS) for f in folds], ignore_index=True)
    rows, tally = st.tunings_lines(scores, [f.label for f in folds], ["apso"],
                                   best=dict.fromkeys(ks, "ekf"), unit="trajectories",
                                   ref_head="compared with")
    t = tally["apso"]
    return ["APSO against the untuned `ekf` (the reference of its fitness) on the same "
            "held-out trajectories, in the same score and paired and pooled the same way "
            "(negative favours APSO):", "", *rows, "",
            f"- `apso` against `ekf` pooled over the tunings (wins / draws / losses of the "
            f"{len(folds)} set(s)): {t['wins against']} / {t['draws with']} / "
            f"{t['loses to']}.", ""]


def apso_bounds_lines(folds=AKIT_FOLDS) -> list:
    """A sentence per fold and tuning whose APSO multipliers sit at an end of their search
    range (:func:`fuzzynav.tuning.baseline_config.bound_hits`), or nothing."""
    import json

    from fuzzynav.pages import science_split_tunings as st
    from fuzzynav.tuning.baseline_config import bound_hits

    out = []
    for fold in folds:
        for k in range(st.N_TUNINGS):
            path = ROOT / st.tuning_file(fold.apso, k)
            if not path.is_file():
                continue
            doc = json.loads(path.read_text())
            params = doc["filters"]["apso"]
            ends = bound_hits("apso", params, doc=doc)
            if ends:
                out.append(f"- `{fold.label}`, tuning {k}: " + ", ".join(
                    f"{key} = {params[key]:.3g} at the {end} end" for key, end in ends.items()))
    if not out:
        return []
    return ["Multipliers at an end of their search range (the optimum may lie outside "
            "what was searched):", "", *out, ""]


def section(frame: tuple) -> list:
    """The markdown lines of the held-out section (``frame``: :func:`heldout_frame`)."""
    df, best = frame
    filters = ["ekf", "huber", TUNED_LABEL, BEST_LABEL, APSO_LABEL]
    chosen = "; ".join(f"{fold}: `{name}`" for fold, name in best.items())
    head = ["fold", "held out", "fuzzy − best, horizontal RMS (m) [95 % CI]",
            "fuzzy vs best (positive = fuzzy smaller)", "trajectories"]
    return ["### Trained on four A-KIT trajectories, judged on the other four", "",
            "The fuzzy DVL R-scaling study (`studies/paper004_fuzzy.toml`, trained on "
            "trajectories 1–4; `paper004_fuzzy_rev.toml`, trained on 5–8; 150 TPE trials "
            "each), the classical filters tuned with the same budget, pruner and objective "
            "on the same four (`studies/paper004_baselines.toml` / `_rev`: `ekf-tuned`, "
            "`sage-husa-tuned`, `vb-tuned`, `huber-tuned`, 150 TPE trials each) and the APSO "
            "of the Q/R multipliers (`studies/paper004_apso.toml` / `_rev`: 10 particles × "
            "15 iterations, inertia 0.9 → 0.4) run with what they found on the trajectories "
            f"they did not see. The best equally tuned classical filter per fold ({chosen}) "
            "is chosen on the held-out trajectories by the studies' objective (which favours "
            "it). Horizontal RMS (m) per held-out trajectory; pooled over the eight (each "
            "held out once); paired change vs the EKF, positive = smaller error:", "",
            heldout_table(df, filters=filters), "",
            "End error as % of the distance travelled:", "",
            heldout_table(df, "end_pos_h_pct", filters), "",
            "The fuzzy controller against the best equally tuned classical filter, paired "
            "on the held-out trajectories (four per fold: a wide CI, Student t with 3 "
            "degrees of freedom):", "",
            render(head, paired_best(df), markdown=True), "",
            "Per fold (horizontal RMS, paired change vs the EKF on the fold's four held-out "
            "trajectories):", "", fold_table(df), ""]
