"""Scores of the science page: each run's RMS ratios to a reference filter, the paired
difference of two filters per scenario with its 95 % CI, and the markdown built from them."""
from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from fuzzynav.errors import InputFileError
from fuzzynav.metrics import mean_ci
from fuzzynav.report import ci_cell, diff_cell

__all__ = ["FUZZY", "NOT_CLASSICAL", "MIN_EFFECT", "METRICS", "scores_to", "cell", "ratio_table",
           "is_classical", "best_classical", "best_on_training", "paired", "verdict", "sentence",
           "comparison_lines"]

FUZZY = "fuzzy-tuned"
REF, ORACLE = "ekf-tuned", "ekf-true"
#: filters that are neither fuzzy nor told the truth: the "best classical baseline" pool
NOT_CLASSICAL = (FUZZY, "fakf", "fuzzy", ORACLE)
#: the smallest paired score difference called a win or a loss (0.5 % of the reference's
#: error): a supervisor that stays at its parent differs by ~1e-5 with a CI just as narrow,
#: and a CI that excludes zero is then no result
MIN_EFFECT = 0.005
METRICS = ("rms_pos_m", "rms_vel_mps", "rms_att_deg")


def scores_to(df: pd.DataFrame, ref: str, metrics=METRICS, weights=None) -> pd.DataFrame:
    """Per run and filter: the mean over ``metrics`` (pos/vel/att) of the RMS ratio to
    ``ref`` on the same run, weighted by ``weights`` (one per metric; default equal), as a
    study's objective weighs its groups."""
    key = ["scenario", "seed"]
    metrics = list(metrics)
    weights = [1.0] * len(metrics) if weights is None else [float(w) for w in weights]
    if len(weights) != len(metrics) or sum(weights) <= 0:
        raise ValueError(f"weights {weights} do not fit the metrics {metrics}")
    base = df[df["filter"] == ref][[*key, *metrics]]
    out = df[[*key, "filter", *metrics]].merge(base, on=key, suffixes=("", "_ref"))
    ratios = [w * out[m] / out[m + "_ref"] for m, w in zip(metrics, weights)]
    out["score"] = sum(ratios) / sum(weights)
    return out[["scenario", "seed", "filter", "score"]]


def cell(values) -> str:
    return ci_cell(values, ".2f")


def ratio_table(scores: pd.DataFrame, order, scenarios) -> list:
    """Markdown rows: filter x scenario, mean score (95 % CI over seeds)."""
    lines = ["| filter | " + " | ".join(f"`{s}`" for s in scenarios) + " |",
             "|---|" + "---|" * len(scenarios)]
    for f in order:
        sub = scores[scores["filter"] == f]
        cells = [cell(sub[sub["scenario"] == s]["score"]) for s in scenarios]
        lines.append(f"| {f} | " + " | ".join(cells) + " |")
    return lines


def is_classical(names: pd.Series) -> pd.Series:
    """Neither fuzzy (``fakf``, ``fuzzy*``) nor told the truth (``ekf-true``)."""
    return ~names.isin(NOT_CLASSICAL) & ~names.str.startswith("fuzzy")


def best_classical(scores: pd.DataFrame, scenario: str, pool=None) -> str:
    """The classical filter with the lowest mean score on ``scenario``: among ``pool`` (the
    filter names allowed, e.g. the equally tuned ones) or else among every filter
    :func:`is_classical` calls classical."""
    chosen = is_classical(scores["filter"]) if pool is None else scores["filter"].isin(pool)
    sub = scores[(scores["scenario"] == scenario) & chosen]
    if sub.empty:
        raise ValueError(f"no classical filter of {sorted(pool or [])} ran on {scenario!r}")
    return sub.groupby("filter")["score"].mean().idxmin()


def best_on_training(path, pool) -> tuple:
    """The filter of ``pool`` with the lowest training score in a baseline study's output
    (``train_score`` of ``studies/*_baselines.json``: the objective on the training runs,
    the same for every filter of the study), and every filter of ``pool`` -> its score.

    Raises
    ------
    InputFileError
        The file has no ``train_score`` for a filter of ``pool``.
    """
    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    # a pool entry may name the file (``NAME@FILE``): the study's key is the bare name
    train = {n: (doc.get("train_score") or {}).get(n.split("@", 1)[0]) for n in pool}
    missing = [n for n in pool if not isinstance(train[n], (int, float))]
    if missing:
        raise InputFileError(path, "$.train_score", f"no score for {', '.join(missing)}; "
                             "run the baseline study that tunes it")
    best = min(pool, key=lambda n: train[n])
    return best, {n: float(train[n]) for n in pool}


def paired(scores: pd.DataFrame, scenario: str, a: str, b: str):
    """Mean and 95 % CI of ``score(a) - score(b)`` over the scenario's seeds."""
    sub = scores[scores["scenario"] == scenario].pivot(index="seed", columns="filter",
                                                       values="score")
    return mean_ci((sub[a] - sub[b]).to_numpy())


def verdict(est) -> str:
    """``wins against`` / ``draws with`` / ``loses to`` by the 95 % CI of a paired difference
    (negative favours the first filter) that also exceeds :data:`MIN_EFFECT` in its mean;
    with one pair there is no CI to tell."""
    if est.n < 2:
        return "is not told apart (one seed) from"
    if est.hi < 0 and est.mean <= -MIN_EFFECT:
        return "wins against"
    if est.lo > 0 and est.mean >= MIN_EFFECT:
        return "loses to"
    return "draws with"


def sentence(scenario: str, a: str, b: str, est, unit: str = "seeds") -> str:
    """One sentence of a paired comparison; ``unit`` names the pairs (seeds, trajectories)."""
    return (f"On `{scenario}`, {a} **{verdict(est)}** {b}: score difference "
            f"{est.mean:+.3f} (95 % CI {est.lo:+.3f} to {est.hi:+.3f}, {est.n} {unit}).")


def comparison_lines(scores: pd.DataFrame, scenarios, fuzzy: str = FUZZY) -> tuple:
    """Table rows and one sentence per scenario: the fuzzy design ``fuzzy`` vs the best
    classical baseline and vs the tuned constant-noise EKF."""
    rows = ["| scenario | best classical | fuzzy − best (95 % CI) | verdict | "
            "fuzzy − ekf-tuned (95 % CI) | verdict |", "|---|---|---|---|---|---|"]
    text, tally = [], {"wins against": 0, "draws with": 0, "loses to": 0}
    for s in scenarios:
        best = best_classical(scores, s)
        vs_best, vs_ref = paired(scores, s, fuzzy, best), paired(scores, s, fuzzy, REF)
        tally[verdict(vs_best)] = tally.get(verdict(vs_best), 0) + 1
        rows.append(f"| `{s}` | {best} | {diff_cell(vs_best)} | {verdict(vs_best)} | "
                    f"{diff_cell(vs_ref)} | {verdict(vs_ref)} |")
        text.append("- " + sentence(s, f"`{fuzzy}`", f"`{best}`", vs_best))
    return rows, text, tally
