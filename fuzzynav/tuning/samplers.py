"""The optimisers a study may use: sampler name -> how to make its Optuna sampler.

A new optimiser is one module with an :class:`optuna.samplers.BaseSampler` and one
:func:`register_optimiser` call, the module named in ``OPTIMISERS.builtin_modules`` (or
imported before the study config is loaded).  The rest of the study machinery -- workers,
storage, pruning, reaping, export, report -- reads only the entry's fields, never the name.
"""
from __future__ import annotations

import importlib.util
from dataclasses import dataclass
from typing import Callable

import optuna

from fuzzynav.registry import Registry

__all__ = ["Optimiser", "OPTIMISERS", "register_optimiser", "get_optimiser", "optimiser_names"]


def _all_trials(cfg, total: int) -> int:
    return total


def _always(study, cfg) -> bool:
    return True


@dataclass(frozen=True)
class Optimiser:
    """One ``sampler = "<name>"`` choice of a study file.

    Attributes
    ----------
    name : str
    make : callable
        ``make(cfg, seed) -> optuna.samplers.BaseSampler``.
    description : str
    pruning : bool
        Whether the configured pruner may stop its trials early (False: a Nop pruner, every
        trial runs every training run -- e.g. a swarm needs full values).
    multi_objective : bool
        Whether it handles ``objective = "multi"``.
    shared_seed : bool
        Seed every worker and resumed run with the config's seed (one shared sequence,
        QMC) instead of a seed per (worker, trials stored).
    needs : str or None
        A package it imports, checked when the config is loaded.
    budget : callable
        ``budget(cfg, total) -> trials`` it runs when asked for ``total`` (PSO: whole swarms).
    ready : callable
        ``ready(study, cfg) -> bool``: whether the sampler can place a new trial now; a
        worker holding the trial-slot lock asks before starting one and otherwise lets the
        lock go and waits (PSO: a swarm waits for the values of the previous one).
    """

    name: str
    make: Callable
    description: str = ""
    pruning: bool = True
    multi_objective: bool = True
    shared_seed: bool = False
    needs: str | None = None
    budget: Callable = _all_trials
    ready: Callable = _always

    def check(self, multi_objective: bool) -> str | None:
        """Why this optimiser cannot run a study (None: it can)."""
        if multi_objective and not self.multi_objective:
            return f"{self.name} is single-objective here"
        if self.needs and importlib.util.find_spec(self.needs) is None:
            return (f"{self.name!r} needs the {self.needs} package, which is not installed "
                    f"(pip install {self.needs})")
        return None


OPTIMISERS = Registry("sampler", "fuzzynav.tuning", ("pso",))


def register_optimiser(opt: Optimiser) -> Optimiser:
    """Add an optimiser under its name; returns it."""
    return OPTIMISERS.add(opt.name, opt)


def get_optimiser(name: str) -> Optimiser:
    """The optimiser ``name`` (:class:`~fuzzynav.errors.UnknownNameError` listing the
    known ones)."""
    return OPTIMISERS.lookup(name)


def optimiser_names() -> tuple:
    """Every registered sampler name, built-ins first."""
    return tuple(OPTIMISERS.load())


def _tpe(cfg, seed):
    # group=True: each partition structure of the conditional space is its own group;
    # constant_liar: parallel workers do not all propose around the same running trial
    return optuna.samplers.TPESampler(seed=seed, multivariate=True, group=True,
                                      constant_liar=True, n_startup_trials=10)


register_optimiser(Optimiser(
    "tpe", _tpe, "multivariate TPE over each structure of the space (group=True)"))
register_optimiser(Optimiser(
    "tpe-univariate", lambda cfg, seed: optuna.samplers.TPESampler(seed=seed),
    "Optuna's default TPE (each parameter on its own; the alignment study's)"))
register_optimiser(Optimiser(
    "random", lambda cfg, seed: optuna.samplers.RandomSampler(seed=seed), "uniform sampling"))
register_optimiser(Optimiser(
    "qmc", lambda cfg, seed: optuna.samplers.QMCSampler(seed=seed,
                                                        warn_independent_sampling=False),
    "scrambled Sobol sequence", shared_seed=True))
register_optimiser(Optimiser(
    "cmaes", lambda cfg, seed: optuna.samplers.CmaEsSampler(seed=seed,
                                                            warn_independent_sampling=False),
    "CMA-ES", needs="cmaes"))
register_optimiser(Optimiser(
    "nsga2", lambda cfg, seed: optuna.samplers.NSGAIISampler(seed=seed),
    "NSGA-II (multi-objective)"))
