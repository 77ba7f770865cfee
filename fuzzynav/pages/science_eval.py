"""Held-out runs of ``docs/science.md``: every tuning's filters on every held-out run.

:func:`held_out_runs` gives one row per (tuning seed, scenario, seed, filter) with the RMS
metrics; the filters that are not tuned (``ekf``, ``sage-husa``, ``vb``, ``fakf``,
``ekf-true``: the fair study's compared filters that no study tunes) are run once and repeated under every tuning seed, so each tuning's table is
complete.  :func:`curve_points` scores the best trial of the first ``n`` trials of a study
on the held-out runs (training score beside), for the budget curves.
"""
from __future__ import annotations

import json
import tempfile
from pathlib import Path

import pandas as pd

from fuzzynav.pages.science_tuning import (baseline_params_at, fuzzy_systems_at)

__all__ = ["fuzzy_rows", "named_rows", "held_out_runs", "curve_points"]


def fuzzy_rows(cfg, systems, runs, label, cache) -> pd.DataFrame:
    """Rows of the fuzzy systems ``systems`` of study ``cfg`` on ``runs``, labelled ``label``."""
    from fuzzynav.tuning.evaluate import run_table
    from fuzzynav.tuning.objective import CANDIDATE, Evaluator

    df = run_table(Evaluator(cfg, cache), systems, runs)
    return df.assign(filter=df["filter"].replace({CANDIDATE: label}))


def named_rows(cfg, specs: dict, runs, cache) -> pd.DataFrame:
    """Rows of named filters (label -> ``NAME`` or ``NAME@FILE``)."""
    from fuzzynav.tuning.evaluate import run_table
    from fuzzynav.tuning.objective import Evaluator

    df = run_table(Evaluator(cfg, cache), {}, runs, tuple(specs.values()))
    return df.assign(filter=df["filter"].replace({v: k for k, v in specs.items()}))


def held_out_runs(tunings, runs, cache, trials=None) -> pd.DataFrame:
    """Every filter of every tuning on ``runs`` (``(scenario, seed)`` pairs); each fuzzy
    design is the best of its study's first ``trials`` trials (None: of all)."""
    from fuzzynav.filters.baselines import TUNED

    frames = []
    cfg0 = next(iter(tunings[0].fuzzy.values()))[0]  # the fair study: its compared filters
    tuned = [n for n in cfg0.compare if n in TUNED]
    untuned = named_rows(cfg0, {n: n for n in cfg0.compare if n not in TUNED}, runs, cache)
    for t in tunings:
        for label, (cfg, study) in t.fuzzy.items():
            systems, _ = fuzzy_systems_at(cfg, study, trials)
            frames.append(fuzzy_rows(cfg, systems, runs, label, cache)
                          .assign(tuning_seed=t.seed))
        specs = {n: f"{n}@{t.params}" for n in tuned}
        frames.append(named_rows(cfg0, specs, runs, cache).assign(tuning_seed=t.seed))
        frames.append(untuned.assign(tuning_seed=t.seed))
    return pd.concat(frames, ignore_index=True)


def _params_file(name: str, params: dict, directory: Path) -> Path:
    path = directory / f"{name}.json"
    path.write_text(json.dumps({"format": "fuzzynav-baselines", "version": 1,
                                "filters": {name: params}}))
    return path


def curve_points(tunings, labels, budgets, runs, cache) -> pd.DataFrame:
    """Per tuning, label and budget ``n``: the best of the first ``n`` trials, its training
    score and its held-out runs' score against ``ekf`` (mean over ``runs``).

    A budget beyond a study's trials is left out (only the continued studies reach it)."""
    from fuzzynav.pages.scores import scores_to

    cfg0 = next(iter(tunings[0].fuzzy.values()))[0]
    ekf = named_rows(cfg0, {"ekf": "ekf"}, runs, cache)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for t in tunings:
            for label in labels:
                study = t.fuzzy[label][1] if label in t.fuzzy else t.baselines[label]
                n_have = len(study.get_trials(deepcopy=False))
                for n in budgets:
                    if n > n_have:
                        continue
                    if label in t.fuzzy:
                        cfg = t.fuzzy[label][0]
                        systems, train = fuzzy_systems_at(cfg, study, n)
                        df = fuzzy_rows(cfg, systems, runs, label, cache)
                    else:
                        params, train = baseline_params_at(t, label, n)
                        path = _params_file(label, params, Path(tmp))
                        df = named_rows(cfg0, {label: f"{label}@{path}"}, runs, cache)
                    s = scores_to(pd.concat([df, ekf]), "ekf")
                    held = s[s["filter"] == label]["score"]
                    rows.append({"tuning_seed": t.seed, "filter": label, "trials": n,
                                 "train_score": train, "held_out_score": float(held.mean()),
                                 "runs": int(held.size)})
    return pd.DataFrame(rows)
