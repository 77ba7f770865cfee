"""Study kinds: what a study file tunes, plugged into the one study driver.

Every study file -- fuzzy controllers (``[[controllers]]``), classical baselines
(``[baselines]``), the alignment filter's rules (``kind = "alignment"``) -- runs through the
same driver (:func:`fuzzynav.tuning.study_run.run_plan`): its workers, storages (journal file,
PostgreSQL), slot locks, reaping, resume, export and report.  A kind is one module here
with a *plan* class and one :func:`register_kind` call; the driver reads only the plan.

A plan is a study file opened with its simulation cache.  It has

``name``, ``path``
    the file's study name and path;
``parts()``
    the keys of the Optuna studies it runs, in order (``""`` for one study; a baseline
    file runs one study per searched filter);
``config(key)``
    the :class:`~fuzzynav.tuning.study_config.StudyConfig` of a part (name, storage, sampler,
    seed, trials, pruner, stale-trial period: what the driver reads);
``warm(processes, progress)``
    load what every trial needs, once, in the parent before workers fork (idempotent);
``objective(key, worker)``
    the part's :class:`~fuzzynav.tuning.objective.TrialObjective` for worker ``worker``;
``finish(studies, storage)``
    after the parts ran (``key -> optuna.Study``; ``storage``: the URL given, if any): write the kind's product (a baseline
    parameter file, a tuned alignment rule file; nothing for fuzzy studies) and return
    the lines to print;
``summary(studies)``, ``export(studies, out, trial)``, ``report(studies, out, evaluate)``
    what ``fuzzynav study run | export | report`` print and write.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from fuzzynav.registry import Registry


@dataclass(frozen=True)
class StudyKind:
    """One kind of study file.

    Attributes
    ----------
    name : str
    detect : callable
        ``detect(doc) -> bool``: whether a study file's parsed TOML is of this kind (a file
        no other kind claims is a :data:`DEFAULT` study).
    load : callable
        ``load(path, cache_dir) -> plan`` (errors name the file and the key).
    description : str
    """

    name: str
    detect: Callable
    load: Callable
    description: str = ""


#: the kind of a study file that no other kind claims
DEFAULT = "fuzzy"
KINDS = Registry("study kind", "fuzzynav.tuning.kinds", ("baseline_studies", "alignment", "fuzzy"))


def register_kind(kind: StudyKind) -> StudyKind:
    """Add a study kind under its name; returns it."""
    return KINDS.add(kind.name, kind)


def study_settings(path, name: str, *, sampler: str, seed: int, trials: int, storage: str = "",
                   stale_after_s: float = 300.0, train=(), test=(), space=(), **more):
    """The :class:`~fuzzynav.tuning.study_config.StudyConfig` of a kind's study that has none of a
    fuzzy study's controllers, weights or baseline filter: what the driver reads (name,
    storage, sampler, seed, trials, stale-trial period; ``train``: what ``n_runs`` of a
    complete trial counts), no pruner, one objective.  ``more``: other fields to set."""
    from fuzzynav.tuning.study_config import PsoConfig, StudyConfig

    fields = dict(name=name, description="", path=Path(path).resolve(), sampler=sampler,
                  seed=seed, trials=trials, pruner="none", multi_objective=False,
                  storage=storage, stale_after_s=stale_after_s, pso=PsoConfig(), weights={},
                  baseline="", t_start_s=0.0, train=tuple(train), test=tuple(test),
                  compare=(), controllers=(), space=tuple(space))
    return StudyConfig(**{**fields, **more})


def kind_of(path) -> StudyKind:
    """The kind of the study file ``path`` (read once, not checked beyond that)."""
    from fuzzynav.sim.tomltable import read_toml

    doc = read_toml(Path(path), "study file")
    claimed = [k for name, k in KINDS.load().items() if name != DEFAULT and k.detect(doc)]
    return claimed[0] if claimed else KINDS.lookup(DEFAULT)


def load_plan(path, cache_dir=None):
    """The plan of the study file ``path`` (see the module docstring)."""
    return kind_of(path).load(Path(path), cache_dir)
