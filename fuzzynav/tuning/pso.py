"""Particle-swarm optimisation over the rule search space (paper 004's inertia schedule).

PSO needs a fixed-length vector, so it works on one *structure* of the conditional space: the
partition counts are fixed to the smallest allowed count of each variable (the template's
count when allowed), and every other parameter of that structure is a coordinate in [0, 1]
(categorical rule consequents are the floor of the scaled coordinate).  Velocity update::

    v <- w(i) v + c1 r1 (p_best - x) + c2 r2 (g_best - x),   x <- clip(x + v, 0, 1)

with ``w`` decreasing linearly from ``inertia[0]`` to ``inertia[1]`` over the configured
``iterations`` (a shorter run with ``--trials`` follows the same schedule and stops early).
Each swarm is enqueued into the Optuna study and evaluated by the same objective as the other
samplers, by ``workers`` processes in parallel; the study then holds every evaluation, so
``study report`` and ``study export`` work unchanged.

Resuming replays the swarm from the seed and the values already in the study (each
particle's trial carries ``pso_iteration`` and ``particle``); only particles without a trial
are enqueued, and a trial whose parameters differ from the replayed particle (the config
changed) is an error rather than a silent mix of two swarms.
"""
from __future__ import annotations

import numpy as np
from tqdm.auto import tqdm

from optuna.trial import TrialState

from fuzzynav.errors import FuzzynavError
from fuzzynav.tuning.space import ControllerSpace

_PENDING = (TrialState.WAITING, TrialState.RUNNING)


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
    """The recorded parameters and the fixed counts of the PSO structure."""
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
        else:
            out[name] = float(spec[0] + u * (spec[1] - spec[0]))
    return out


def inertia(cfg, it: int) -> float:
    """Inertia weight of iteration ``it``: linear from start to end over the iterations."""
    w0, w1 = cfg.pso.inertia
    return w0 + (w1 - w0) * it / max(cfg.pso.iterations - 1, 1)


def _trials_of(study, it):
    """Particle -> trials of iteration ``it`` in the study."""
    out = {}
    for t in study.get_trials(deepcopy=False):
        if t.user_attrs.get("pso_iteration") == it:
            out.setdefault(t.user_attrs["particle"], []).append(t)
    return out


def _evaluate(study, cfg, swarm_params, it, workers, storage, cache_dir):
    """Enqueue the particles of a swarm not in the study yet, let the workers evaluate
    every queued one, return the values in particle order (inf: failed)."""
    from fuzzynav.tuning.run import supervise
    from fuzzynav.tuning.study import n_finished, run_worker

    have = _trials_of(study, it)
    todo = 0
    for i, p in enumerate(swarm_params):
        for t in have.get(i, []):  # (a queued trial shows no params yet; a killed one some)
            if any(p.get(k) != val for k, val in t.params.items()):
                raise FuzzynavError(
                    f"study {cfg.name!r}: PSO iteration {it}, particle {i} in the study has "
                    "other parameters than the swarm replayed from this config (was the "
                    "config changed?); use a new study name")
        states = [t.state for t in have.get(i, [])]
        if not states:  # (a failed particle stays failed: its retries are the reaper's job)
            study.enqueue_trial(p, user_attrs={"pso_iteration": it, "particle": i})
            states.append(TrialState.WAITING)
        todo += any(s in _PENDING for s in states)
    if not todo:
        return _recorded(study, it, len(swarm_params))
    total = n_finished(study) + len(swarm_params)
    if workers == 1:
        run_worker(cfg, total, storage, 0, cache_dir)
    else:
        supervise(cfg, study, total, workers, storage, cache_dir)  # restarts dead workers
    return _recorded(study, it, len(swarm_params))


def run_pso(cfg, study, total, workers=1, storage=None, cache_dir=None, progress=True):
    """Run PSO until about ``total`` evaluations (whole swarms); returns the study."""
    params, fixed = structure(cfg)
    rng = np.random.default_rng(cfg.seed)
    n, dim = cfg.pso.particles, len(params)
    iters = max(1, min(cfg.pso.iterations, total // n))
    x = rng.random((n, dim))
    v = 0.1 * rng.standard_normal((n, dim))
    pbest, pval = x.copy(), np.full(n, np.inf)
    g, gval = x[0].copy(), np.inf
    bar = tqdm(total=iters, disable=not progress, unit="swarm", desc=f"{cfg.name} (PSO)")
    for it in range(iters):
        vals = _evaluate(study, cfg, [to_params(p, params, fixed) for p in x], it, workers,
                         storage, cache_dir)
        better = vals < pval
        pbest[better], pval[better] = x[better], vals[better]
        if pval.min() < gval:
            g, gval = pbest[pval.argmin()].copy(), float(pval.min())
        r1, r2 = rng.random((n, dim)), rng.random((n, dim))
        v = inertia(cfg, it) * v + cfg.pso.c1 * r1 * (pbest - x) + cfg.pso.c2 * r2 * (g - x)
        x = np.clip(x + v, 0.0, 1.0)
        bar.update(1)
    bar.close()
    return study


def _recorded(study, it, n):
    """Values of an iteration's particles in the study (inf where none completed)."""
    vals = np.full(n, np.inf)
    for i, trials in _trials_of(study, it).items():
        done = [t.value for t in trials if t.state == TrialState.COMPLETE]
        if done and i < n:
            vals[i] = done[0]
    return vals
