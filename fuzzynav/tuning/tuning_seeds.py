"""Tuning variance: one study file tuned with several independent study (sampler) seeds.

``fuzzynav study run FILE --study-seeds N`` runs the file's study ``N`` times, with the
sampler seeds ``[study] seed + 0, ..., + N-1`` (Optuna's TPE/CMA-ES/random sampler seed, the
PSO swarm's seed), each into its own Optuna study and storage named ``<name>-seed<S>`` (the
default journal ``<name>-seed<S>.journal`` next to the file; a baseline study's parameter
file ``<out stem>-seed<S>.json``).  Everything else -- training and test runs, search
space, budget -- is the file's, so the tunings differ only by the search's randomness, and
the same seed reproduces the same trials.

``fuzzynav study report FILE --study-seeds N`` writes each tuning's report into
``<out>/seed<S>/`` and the spread between tunings into ``<out>/tunings.md`` and
``tunings.csv`` (:func:`tuning_spread`; the science page can call it on its own tables).
The paired tests are reported per tuning (each tuning against the EKF and the compared
filters on the same test runs), not pooled over tunings.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from fuzzynav.errors import FuzzynavError
from fuzzynav.metrics import improvement_ci, mean_ci

__all__ = ["study_seeds", "seeded_plan", "tunings", "tuned_names", "tuning_spread",
           "format_spread", "write_spread_report"]


def study_seeds(plan, n: int) -> list:
    """The ``n`` sampler seeds of a plan's tunings: its ``[study] seed`` plus 0 .. n-1."""
    base = plan.config(plan.parts()[0]).seed if plan.parts() else 0
    return [base + k for k in range(int(n))]


def _seeded_cfg(cfg, seed: int):
    """The study config of one tuning: name ``<name>-seed<S>``, sampler seed ``S``."""
    return replace(cfg, name=f"{cfg.name}-seed{seed}", seed=int(seed))


def seeded_plan(plan, seed: int):
    """The plan of ``plan``'s file tuned with sampler seed ``seed`` (a new plan of the same
    kind; its studies, storages and outputs are named ``...-seed<S>``).

    Raises
    ------
    FuzzynavError
        For a kind without tuning seeds (the alignment filter's rules).
    """
    from fuzzynav.tuning.kinds.baseline_studies import BaselinePlan
    from fuzzynav.tuning.kinds.fuzzy import FuzzyPlan

    if isinstance(plan, FuzzyPlan):
        out = FuzzyPlan(_seeded_cfg(plan.cfg, seed), plan.cache_dir)
    elif isinstance(plan, BaselinePlan):
        b = plan.bcfg
        out_file = b.out.with_name(f"{b.out.stem}-seed{seed}{b.out.suffix}")
        out = BaselinePlan(replace(b, study=_seeded_cfg(b.study, seed), out=out_file),
                           plan.cache_dir)
    else:
        raise FuzzynavError(f"{plan.path}: --study-seeds applies to fuzzy and baseline "
                            f"studies, not to a {plan.kind!r} study")
    out.study_seed = int(seed)
    return out


def tunings(plan, n) -> list:
    """``[(seed, plan), ...]`` of ``n`` tunings (``n`` None: ``[(None, plan)]``, the file's
    one study as named in it)."""
    if n is None:
        return [(None, plan)]
    return [(s, seeded_plan(plan, s)) for s in study_seeds(plan, n)]


def tuned_names(plan) -> list:
    """The filters a plan tunes, as its report's run tables name them."""
    from fuzzynav.tuning.objective import CANDIDATE

    return list(plan.bcfg.tune) if plan.kind == "baselines" else [CANDIDATE]


def tuning_spread(tables: dict, candidates) -> tuple:
    """The spread between tunings of their held-out scores.

    Parameters
    ----------
    tables : dict
        Tuning (sampler) seed -> that tuning's held-out run table (one row per (scenario,
        seed, filter) with a ``score`` column, :func:`fuzzynav.tuning.evaluate.run_table`).
    candidates : sequence of str
        The tuned filters (``"tuned"`` for a fuzzy study, the ``-tuned`` names of a
        baseline study).

    Returns
    -------
    (pandas.DataFrame, pandas.DataFrame)
        Per tuning and candidate: ``tuning_seed, filter, score`` (mean over the held-out
        runs), ``score_ci`` (Student-t 95 % half width over those runs: the spread between
        test seeds), ``runs`` and ``change_pct`` [``change_lo``, ``change_hi``] (that
        tuning's paired change against the baseline, score 1 on every run:
        :func:`~fuzzynav.metrics.improvement_ci`, positive = smaller error); and per candidate across tunings: ``tunings, mean, min,
        max, std`` (sample std, NaN from one tuning) of the per-tuning scores.
    """
    rows = []
    for seed, df in tables.items():
        for cand in candidates:
            x = df.loc[df["filter"] == cand, "score"].to_numpy(float) if "score" in df \
                else np.array([])
            est, imp = mean_ci(x), improvement_ci(np.ones_like(x), x)
            rows.append({"tuning_seed": seed, "filter": cand, "score": est.mean,
                         "score_ci": est.mean - est.lo if est.n >= 2 else np.nan,
                         "runs": est.n, "change_pct": imp.mean, "change_lo": imp.lo,
                         "change_hi": imp.hi})
    per = pd.DataFrame(rows, columns=["tuning_seed", "filter", "score", "score_ci", "runs",
                                      "change_pct", "change_lo", "change_hi"])
    across = []
    for cand, sub in per.groupby("filter", sort=False):
        s = sub["score"].to_numpy(float)
        s = s[np.isfinite(s)]
        across.append({"filter": cand, "tunings": s.size,
                       "mean": s.mean() if s.size else np.nan,
                       "min": s.min() if s.size else np.nan,
                       "max": s.max() if s.size else np.nan,
                       "std": s.std(ddof=1) if s.size >= 2 else np.nan})
    return per, pd.DataFrame(across, columns=["filter", "tunings", "mean", "min", "max", "std"])


def format_spread(per: pd.DataFrame, across: pd.DataFrame) -> str:
    """Markdown of :func:`tuning_spread`'s two tables."""
    from fuzzynav.report import render

    rows = [[int(r.tuning_seed), r.filter, int(r.runs),
             f"{r.score:.3f}" + (f" ± {r.score_ci:.3f}" if np.isfinite(r.score_ci) else ""),
             f"{r.change_pct:+.1f} % [{r.change_lo:+.1f}, {r.change_hi:+.1f}]"]
            for r in per.itertuples()]
    one = render(["tuning seed", "filter", "held-out runs", "held-out score",
                  "vs baseline (paired)"], rows, markdown=True)
    rows = [[r.filter, int(r.tunings), *(f"{getattr(r, c):.3f}" if np.isfinite(getattr(r, c))
                                         else "—" for c in ("mean", "min", "max", "std"))]
            for r in across.itertuples()]
    two = render(["filter", "tunings", "mean", "min", "max", "std"], rows, markdown=True)
    return one + "\n\nAcross tunings (of the per-tuning held-out scores):\n\n" + two


def write_spread_report(plan, seeds, out, candidates) -> Path:
    """Write ``tunings.md`` and ``tunings.csv`` into ``out`` from the held-out rows of the
    per-tuning reports' ``out/seed<S>/runs.csv``; returns the Markdown's path."""
    from fuzzynav.fileio import write_atomic

    out = Path(out)
    tables = {}
    for seed in seeds:
        runs = out / f"seed{seed}" / "runs.csv"
        if not runs.is_file():
            raise FuzzynavError(f"{runs}: no held-out table of tuning seed {seed} (was its "
                                "report evaluated?)")
        df = pd.read_csv(runs)
        tables[seed] = df[df["set"] == "test"]
    per, across = tuning_spread(tables, candidates)
    text = (f"# Tuning variance of `{plan.name}`\n\n{len(seeds)} tunings (sampler seeds "
            f"{', '.join(map(str, seeds))}); held-out score = mean ratio to the baseline "
            "over the test runs (± Student-t 95 % CI over those runs). Each tuning's paired "
            "tests against the EKF and the compared filters are in its own report "
            "(`seed<S>/report.md`).\n\n" + format_spread(per, across) + "\n")
    write_atomic(out / "tunings.csv", lambda tmp: per.to_csv(tmp, index=False))
    write_atomic(out / "tunings.md", lambda tmp: Path(tmp).write_text(text))
    return out / "tunings.md"
