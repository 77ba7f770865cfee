"""Multi-objective studies: accuracy against robustness, and the Pareto front in reports.

A study with ``objective = "robust"`` minimises two values per trial:

* **accuracy** -- the mean score over all training runs (what a single-objective study
  minimises);
* **robustness** -- the mean score of the *worst* training scenario (scores averaged over
  its seeds first, so one unlucky seed does not decide it).

No trial is better on both when the controller that wins on average is beaten on one
scenario: the trials no other trial dominates form the Pareto front, which
``fuzzynav study report`` prints as a table (and draws, ``pareto.png``).  The three-group
``objective = "multi"`` studies get the same table of their front.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from fuzzynav import plots

__all__ = ["ROBUST_NAMES", "scenario_label", "accuracy_and_worst", "objective_names",
           "front_table", "front_section", "robust_figure"]

ROBUST_NAMES = ("accuracy (mean score)", "robustness (worst scenario)")


def scenario_label(scenario) -> str:
    """A short name of a training scenario: a built-in name, or a TOML file's stem."""
    text = str(scenario)
    return Path(text).stem if text.endswith(".toml") else text


def accuracy_and_worst(trial, scenarios, scores) -> tuple:
    """The two objectives of a ``robust`` study from one trial's run scores.

    Parameters
    ----------
    trial : optuna.Trial
        Gets the user attribute ``scenario_scores`` (scenario label -> mean score).
    scenarios : sequence
        The scenario of each scored run.
    scores : sequence of float
        Each run's score (ratio to the baseline, lower is better).

    Returns
    -------
    (float, float)
        The mean over the runs, and the largest per-scenario mean.
    """
    per = {}
    for scenario, score in zip(scenarios, scores):
        per.setdefault(scenario_label(scenario), []).append(float(score))
    means = {k: float(np.mean(v)) for k, v in per.items()}
    trial.set_user_attr("scenario_scores", means)
    return float(np.mean(scores)), max(means.values())


def objective_names(cfg) -> tuple:
    """Names of a multi-objective study's values, in order."""
    if cfg.robust:
        return ROBUST_NAMES
    from fuzzynav.tuning.study_config import GROUP_METRICS

    return tuple(f"{g} ratio" for g in GROUP_METRICS)


def _worst_scenario(trial) -> str:
    per = trial.user_attrs.get("scenario_scores") or {}
    return max(per, key=per.get) if per else "-"


def front_table(cfg, front) -> list:
    """Markdown lines: one row per Pareto-optimal trial, best accuracy first."""
    names = objective_names(cfg)
    head = ["trial", *names] + (["worst scenario"] if cfg.robust else [])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for t in sorted(front, key=lambda t: tuple(t.values)):
        cells = [str(t.number), *(f"{v:.3f}" for v in t.values)]
        if cfg.robust:
            cells.append(f"`{_worst_scenario(t)}`")
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def front_section(study, cfg, front) -> list:
    """The report's Pareto section (empty for a single-objective study); ``front``: the
    Pareto-optimal trials (:func:`fuzzynav.tuning.optuna_study.best_trials`)."""
    if not cfg.multi_objective:
        return []
    lines = ["", "## Pareto front", ""]
    if not front:
        return lines + ["No complete trial has run every training run yet.", ""]
    what = ("the mean score over the training runs against the mean score of the worst "
            "training scenario" if cfg.robust else "the three group ratios")
    lines += [f"{len(front)} of {len(study.trials)} trials are not dominated on {what} "
              f"(lower is better; `fuzzynav study export --pareto K` exports row K, "
              f"counted from 0).", "", *front_table(cfg, front), ""]
    return lines


def robust_figure(study, front, path):
    """Accuracy against robustness of every finished trial, the ``front`` joined; the path."""
    pts = np.array([t.values for t in study.trials if t.values is not None], dtype=float)
    if pts.size == 0:
        return None
    front = np.array(sorted(tuple(t.values) for t in front), dtype=float)
    fig, ax = plots.plt.subplots(figsize=(5.5, 4))
    ax.plot(pts[:, 0], pts[:, 1], ".", alpha=0.4, label="trial")
    if front.size:
        ax.plot(front[:, 0], front[:, 1], "o-", mfc="none", label="Pareto front")
    lo = float(np.nanmin(pts[:, 0]))
    ax.axline((lo, lo), slope=1.0, color="k", lw=0.6, ls=":", label="worst = mean")
    ax.set_xlabel(ROBUST_NAMES[0])
    ax.set_ylabel(ROBUST_NAMES[1])
    ax.legend()
    fig.tight_layout()
    return plots.save(fig, path)
