"""Optuna's pruners as a study uses them, without their per-call copies.

Optuna's :class:`~optuna.pruners.WilcoxonPruner` asks for ``study.best_trial`` at every
report, which deep-copies the best trial -- every parameter and distribution of a rule
table, about as long as the test itself.  The pruner only reads the best trial's
intermediate values, so :class:`WilcoxonPruner` hands it the stored trial uncopied; its
decisions are Optuna's own.
"""
from __future__ import annotations

import optuna


class _BestUncopied:
    """A study whose ``best_trial`` is the stored one, not a copy (read-only use)."""

    def __init__(self, study):
        self._study = study

    def __getattr__(self, name):
        return getattr(self._study, name)

    @property
    def best_trial(self):
        get = getattr(self._study, "_get_best_trial", None)
        return get(deepcopy=False) if get is not None else self._study.best_trial


class WilcoxonPruner(optuna.pruners.WilcoxonPruner):
    """:class:`optuna.pruners.WilcoxonPruner` reading the best trial without copying it."""

    def prune(self, study, trial) -> bool:
        """Optuna's decision for ``trial`` (see :class:`optuna.pruners.WilcoxonPruner`)."""
        return super().prune(_BestUncopied(study), trial)
