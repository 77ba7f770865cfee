"""Baseline studies: tune the classical filters with the same budget as a fuzzy study.

A baseline study file has the ``[study]``, ``[objective]``, ``[train]`` and ``[test]``
tables of a fuzzy study (``docs/studies.md``) and, instead of ``[[controllers]]``::

    [baselines]
    tune = ["ekf-tuned", "sage-husa-tuned", "vb-tuned", "huber-tuned",
            "strong-tracking-tuned", "als"]
    out = "paper000_baselines.json"     # relative to the study file

Each tuned filter (:data:`fuzzynav.filters.baselines.TUNED`) gets its own Optuna study
``<name>.<filter>`` in the same storage, run by the one study driver (workers, reaping,
resume: :mod:`fuzzynav.tuning.kinds.baseline_studies`), with the configured sampler, pruner and number of
trials, scored exactly as a fuzzy candidate (:class:`~fuzzynav.tuning.objective.Evaluator`:
weighted mean of RMS ratios to the baseline filter on the training runs).  ``als`` is not
searched: its Q and R come from autocovariance least squares on the training runs
(:mod:`fuzzynav.tuning.als_fit`).  The best parameters of every filter are written to
``out``, the file the named filters read (``ekf-tuned@FILE``).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from optuna.trial import TrialState

from fuzzynav.errors import FuzzynavError
from fuzzynav.experiment import filter_context
from fuzzynav.fileio import study_output, write_atomic
from fuzzynav.filters import measurements
from fuzzynav.filters.baselines import Q_FIELDS, TUNED
from fuzzynav.filters.multipliers import R_ALL, R_PREFIX
from fuzzynav.filters.params_file import PARAMS_FORMAT, PARAMS_VERSION, check_params, \
    known_keys
from fuzzynav.sim.tomltable import Table, read_toml, with_path
from fuzzynav.tuning.baseline_ranges import parse_ranges, recorded, with_ranges
from fuzzynav.tuning.study_config import study_config_from_dict
from fuzzynav.tuning.objective import TrialObjective

__all__ = ["TUNABLE", "Q_BOUNDS", "R_BOUNDS", "SPACES", "BaselineConfig",
           "load_baseline_config", "training_channels", "space_of", "default_space", "suggest",
           "run_params", "BaselineObjective", "sub_config", "best_params", "write_params",
           "train_score", "bound_hits"]

#: filters a baseline study can tune: the searched ones, the ALS estimate and paper 004's
#: APSO (the ``apso`` filter's Q/R multipliers, best with ``sampler = "pso"``)
TUNABLE = tuple(TUNED) + ("apso",)
#: bounds of the searched parameters: (low, high, log scale)
Q_BOUNDS = (0.1, 10.0, True)
R_BOUNDS = (0.1, 100.0, True)
SPACES = {
    "sage-husa-tuned": {"b": (0.9, 0.999, False), "floor": (0.01, 1.0, True),
                        "cap": (1.0, 1000.0, True)},
    "vb-tuned": {"rho": (0.9, 0.999, False), "iterations": (1, 5, "int")},
    "huber-tuned": {"gamma": (0.5, 10.0, True)},
    # paper 004 says "Q and R" without listing the entries: the attitude and velocity rows
    # of Q (ARW/VRW densities) and every measurement's R (factors on the variances)
    "apso": {"q_att": (0.01, 100.0, True), "q_vel": (0.01, 100.0, True),
             "r_all": (0.1, 100.0, True)},
    # the cap is searched too: uncapped (Zhou's form) it diverges on paper000, where the
    # compass's H P- H^T is far below its R and the innovation average alone gives huge factors
    "strong-tracking-tuned": {"rho": (0.5, 0.99, False), "beta": (1.0, 20.0, True),
                              "lam_max": (1.01, 100.0, True)},
}


def bound_hits(name: str, params: dict, rel: float = 0.01, doc=None) -> dict:
    """Parameter -> ``"lower"``/``"upper"`` for each of ``params`` (tuned values of baseline
    ``name``) within ``rel`` of its search range's end (on the log scale where searched on
    it): the optimum may lie outside what was searched.  ``doc``: the parameter file, whose
    ``space`` says the ranges searched (else the defaults).  Unsearched keys are left out."""
    space = recorded(doc or {}, name, default_space(name))
    out = {}
    for key, value in params.items():
        lo, hi, scale = space.get(key, (None, None, None))
        if lo is None:
            continue
        f = (math.log(value / lo) / math.log(hi / lo) if scale is True
             else (value - lo) / (hi - lo))
        if f <= rel:
            out[key] = "lower"
        elif f >= 1.0 - rel:
            out[key] = "upper"
    return out


@dataclass(frozen=True)
class BaselineConfig:
    """A parsed baseline study: the shared study settings, what to tune, where to write."""

    study: object          # StudyConfig (no controllers)
    tune: tuple
    out: Path
    ranges: dict = field(default_factory=dict)  # filter -> {key: (lo, hi)}: [baselines.ranges]


def load_baseline_config(path) -> BaselineConfig:
    """Read and check a baseline study file (errors name the file and the key)."""
    path = Path(path)
    doc = dict(read_toml(path, "study file"))
    with with_path(str(path)):
        bt = Table(doc.pop("baselines"), "baselines")
        tune = bt.data.get("tune", list(TUNABLE))
        bt._used.add("tune")
        if not isinstance(tune, list) or not tune or \
                not all(isinstance(n, str) and n in TUNABLE for n in tune):
            raise bt.error("tune", f"must be a non-empty array of: {', '.join(TUNABLE)}")
        out = Path(bt.string("out", f"{path.stem}.json"))
        ranges = parse_ranges(bt.table("ranges", False), lambda name: (
            default_space(name) or None if name in tune else None))
        bt.finish()
        study = study_config_from_dict(doc, path, need_controllers=False)
    out = study_output(out, path, "baselines.out")
    return BaselineConfig(study, tuple(dict.fromkeys(tune)), out, ranges)


# -- search spaces ------------------------------------------------------------------------------
def training_channels(evaluator, runs) -> tuple:
    """Measurement channels of the sensors in the training runs, in first-seen order."""
    chans = {}
    for scenario, seed in runs:
        for d in evaluator.log(scenario, seed).sensors.values():
            chans.update(dict.fromkeys(measurements.get(d.kind).channels))
    return tuple(chans)


def space_of(name: str, channels=(), ranges=None) -> dict:
    """The searched parameters of a tuned filter: key -> (low, high, log | ``"int"``);
    ``ranges``: a study file's ranges of its keys (:mod:`fuzzynav.tuning.baseline_ranges`)."""
    if name == "ekf-tuned":
        space = {**{k: Q_BOUNDS for k in Q_FIELDS}, **{f"r_{c}": R_BOUNDS for c in channels}}
    else:
        space = dict(SPACES[name])
    return with_ranges(space, ranges or {}, f"baselines.ranges.{name}")


def default_space(name: str) -> dict:
    """Every key filter ``name`` may search, with its default range (``ekf-tuned``: an
    ``r_<channel>`` for every channel a measurement model has); empty for a filter that is
    not searched (``als``)."""
    if name == "ekf-tuned":
        return space_of(name, [k[len(R_PREFIX):] for k in known_keys(name)
                               if k.startswith(R_PREFIX) and k != R_ALL])
    return space_of(name) if name in SPACES else {}


def suggest(trial, space: dict) -> dict:
    """Draw one parameter set from an Optuna trial."""
    out = {}
    for key, (lo, hi, kind) in space.items():
        if kind == "int":
            out[key] = trial.suggest_int(key, lo, hi)
        else:
            out[key] = trial.suggest_float(key, lo, hi, log=bool(kind))
    return out


# -- scoring ------------------------------------------------------------------------------------
def run_params(evaluator, name: str, params: dict, scenario: str, seed: int) -> dict:
    """Metrics of tuned filter ``name`` with ``params`` on one run."""
    if name not in TUNED:  # a named filter that takes its parameters as options (apso)
        return evaluator.run(scenario, seed, name, options=params).metrics
    setup = TUNED[name][1](filter_context(evaluator.log(scenario, seed)), params)
    return evaluator.run(scenario, seed, name, setup=setup).metrics


class BaselineObjective(TrialObjective):
    """Optuna objective of one tuned filter (pruned like a fuzzy study's trials).

    Parameters
    ----------
    cfg : StudyConfig
        The filter's study (:func:`sub_config`).
    evaluator : Evaluator
        Shared by every filter of the baseline study.
    name : str
        The tuned filter.
    space : dict
        Its searched parameters (:func:`space_of`).
    worker : int
    """

    def __init__(self, cfg, evaluator, name: str, space: dict, worker: int = 0):
        super().__init__(cfg, worker)
        self.evaluator, self.name, self.space = evaluator, name, space

    def _run(self, trial):
        self.claim(trial)
        params = suggest(trial, self.space)
        runs = list(enumerate(self.cfg.train))
        np.random.default_rng(trial.number).shuffle(runs)
        scores = []
        for step, (scenario, seed) in runs:
            m = run_params(self.evaluator, self.name, params, scenario, seed)
            scores.append(self.evaluator.judge(m, scenario, seed).score)
            self._beat(trial)
            trial.report(scores[-1], step=step)
            if trial.should_prune():
                break
        trial.set_user_attr("n_runs", len(scores))
        return float(np.mean(scores))


def sub_config(cfg, name: str, space=None):
    """The study of one tuned filter (its parameters as ``space``, for a PSO swarm)."""
    from dataclasses import replace

    kinds = {True: "log", False: "linear", "int": "int"}
    flat = tuple((k, lo, hi, kinds[kind]) for k, (lo, hi, kind) in (space or {}).items())
    return replace(cfg, name=f"{cfg.name}.{name}", multi_objective=False, space=flat)


def best_params(bcfg: BaselineConfig, study) -> tuple:
    """``(params, train score)`` of the best trial that ran every training run."""
    full = [t for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))
            if t.user_attrs.get("n_runs") == len(bcfg.study.train) and np.isfinite(t.value)]
    if not full:
        raise FuzzynavError(f"study {study.study_name!r}: no trial ran every training run")
    best = min(full, key=lambda t: t.value)
    return dict(best.params), float(best.value)


def write_params(bcfg: BaselineConfig, found: dict, scores: dict, trials: dict,
                 history=None, spaces=None) -> Path:
    """Write the tuned-parameter file the named filters read (atomically); ``history``:
    filter -> the PSO swarm's convergence (:func:`fuzzynav.tuning.pso.history`);
    ``spaces``: filter -> the ranges searched (written as ``space``)."""
    for name, p in found.items():  # what the reader would refuse is never written
        check_params(name, p, bcfg.out, f"$.filters.{name}.")
    doc = {"format": PARAMS_FORMAT, "version": PARAMS_VERSION, "study": bcfg.study.name,
           "baseline": bcfg.study.baseline,
           "train": [list(r) for r in bcfg.study.train],
           "trials": trials, "train_score": scores, "filters": found}
    if spaces:
        doc["space"] = {name: {k: [lo, hi] for k, (lo, hi, _) in sp.items()}
                        for name, sp in spaces.items()}
    if history:
        doc.update(sampler=bcfg.study.sampler, history=history)
    text = json.dumps(doc, indent=1) + "\n"
    return write_atomic(bcfg.out, lambda tmp: Path(tmp).write_text(text),
                        what="tuned-parameter file")


def train_score(ev, name: str, params: dict) -> float:
    """The mean training score of filter ``name`` with ``params`` (as a trial's)."""
    runs = ev.config.train
    return float(np.mean([ev.judge(run_params(ev, name, params, sc, sd), sc, sd).score
                          for sc, sd in runs]))
