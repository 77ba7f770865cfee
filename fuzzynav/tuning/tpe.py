"""Optuna's multivariate TPE (``group=True``) doing only the work a trial uses.

A study's space is conditional: each partition count gives its own rule table and
breakpoints, so Optuna's group-decomposed TPE splits it into about twenty groups and, before
a trial's first parameter, fits two Parzen estimators per group and samples every group --
also the groups of structures the trial does not pick (more than half of the sampling time
of ``paper000_tune``).  :class:`LazyGroupTPESampler` proposes exactly what Optuna's
:class:`~optuna.samplers.TPESampler` proposes, for less:

* a group is sampled when the trial first asks for one of its parameters.  Every group's
  draws come from the sampler's one random stream, in group order, and their number does
  not depend on the data (``n_ei_candidates x (1 + parameters)`` uniform doubles, see
  :func:`group_draws`): at the start of a trial the stream's state at each group is saved
  and the stream advanced past them all, so a group sampled later -- or never -- draws the
  numbers it would have drawn, and the parameters sampled independently afterwards too;
* the group-decomposed search space is refined with the trials finished since the last
  trial instead of all of them, and not deep-copied (:class:`IncrementalGroupSearchSpace`).

With one worker a seeded study proposes the identical parameters (``tests/tuning/
test_tpe.py`` compares it with Optuna's sampler).  With several workers one thing differs
on purpose: Optuna shares a running trial's sampled values of every group (constant liar),
this sampler only the parameters the trial uses (its ``params``), so a running trial is a
"liar" only in the groups of the structure it runs.  Set :data:`ENABLED` to False for
Optuna's own sampler.
"""
from __future__ import annotations

from collections.abc import Mapping

import optuna
from optuna.samplers import TPESampler
from optuna.trial import TrialState

try:  # Optuna internals: present in the releases of CHECKED_OPTUNA
    from optuna.search_space.group_decomposed import _GroupDecomposedSearchSpace, \
        _SearchSpaceGroup
except ImportError:  # pragma: no cover - another Optuna: the plain sampler is used
    _GroupDecomposedSearchSpace, _SearchSpaceGroup = object, None

#: Optuna releases (major.minor) whose TPE internals the lazy sampler was checked against
#: (``tests/tuning/test_tpe.py``); on any other release ``sampler = "tpe"`` falls back to
#: Optuna's own TPESampler rather than risk proposing something else
CHECKED_OPTUNA = ("5.0",)
SUPPORTED = (".".join(optuna.__version__.split(".")[:2]) in CHECKED_OPTUNA
             and _SearchSpaceGroup is not None)
#: False: ``sampler = "tpe"`` makes Optuna's own TPESampler (to compare against)
ENABLED = SUPPORTED


def group_draws(n_ei_candidates: int, n_params: int) -> int:
    """Uniform doubles Optuna 5's TPE draws to sample one group of ``n_params``: a mixture
    component per candidate, then one quantile per candidate and parameter."""
    return n_ei_candidates * (1 + n_params)


class IncrementalGroupSearchSpace(_GroupDecomposedSearchSpace):
    """Optuna's group-decomposed search space, refined only with trials not seen yet.

    Optuna keeps its groups between calls and refines them with every finished trial at
    every call; refining with a parameter set already added changes nothing (every group
    is then inside it or outside it), not even the order of the groups (the order the
    sampler draws them in).  Adding only the new trials, in Optuna's order, gives the same
    groups in the same order -- also when trials finish out of number order.
    """

    def __init__(self, include_pruned: bool = False) -> None:
        super().__init__(include_pruned)
        self._seen: set = set()

    def calculate(self, study, use_cache: bool = False) -> _SearchSpaceGroup:
        """The groups of the study's finished trials (a copy the caller may keep)."""
        if self._study_id is None:
            self._study_id = study._study_id
        elif self._study_id != study._study_id:
            raise ValueError("`_GroupDecomposedSearchSpace` cannot handle multiple studies.")
        states = ((TrialState.COMPLETE, TrialState.PRUNED) if self._include_pruned
                  else (TrialState.COMPLETE,))
        trials = study._get_trials(deepcopy=False, states=states, use_cache=use_cache)
        for t in trials:
            if t.number not in self._seen:
                self._search_space.add_distributions(t.distributions)
                self._seen.add(t.number)
        out = _SearchSpaceGroup()  # add_distributions replaces the list and its dicts,
        out._search_spaces = list(self._search_space.search_spaces)  # never mutates them
        return out


class _LazyParams(Mapping):
    """A trial's relative parameters, each group sampled on its first lookup."""

    def __init__(self, sampler, study, trial, groups):
        self._sampler, self._study, self._trial = sampler, study, trial
        self._groups = groups  # [(search space, random state at its start)]
        self._where = {name: i for i, (space, _) in enumerate(groups) for name in space}
        self._values: dict = {}

    def __getitem__(self, name):
        if name not in self._values:
            space, state = self._groups[self._where[name]]  # KeyError: not relative
            self._values.update(self._sampler._sample_group(self._study, self._trial,
                                                            space, state))
        return self._values[name]

    def __contains__(self, name) -> bool:
        return name in self._where

    def __iter__(self):
        return iter(self._where)

    def __len__(self) -> int:
        return len(self._where)


class LazyGroupTPESampler(TPESampler):
    """:class:`optuna.samplers.TPESampler` (``multivariate=True, group=True``) sampling a
    group of the search space only when the trial uses it (see the module docstring)."""

    def __init__(self, **kwargs) -> None:
        super().__init__(**kwargs)
        if not self._group:
            raise ValueError("LazyGroupTPESampler needs group=True")
        self._group_decomposed_search_space = IncrementalGroupSearchSpace(True)

    def sample_relative(self, study, trial, search_space) -> Mapping:
        """The trial's relative parameters, lazily: the random stream is advanced past
        every group now, each group sampled from its saved state when first looked up."""
        trials = study._get_trials(deepcopy=False, use_cache=True,
                                   states=(TrialState.COMPLETE, TrialState.PRUNED))
        if len(trials) < self._n_startup_trials:
            return {}
        rng, groups = self._rng.rng, []
        for sub_space in self._search_space_group.search_spaces:
            # Optuna's order and filter (sorted: string hashing is not deterministic)
            space = {name: dist for name, dist in sorted(sub_space.items())
                     if not dist.single() and name in search_space}
            if space:
                groups.append((space, rng.get_state()))
                rng.random_sample(group_draws(self._n_ei_candidates, len(space)))
        return _LazyParams(self, study, trial, groups)

    def _sample_group(self, study, trial, space, state) -> dict:
        """Optuna's sample of one group, its draws starting at ``state``."""
        main = self._rng._rng
        self._rng._rng = rng = type(main)()
        rng.set_state(state)
        try:
            return self._sample(study, trial, space)
        finally:
            self._rng._rng = main
