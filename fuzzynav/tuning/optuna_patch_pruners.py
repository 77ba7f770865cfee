"""Patches Optuna: its Wilcoxon pruner as a study uses it, without a per-call copy.

Optuna's :class:`~optuna.pruners.WilcoxonPruner` asks for ``study.best_trial`` at every
report, which deep-copies the best trial -- every parameter and distribution of a rule
table, about as long as the test itself.  The pruner only reads the best trial's
intermediate values, so :class:`WilcoxonPruner` hands it the stored trial uncopied; its
decisions are Optuna's own.

This module relies on Optuna's private ``Study._get_best_trial(deepcopy=False)`` (in 5.1;
4.2, pyproject's lower bound, lacks it).  Without it the pruner reads Optuna's public ``study.best_trial`` -- the same decisions, with
the copy.  The measured gain: ``benchmarks/bench_patches.py`` (``docs/benchmarks.md``,
"Library patches").
"""
from __future__ import annotations

import optuna


#: Optuna's private ``Study`` method giving the best trial uncopied (looked up by name: a
#: release without it takes the public ``best_trial``)
PRIVATE_BEST_TRIAL = "_get_best_trial"


class _BestUncopied:
    """A study whose ``best_trial`` is the stored one, not a copy (read-only use)."""

    def __init__(self, study):
        self._study = study

    def __getattr__(self, name):
        return getattr(self._study, name)

    @property
    def best_trial(self):
        get = getattr(self._study, PRIVATE_BEST_TRIAL, None)
        return get(deepcopy=False) if get is not None else self._study.best_trial


class WilcoxonPruner(optuna.pruners.WilcoxonPruner):
    """:class:`optuna.pruners.WilcoxonPruner` reading the best trial without copying it."""

    def prune(self, study, trial) -> bool:
        """Optuna's decision for ``trial`` (see :class:`optuna.pruners.WilcoxonPruner`)."""
        return super().prune(_BestUncopied(study), trial)
