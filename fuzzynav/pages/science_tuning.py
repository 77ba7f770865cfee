"""The tunings of ``docs/science.md``: every tuned filter, once per tuning (sampler) seed.

For each tuning seed ``S`` (:func:`fuzzynav.tuning.tuning_seeds.seeded_plan`: the study
files' ``[study] seed`` + 0, 1, ...), in this order:

1. the classical baselines of ``studies/paper000_baselines.toml`` (one Optuna study per
   filter; ALS estimated) into ``<work>/paper000_baselines-seed<S>.json``;
2. the fuzzy R-scaling controller of ``studies/paper000_fair.toml``;
3. the fuzzy supervisors (``studies/paper000_fuzzy_{sage_husa,vb,huber}.toml``), each
   warm-started (:mod:`fuzzynav.tuning.warm_start`) from *this tuning's* tuned parent.

Every study runs its file's budget (or ``trials``) with the same sampler, pruner,
objective and training runs; journals are ``<work>/<study>-seed<S>.journal`` (an existing
one is resumed, so ``fuzzynav study run FILE --study-seeds N`` run beforehand in ``work``
is picked up).  :func:`best_of_first` is a study stopped after ``n`` trials: the best
among its trials numbered below ``n`` (a sequential sampler's first ``n`` trials are the
trials a budget of ``n`` would have run; with parallel workers, to within the trials in
flight) -- the budget curves read their points from it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from fuzzynav.pages.common import REPO_ROOT as ROOT
from fuzzynav.tuning.kinds.fuzzy import FuzzyPlan
from fuzzynav.tuning.study_run import run_study

__all__ = ["FAIR", "BASELINES", "SUPERVISOR_STUDIES", "Tuning", "tune_seed",
           "best_of_first", "fuzzy_systems_at", "baseline_params_at"]

FAIR = ROOT / "studies" / "paper000_fair.toml"
BASELINES = ROOT / "studies" / "paper000_baselines.toml"
#: label on the page -> supervisor study (the label is the named filter it tunes)
SUPERVISOR_STUDIES = {
    "fuzzy-sage-husa-tuned": ROOT / "studies" / "paper000_fuzzy_sage_husa.toml",
    "fuzzy-vb-tuned": ROOT / "studies" / "paper000_fuzzy_vb.toml",
    "fuzzy-huber-tuned": ROOT / "studies" / "paper000_fuzzy_huber.toml",
}
FUZZY_RSCALING = "fuzzy-tuned"


@dataclass
class Tuning:
    """What one tuning seed produced.

    Attributes
    ----------
    seed : int
        The sampler seed.
    params : Path
        The tuned baselines' parameter file.
    bplan : object
        Its baseline plan (the studies' configs).
    fuzzy : dict
        Label (``fuzzy-tuned``, ``fuzzy-sage-husa-tuned``, ...) -> ``(config, study)``.
    baselines : dict
        Tuned baseline name -> its Optuna study.
    """

    seed: int
    params: Path
    bplan: object
    fuzzy: dict = field(default_factory=dict)
    baselines: dict = field(default_factory=dict)


def _storage(work: Path, name: str) -> str:
    return f"journal:{work / (name + '.journal')}"


def _tune_fuzzy(plan, trials, workers, work, cache):
    return run_study(plan.cfg, trials, workers, _storage(work, plan.cfg.name), cache,
                     progress=True, plan=plan)


def tune_seed(seed: int, trials, workers: int, work: Path, cache: str,
              curve: dict | None = None) -> Tuning:
    """Tune every filter of the page with sampler seed ``seed`` (see the module docstring).

    ``trials``: per study (None: each file's own budget); the parameter file and the warm
    starts take the best of those trials.  ``curve``: label (a tuned baseline or a fuzzy
    label) -> a longer budget its study is then continued to (the budget curves' last
    point; the page's tables still read the best of the first ``trials``)."""
    from fuzzynav.tuning.baseline_config import load_baseline_config
    from fuzzynav.tuning.kinds.baseline_studies import BaselinePlan
    from fuzzynav.tuning.study_config import load_study_config
    from fuzzynav.tuning.tuning_seeds import seeded_plan
    from fuzzynav.tuning.warm_start import with_parent_file

    bplan = seeded_plan(BaselinePlan(load_baseline_config(BASELINES), cache), seed)
    out = work / f"{bplan.name}.json"
    run = {}  # label -> (plan, part) of every study, to continue the curve ones

    def baseline(part, n):
        cfg = bplan.config(part)
        return run_study(cfg, n, workers, _storage(work, cfg.name), cache, progress=True,
                         plan=bplan, part=part)

    studies = {part: baseline(part, trials) for part in bplan.parts()}
    bplan.write({k: best_of_first(s, trials) for k, s in studies.items()}, out)
    tuned = Tuning(seed, out, bplan, baselines=studies)
    cfgs = {FUZZY_RSCALING: load_study_config(FAIR)}
    cfgs.update({label: with_parent_file(load_study_config(path), out)
                 for label, path in SUPERVISOR_STUDIES.items()})
    for label, cfg in cfgs.items():
        run[label] = seeded_plan(FuzzyPlan(cfg, cache), seed)
        tuned.fuzzy[label] = (run[label].cfg, _tune_fuzzy(run[label], trials, workers, work,
                                                          cache))
    for label, n in (curve or {}).items():  # continued: the first `trials` stay the same
        if label in studies:
            tuned.baselines[label] = baseline(label, n)
        else:
            tuned.fuzzy[label] = (run[label].cfg, _tune_fuzzy(run[label], n, workers, work,
                                                              cache))
    return tuned


class _FirstTrials:
    """A study seen as if stopped after its first ``n`` trials (numbers below ``n``)."""

    def __init__(self, study, n: int):
        self._study, self._n = study, int(n)
        self.study_name = study.study_name

    def get_trials(self, deepcopy=False, states=None):
        return [t for t in self._study.get_trials(deepcopy=deepcopy, states=states)
                if t.number < self._n]


def best_of_first(study, n: int | None):
    """``study`` as a budget of ``n`` trials would have left it (None: all of it)."""
    return study if n is None else _FirstTrials(study, n)


def fuzzy_systems_at(cfg, study, n: int | None = None):
    """``(systems, training score)`` of the best trial among the first ``n``."""
    from fuzzynav.tuning.export import choose_trial, systems_of

    trial = choose_trial(best_of_first(study, n), cfg)
    return systems_of(cfg, trial), float(trial.value)


def baseline_params_at(tuned: Tuning, name: str, n: int | None = None):
    """``(params, training score)`` of baseline ``name``'s best trial among the first ``n``."""
    from fuzzynav.tuning.baseline_config import best_params

    return best_params(tuned.bplan.bcfg, best_of_first(tuned.baselines[name], n))
