"""Particle-swarm optimisation over the rule search space, as an Optuna sampler (paper 004).

PSO needs a fixed-length vector, so it works on one *structure* of the conditional space: the
partition counts are fixed to the smallest allowed count of each variable (the template's
count when allowed), and every other parameter of that structure is a coordinate in [0, 1]
(categorical rule consequents are the floor of the scaled coordinate).  Velocity update::

    v <- w(i) v + c1 r1 (p_best - x) + c2 r2 (g_best - x),   x <- clip(x + v, 0, 1)

with the inertia ``w`` constant or decreasing linearly from ``inertia[0]`` to ``inertia[1]``
over the configured ``iterations`` (a shorter run with ``--trials`` follows the same schedule
and stops early, after whole swarms).

:class:`PsoSampler` gives each new trial the next free particle of the swarm (recorded in
the trial's user attributes ``pso_iteration`` and ``particle``), so the ordinary study
workers evaluate a swarm in parallel and ``study report`` / ``export`` work unchanged.  The
swarm is synchronous: a trial of iteration ``k + 1`` waits until every particle of
iteration ``k`` has its value.  The sampler keeps no state of its own: the swarm is replayed
from the seed and the values stored in the study, so any worker -- or a resumed run -- sees
the same swarm; a particle whose trial failed for good counts as infinitely bad, a trial of
the study whose parameters differ from the replayed particle (the config changed) is an error
rather than a silent mix of two swarms.
"""
from __future__ import annotations

import time

import numpy as np
import optuna
from optuna.trial import TrialState

from fuzzynav.errors import FuzzynavError
from fuzzynav.tuning.samplers import Optimiser, register_optimiser
from fuzzynav.tuning.space import ControllerSpace

__all__ = ["POLL_S", "structure", "to_params", "inertia", "history", "swarm_budget", "slots",
           "iteration_values", "positions", "next_slot", "swarm_ready", "PsoSampler"]

_PENDING = (TrialState.WAITING, TrialState.RUNNING)
#: user attributes placing a trial in the swarm
ITERATION, PARTICLE = "pso_iteration", "particle"
#: how often a trial waiting for the previous swarm looks at the study again [s]
POLL_S = 0.05


class _Recorder:
    """A trial stand-in recording the parameters one structure of the space asks for."""

    def __init__(self, spaces):
        self.params = []   # (name, kind, spec)
        self.fixed = {}    # the counts the structure asked for, fixed
        self._fixed = {}
        for sp in spaces:
            t = sp.template
            for v in t.inputs + t.outputs:
                allowed = sp.config.partitions.get(v.name, (len(v.terms),))
                n = len(v.terms) if len(v.terms) in allowed else min(allowed)
                self._fixed[f"{sp.config.name}.n.{v.name}"] = n

    def suggest_categorical(self, name, choices):
        if name in self._fixed:
            self.fixed[name] = self._fixed[name]
            return self._fixed[name]
        self.params.append((name, "cat", list(choices)))
        return choices[0]

    def suggest_float(self, name, lo, hi):
        self.params.append((name, "float", (lo, hi)))
        return 0.5 * (lo + hi)

    def suggest_int(self, name, lo, hi):
        self.params.append((name, "int", (lo, hi)))
        return (lo + hi) // 2


def structure(cfg):
    """The recorded parameters and the fixed counts of the PSO structure (a baseline
    study's ``cfg.space`` when it has no controllers)."""
    if not cfg.controllers:
        return [(name, kind, (lo, hi)) for name, lo, hi, kind in cfg.space], {}
    spaces = [ControllerSpace.from_config(c) for c in cfg.controllers]
    rec = _Recorder(spaces)
    for sp in spaces:
        sp.build(rec)
    return rec.params, rec.fixed


def to_params(x, params, fixed) -> dict:
    """A point of [0, 1]^D as an Optuna parameter dict."""
    out = dict(fixed)
    for u, (name, kind, spec) in zip(x, params):
        if kind == "cat":
            out[name] = spec[min(int(u * len(spec)), len(spec) - 1)]
        elif kind == "int":
            out[name] = int(round(spec[0] + u * (spec[1] - spec[0])))
        elif kind == "log":  # a scale factor: uniform in its logarithm
            v = np.exp(np.log(spec[0]) + u * np.log(spec[1] / spec[0]))
            out[name] = float(np.clip(v, spec[0], spec[1]))  # exp(log) may round past one
        else:
            out[name] = float(spec[0] + u * (spec[1] - spec[0]))
    return out


def inertia(cfg, it: int) -> float:
    """Inertia weight of iteration ``it``: linear from start to end over the iterations
    (constant when both are equal), the end weight after the last one."""
    w0, w1 = cfg.pso.inertia
    return w0 + (w1 - w0) * min(it, cfg.pso.iterations - 1) / max(cfg.pso.iterations - 1, 1)


def history(study, cfg) -> list:
    """Per iteration of a finished swarm: its inertia weight, the best value so far and the
    swarm's mean (finite values) -- the convergence of the run."""
    by_slot = slots(study.get_trials(deepcopy=False))
    n, out, best = cfg.pso.particles, [], np.inf
    it = 0
    while any((it, i) in by_slot for i in range(n)):
        vals = iteration_values(by_slot, it, n)
        best = min(best, float(vals.min()))
        fin = vals[np.isfinite(vals)]
        out.append({"iteration": it, "inertia": inertia(cfg, it), "best": best,
                    "swarm_mean": float(fin.mean()) if fin.size else float("nan")})
        it += 1
    return out


def swarm_budget(cfg, total: int) -> int:
    """Trials of the whole swarms that fit in ``total`` (at least one swarm)."""
    n = cfg.pso.particles
    return max(1, min(cfg.pso.iterations, total // n)) * n


def slots(trials) -> dict:
    """``(iteration, particle) -> [trials]`` of the swarm's trials."""
    out = {}
    for t in trials:
        if ITERATION in t.user_attrs:
            out.setdefault((t.user_attrs[ITERATION], t.user_attrs[PARTICLE]), []).append(t)
    return out


def iteration_values(by_slot: dict, it: int, n: int) -> np.ndarray:
    """Values of an iteration's particles (inf where none completed)."""
    vals = np.full(n, np.inf)
    for i in range(n):
        done = [t.value for t in by_slot.get((it, i), []) if t.state == TrialState.COMPLETE]
        if done:
            vals[i] = done[0]
    return vals


def positions(cfg, dim: int, by_slot: dict, it: int, check=None) -> np.ndarray:
    """The particles' positions in iteration ``it``, replayed from the seed and the values of
    the iterations before; ``check(k, x)`` is called with every iteration's positions."""
    rng = np.random.default_rng(cfg.seed)
    n = cfg.pso.particles
    x = rng.random((n, dim))
    v = 0.1 * rng.standard_normal((n, dim))
    pbest, pval = x.copy(), np.full(n, np.inf)
    g, gval = x[0].copy(), np.inf
    for k in range(it):
        if check is not None:
            check(k, x)
        vals = iteration_values(by_slot, k, n)
        better = vals < pval
        pbest[better], pval[better] = x[better], vals[better]
        if pval.min() < gval:
            g, gval = pbest[pval.argmin()].copy(), float(pval.min())
        r1, r2 = rng.random((n, dim)), rng.random((n, dim))
        v = inertia(cfg, k) * v + cfg.pso.c1 * r1 * (pbest - x) + cfg.pso.c2 * r2 * (g - x)
        x = np.clip(x + v, 0.0, 1.0)
    if check is not None:
        check(it, x)
    return x


def next_slot(by_slot: dict, n: int):
    """The first particle without a trial, and whether its iteration may start (every
    particle of the one before has a value or failed for good)."""
    it = 0
    while all((it, i) in by_slot for i in range(n)):
        it += 1
    free = next(i for i in range(n) if (it, i) not in by_slot)
    ready = it == 0 or not any(t.state in _PENDING for i in range(n)
                               for t in by_slot.get((it - 1, i), []))
    return (it, free), ready


def swarm_ready(study, cfg) -> bool:
    """Whether a worker may start a trial: a retry is queued, or the next particle's
    iteration may start."""
    trials = study.get_trials(deepcopy=False)
    if any(t.state == TrialState.WAITING for t in trials):
        return True  # (the trial started next is that one)
    return next_slot(slots(trials), cfg.pso.particles)[1]


class PsoSampler(optuna.samplers.BaseSampler):
    """Gives each trial the parameters of the next particle of the swarm (see the module).

    Parameters
    ----------
    cfg : StudyConfig
        With ``cfg.pso`` (particles, iterations, inertia, c1, c2).
    seed : int
        Seed of the swarm (the same for every worker: they share one swarm).
    """

    def __init__(self, cfg, seed: int):
        import dataclasses

        self.cfg = dataclasses.replace(cfg, seed=seed)
        self.params, self.fixed = structure(cfg)
        self._current = None  # (trial number, parameters) of the trial sampled here

    def infer_relative_search_space(self, study, trial):
        return {}

    def sample_relative(self, study, trial, search_space):
        return {}

    def sample_independent(self, study, trial, param_name, param_distribution):
        number, params = self._current or (None, {})
        if number != trial.number or param_name not in params:
            raise FuzzynavError(f"study {self.cfg.name!r}: the PSO structure has no parameter "
                                f"{param_name!r} (trial {trial.number})")
        return params[param_name]

    def before_trial(self, study, trial):
        try:
            it, i = self._place(study, trial)
            by_slot = slots(t for t in study.get_trials(deepcopy=False)
                            if t.number != trial.number)
            x = positions(self.cfg, len(self.params), by_slot, it, self._checker(by_slot))
        except FuzzynavError:  # the trial would stay RUNNING with no owner
            study._storage.set_trial_state_values(trial._trial_id, TrialState.FAIL)
            raise
        self._current = (trial.number, to_params(x[i], self.params, self.fixed))

    def _place(self, study, trial):
        """The trial's ``(iteration, particle)``: its own (a retry) or the next free one,
        recorded in its user attributes once the previous iteration has every value (the
        workers wait for that in :func:`swarm_ready`, holding no lock; this wait only
        covers storages without the trial-slot lock)."""
        if ITERATION in trial.user_attrs:
            return trial.user_attrs[ITERATION], trial.user_attrs[PARTICLE]
        start = time.monotonic()
        while True:
            others = [t for t in study.get_trials(deepcopy=False) if t.number != trial.number]
            slot, ready = next_slot(slots(others), self.cfg.pso.particles)
            if ready:
                break
            if time.monotonic() - start > self.cfg.stale_after_s:
                raise FuzzynavError(f"study {self.cfg.name!r}: PSO iteration {slot[0] - 1} "
                                    f"still has running particles after "
                                    f"{self.cfg.stale_after_s:g} s (stale_after_s)")
            time.sleep(POLL_S)
        for key, value in zip((ITERATION, PARTICLE), slot):
            study._storage.set_trial_user_attr(trial._trial_id, key, value)
        return slot

    def _checker(self, by_slot):
        def check(it, x):
            for i in range(len(x)):
                p = to_params(x[i], self.params, self.fixed)
                for t in by_slot.get((it, i), []):  # (a killed trial may hold some params)
                    if any(p.get(k) != val for k, val in t.params.items()):
                        raise FuzzynavError(
                            f"study {self.cfg.name!r}: PSO iteration {it}, particle {i} in "
                            "the study has other parameters than the swarm replayed from "
                            "this config (was the config changed?); use a new study name")
        return check


register_optimiser(Optimiser(
    "pso", lambda cfg, seed: PsoSampler(cfg, seed),
    "particle swarm with a constant or linearly decreasing inertia weight (paper 004)",
    pruning=False, multi_objective=False, shared_seed=True, budget=swarm_budget,
    ready=swarm_ready))
