"""``fuzzynav study report``: what a study found, as a Markdown page with figures.

Writes into a directory: ``trials.csv`` (pandas table of every trial), ``history.png``
(optimisation history), ``importances.png`` (PED-ANOVA importances -- Optuna's default;
its fANOVA needs scikit-learn -- of the structural
parameters), ``pareto.png`` and a table of the Pareto front (multi-objective studies,
:mod:`fuzzynav.tuning.pareto`), ``mf_<controller>.png`` (the tuned
membership functions), ``report.md`` (summary, rule tables, the train/test table beside the
EKF, the paper's rules and the compared baselines).  All files are written complete into a
temporary directory and then moved into place together: a read-only directory, a full disk
or an error part-way is one :class:`~fuzzynav.errors.OutputError` line, with the files of an
earlier report unchanged and none of the new ones published.
"""
from __future__ import annotations

import itertools
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from fuzzynav import plots
from fuzzynav.fuzzy.describe import rule_markdown
from fuzzynav.errors import FuzzynavError
from fuzzynav.fileio import staged, write_atomic
from fuzzynav.tuning.evaluate import format_summary, run_table, scenario_section
from fuzzynav.tuning.export import choose_trial, systems_of
from fuzzynav.tuning.study_config import GROUP_METRICS
from fuzzynav.tuning import pareto
from fuzzynav.tuning.objective import CANDIDATE, Evaluator, weighted_score
from fuzzynav.tuning.optuna_study import best_trials

__all__ = ["plt", "trials_frame", "write_report"]

plt = plots.plt


def trials_frame(study) -> pd.DataFrame:
    """Trials with state, values, ratios and the structural parameters."""
    df = study.trials_dataframe(attrs=("number", "state", "value", "values", "duration",
                                       "user_attrs"))
    keep = [c for c in df.columns if not c.startswith("user_attrs_") or
            c in ("user_attrs_n_runs", "user_attrs_worker", "user_attrs_retry_of")]
    out = df[keep].copy()
    trials = study.get_trials(deepcopy=False)
    ratios = [t.user_attrs.get("ratios") or {} for t in trials]
    for g in ("pos", "vel", "att"):
        out[f"{g}_ratio"] = [r.get(g, np.nan) for r in ratios]
    for p in _structural_params(trials):
        out[p] = [t.params.get(p) for t in trials]
    return out


def _structural_params(trials) -> list:
    """Partition counts, windows and output-range ends (not the hundreds of rule cells)."""
    return sorted({p for t in trials for p in t.params
                   if ".n." in p or p.endswith((".window", ".out_hi", ".out_lo"))})


def _score(cfg, t) -> float:
    """A finished trial's single score (multi-objective: the weighted mean of its ratios)."""
    if not cfg.multi_objective:
        return t.value
    if cfg.robust:  # the mean score over the training runs
        return t.values[0]
    return weighted_score(dict(zip(GROUP_METRICS, t.values)), cfg.weights)


def _history(study, cfg, path):
    vals = [(t.number, _score(cfg, t)) for t in study.trials if t.values is not None]
    if not vals:
        return None
    n, v = np.array(vals).T
    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.plot(n, v, ".", alpha=0.5, label="trial")
    ax.plot(n, np.minimum.accumulate(v), "-", label="best so far")
    ax.axhline(1.0, color="k", lw=0.8, ls="--", label="EKF")
    ax.set_yscale("log")
    ax.set_xlabel("trial")
    ax.set_ylabel("score (ratio to EKF)" + (", weighted" if cfg.multi_objective else ""))
    ax.legend()
    fig.tight_layout()
    return plots.save(fig, path)


def _importances(study, cfg, path):
    import optuna

    params = _structural_params(study.trials)
    done = [t for t in study.trials if t.values is not None and all(p in t.params for p in params)]
    if len(params) < 2 or len(done) < 10:
        return None
    try:
        with warnings.catch_warnings():  # "importances of low target values": as wanted
            warnings.simplefilter("ignore", UserWarning)
            imp = optuna.importance.get_param_importances(study, params=params,
                                                          target=lambda t: _score(cfg, t))
    except (ValueError, RuntimeError):
        return None
    fig, ax = plt.subplots(figsize=(7, 0.4 * len(imp) + 1))
    ax.barh(list(imp)[::-1], list(imp.values())[::-1])
    ax.set_xlabel("importance (PED-ANOVA)")
    fig.tight_layout()
    return plots.save(fig, path)


def _pareto(study, cfg, path):
    if not cfg.multi_objective:
        return None
    if cfg.robust:
        return pareto.robust_figure(study, best_trials(study, cfg), path)
    pts = np.array([t.values for t in study.trials if t.values is not None])
    front = np.array([t.values for t in best_trials(study, cfg)])
    if pts.size == 0:
        return None
    fig, axs = plt.subplots(1, 3, figsize=(12, 3.5))
    for ax, (i, j) in zip(axs, itertools.combinations(range(3), 2)):
        ax.plot(pts[:, i], pts[:, j], ".", alpha=0.3)
        if front.size:
            ax.plot(front[:, i], front[:, j], "o", mfc="none")
        names = ("pos", "vel", "att")
        ax.set_xlabel(f"{names[i]} ratio")
        ax.set_ylabel(f"{names[j]} ratio")
    fig.tight_layout()
    return plots.save(fig, path)


def _best_trial_section(cfg, trial, out, cache_dir, evaluate) -> list:
    systems = systems_of(cfg, trial)
    lines = ["", f"## Best trial: {trial.number}", "",
             f"Score {trial.values if cfg.multi_objective else trial.value} "
             f"(ratios to {cfg.baseline}: {trial.user_attrs.get('ratios')}).", ""]
    for name, fis in systems.items():
        p = plots.save(plots.membership_functions(fis, name), out / f"mf_{name}.png")
        lines += [f"### Controller `{name}`", "", f"![mf_{name}]({p.name})", "",
                  rule_markdown(fis), "", f"DoM window: {fis.binding.get('window')} epochs.", ""]
    if evaluate:
        ev = Evaluator(cfg, cache_dir)
        compare = tuple(dict.fromkeys(cfg.compare))
        train = run_table(ev, systems, cfg.train, compare)
        test = run_table(ev, systems, cfg.test, compare)
        runs = pd.concat([train.assign(set="train"), test.assign(set="test")])
        write_atomic(out / "runs.csv", lambda tmp: runs.to_csv(tmp, index=False))
        lines += ["## Train and held-out test (ratio of RMS error to the EKF; < 1 is better)",
                  "", "```", format_summary(train, test), "```", ""]
        lines += scenario_section(train, test, [CANDIDATE], cfg.baseline)
    return lines


def write_report(cfg, study, out_dir, cache_dir=None, evaluate: bool = True) -> Path:
    """Write the report directory; returns the path of ``report.md``.

    Every file is built in a temporary directory inside ``out_dir`` and all are moved into
    place at the end (``report.md`` last), so a failure part-way leaves ``out_dir`` as it
    was (see :func:`fuzzynav.fileio.staged`).
    """
    with staged(out_dir, "study report", last=("report.md",)) as tmp:
        _write_files(cfg, study, tmp, cache_dir, evaluate)
    return Path(out_dir) / "report.md"


def _write_files(cfg, study, out: Path, cache_dir, evaluate: bool) -> None:
    df = trials_frame(study)
    write_atomic(out / "trials.csv", lambda tmp: df.to_csv(tmp, index=False))
    figs = [_history(study, cfg, out / "history.png"),
            _importances(study, cfg, out / "importances.png"),
            _pareto(study, cfg, out / "pareto.png")]
    states = df["state"].value_counts().to_dict() if "state" in df else {}
    lines = [f"# Study `{cfg.name}`", "", cfg.description, "",
             f"Sampler `{cfg.sampler}`, pruner `{cfg.pruner}`, "
             f"{'multi' if cfg.multi_objective else 'single'}-objective; trials: "
             + (", ".join(f"{k} {v}" for k, v in states.items()) or "none") + ".", ""]
    lines += [f"![{p.stem}]({p.name})" for p in figs if p is not None]
    lines += pareto.front_section(study, cfg, best_trials(study, cfg)
                                  if cfg.multi_objective else [])
    try:
        trial = choose_trial(study, cfg)
    except FuzzynavError as exc:  # only pruned, failed or running trials so far
        lines += ["", f"No best trial yet: {exc}.", ""]
    else:
        lines += _best_trial_section(cfg, trial, out, cache_dir, evaluate)
    text = "\n".join(lines) + "\n"
    write_atomic(out / "report.md", lambda tmp: Path(tmp).write_text(text))
