"""Paper 004's adaptive PSO of the Q and R diagonals (``studies/paper004_apso.toml``).

The study machinery of :mod:`fuzzynav.tuning.study` tunes rule files; the APSO of paper 004
tunes constant noise multipliers, so it is this small driver instead::

    python -m fuzzynav.tuning.apso studies/paper004_apso.toml \
        --out studies/paper004_apso.result.json

Each particle is a vector of log10 multipliers (``[apso.bounds]``: key -> [lo, hi]; keys of
:mod:`fuzzynav.filters.tuned_qr`); fitness = mean over the training runs of the RMS
horizontal position error against the truth (the paper's f(Q, R) over a window of M epochs:
``window_s``).  Velocity update with the inertia weight decreasing linearly from
``[study.pso] inertia[0]`` to ``inertia[1]`` (:func:`fuzzynav.tuning.pso.inertia`, the same
schedule as the rule-file PSO).  The result file holds the best multipliers, the
convergence history, the test table and an ``expected`` block that
``tests/tuning/test_apso.py`` re-runs.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from fuzzynav.errors import FuzzynavError, InputFileError
from fuzzynav.experiment import run_on_log
from fuzzynav.fileio import publish
from fuzzynav.filters.tuned_qr import Q_KEYS, check_multipliers
from fuzzynav.metrics import errors_vs_trajectory, rms_metrics
from fuzzynav.sim.log import simulate
from fuzzynav.sim.scenario import load_scenario
from fuzzynav.sim.tomltable import Table, read_toml, with_path
from fuzzynav.tuning.pso import inertia

FITNESS = "rms_pos_h_m"


@dataclass(frozen=True)
class ApsoConfig:
    """A parsed ``paper004_apso.toml`` (errors name the file and key)."""

    path: Path
    name: str
    seed: int
    pso: SimpleNamespace          # particles, iterations, inertia, c1, c2
    bounds: dict                  # multiplier key -> (lo, hi) of log10
    window_s: tuple
    train: list                   # (scenario, seed)
    test: list
    compare: tuple

    @classmethod
    def load(cls, path) -> "ApsoConfig":
        path = Path(path)
        with with_path(path):
            t = Table(read_toml(path, "APSO study file"), "")
            name = t.string("name")
            t.string("description", "")
            st = t.table("study")
            st.string("sampler", "pso", choices=("pso",))
            seed = st.integer("seed", 0, lo=0)
            p = st.table("pso")
            pso = SimpleNamespace(particles=p.integer("particles", 8, lo=2, hi=200),
                                  iterations=p.integer("iterations", 10, lo=1, hi=1000),
                                  inertia=p.vector("inertia", 2, (0.9, 0.4), lo=0.0, hi=1.0),
                                  c1=p.number("c1", 1.5, lo=0.0), c2=p.number("c2", 1.5, lo=0.0))
            if not pso.inertia[0] >= pso.inertia[1]:
                raise p.error("inertia", "the start weight must be >= the end weight")
            p.finish()
            st.finish()
            a = t.table("apso")
            b = a.table("bounds")
            bounds = {k: b.vector(k, 2, broadcast=False, lo=-6.0, hi=6.0) for k in list(b.data)}
            check_multipliers({k: 1.0 for k in bounds}, path, "apso.bounds.")
            for k, (lo, hi) in bounds.items():
                if not lo < hi:
                    raise b.error(k, f"needs lo < hi, got {[lo, hi]}")
            b.finish()
            window = a.vector("window_s", 2, (0.0, 1e9), lo=0.0, broadcast=False)
            a.finish()
            runs = {}
            for part in ("train", "test"):
                s = t.table(part)
                scen, compare = _strings(s, "scenarios"), tuple(_strings(s, "compare"))
                seeds = _list(s, "seeds", int)
                s.finish()
                if not scen or not seeds:
                    raise s.error("scenarios", "needs scenarios and seeds")
                runs[part] = ([(sc, int(sd)) for sc in scen for sd in seeds], compare)
            t.finish()
        return cls(path, name, seed, pso, bounds, tuple(window), runs["train"][0],
                   runs["test"][0], runs["test"][1] or ("ekf",))


def _list(t: Table, key: str, kind) -> list:
    """An optional array of ``kind`` values (strings, or non-negative integers)."""
    value, _ = t._get(key, [])
    if not isinstance(value, list) or not all(
            isinstance(v, kind) and not isinstance(v, bool) and (kind is str or v >= 0)
            for v in value):
        raise t.error(key, f"must be an array of {kind.__name__} values, got {value!r}")
    return list(value)


def _strings(t: Table, key: str) -> list:
    return _list(t, key, str)


class Fitness:
    """Training-run fitness of multiplier vectors, with the logs cached in memory."""

    def __init__(self, cfg: ApsoConfig, cache_dir=None):
        self.cfg, self.cache_dir, self._logs = cfg, cache_dir, {}

    def log(self, scenario, seed):
        key = (scenario, seed)
        if key not in self._logs:
            self._logs[key] = simulate(load_scenario(self._resolve(scenario)), seed,
                                       self.cache_dir)
        return self._logs[key]

    def _resolve(self, scenario):
        p = self.cfg.path.parent / scenario
        return str(p) if p.suffix == ".toml" and p.is_file() else scenario

    def metrics(self, mult: dict, scenario, seed) -> dict:
        out = run_on_log(self.log(scenario, seed), "apso", mult)
        err = errors_vs_trajectory(out.result, self.log(scenario, seed).truth)
        lo, hi = self.cfg.window_s
        sel = (err.time_s >= lo) & (err.time_s <= hi)
        windowed = rms_metrics(type(err)(err.time_s[sel], err.pos_m[sel], err.vel_mps[sel],
                                         err.att_rad[sel]))
        return {**out.metrics, "fitness": windowed[FITNESS] if out.result.ok else np.inf}

    def __call__(self, mult: dict) -> float:
        return float(np.mean([self.metrics(mult, sc, sd)["fitness"]
                              for sc, sd in self.cfg.train]))


def multipliers(cfg: ApsoConfig, u) -> dict:
    """A point of [0, 1]^D as multipliers (log10-uniform within the bounds)."""
    return {k: float(10.0 ** (lo + ui * (hi - lo)))
            for ui, (k, (lo, hi)) in zip(u, cfg.bounds.items())}


def run_apso(cfg: ApsoConfig, fitness=None, progress=print) -> dict:
    """Run the swarm; returns ``{"best", "best_fitness", "history"}``."""
    fitness = fitness or Fitness(cfg)
    rng = np.random.default_rng(cfg.seed)
    n, dim = cfg.pso.particles, len(cfg.bounds)
    x = rng.random((n, dim))
    x[0] = [(-lo) / (hi - lo) for lo, hi in cfg.bounds.values()]  # the EKF (all 1) if inside
    x = np.clip(x, 0.0, 1.0)
    v = 0.1 * rng.standard_normal((n, dim))
    pbest, pval = x.copy(), np.full(n, np.inf)
    g, gval, history = x[0].copy(), np.inf, []
    for it in range(cfg.pso.iterations):
        vals = np.array([fitness(multipliers(cfg, p)) for p in x])
        better = vals < pval
        pbest[better], pval[better] = x[better], vals[better]
        if pval.min() < gval:
            g, gval = pbest[pval.argmin()].copy(), float(pval.min())
        w = inertia(cfg, it)
        history.append({"iteration": it, "inertia": w, "best": gval,
                        "swarm_mean": float(np.mean(vals[np.isfinite(vals)]))})
        progress(f"iteration {it}: inertia {w:.3f}, best {gval:.4f} m")
        r1, r2 = rng.random((n, dim)), rng.random((n, dim))
        v = w * v + cfg.pso.c1 * r1 * (pbest - x) + cfg.pso.c2 * r2 * (g - x)
        x = np.clip(x + v, 0.0, 1.0)
    return {"best": multipliers(cfg, g), "best_fitness": gval, "history": history}


def result_document(cfg: ApsoConfig, found: dict, fitness: Fitness) -> dict:
    """The result file: multipliers, provenance, history, test metrics, ``expected``."""
    best = found["best"]
    test = [{"scenario": sc, "seed": sd, FITNESS: {
        f: fitness.metrics(best if f == "apso" else {}, sc, sd)[FITNESS] if f == "apso"
        else run_on_log(fitness.log(sc, sd), f).metrics[FITNESS]
        for f in ("apso", *cfg.compare)}} for sc, sd in cfg.test]
    sc, sd = cfg.test[0]
    exp = fitness.metrics(best, sc, sd)
    return {"multipliers": best,
            "provenance": {"study": cfg.name, "config": cfg.path.name, "seed": cfg.seed,
                           "pso": vars(cfg.pso) | {"inertia": list(cfg.pso.inertia)},
                           "bounds_log10": {k: list(b) for k, b in cfg.bounds.items()},
                           "train": cfg.train, "fitness": f"mean {FITNESS} over the train runs",
                           "best_fitness": found["best_fitness"]},
            "history": found["history"], "test": test,
            "expected": {"filter": "apso", "scenario": sc, "seed": sd,
                         "metrics": {k: exp[k] for k in (FITNESS, "mean_pos_h_m",
                                                         "rms_vel_mps")}}}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m fuzzynav.tuning.apso", description=__doc__)
    ap.add_argument("config")
    ap.add_argument("--out", required=True)
    # the training logs are simulated once into the cache and read from it by every later run
    ap.add_argument("--cache", metavar="DIR", help="simulation cache (default: $FUZZYNAV_CACHE "
                    "or ~/.cache/fuzzynav, as fuzzynav study run)",
                    default=os.environ.get("FUZZYNAV_CACHE",
                                           str(Path.home() / ".cache" / "fuzzynav")))
    args = ap.parse_args(argv)
    try:
        cfg = ApsoConfig.load(args.config)
        fit = Fitness(cfg, args.cache)
        doc = result_document(cfg, run_apso(cfg, fit), fit)
        out = Path(args.out)
        tmp = out.with_name(f".{out.name}.tmp")
        tmp.write_text(json.dumps(doc, indent=2) + "\n")
        publish(tmp, out)
    except (FuzzynavError, InputFileError) as exc:
        print(f"apso: error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
