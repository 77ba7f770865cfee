"""Speed of the fuzzy engine against scikit-fuzzy, measured in one run (issue 2).

System (the issue's): 2 inputs x 3 triangular terms (strong partition on [-1, 1]),
3 x 3 rules, 5 triangular output terms on [0, 1], min / max / min / max / centroid.

Figures:
1. batch of 100 000 random inputs: ``FuzzySystem.evaluate`` (exact, compiled kernel)
   against scikit-fuzzy's ControlSystemSimulation given the same arrays;
2. one evaluation through the compiled form inside a numba loop (``eval_compiled``).

Each figure carries the largest output difference to a reference: scikit-fuzzy against
fuzzynav's exact value, fuzzynav against its pure-Python exact path.  The results go
into docs/benchmarks.md between the fuzzy markers (the rest of the file is kept).

Run: ``python benchmarks/bench_fuzzy.py [--n 100000] [--no-write]``
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numba
import numpy as np
from _report import DOC, machine, write_section

from fuzzynav.fuzzy import load_fis, to_skfuzzy
from fuzzynav.fuzzy.compiled import eval_compiled, eval_compiled_batch


def issue_system():
    """The issue's benchmark system (see the module docstring)."""
    part = [{"name": "NS", "mf": "tri", "params": [-2.0, -1.0, 0.0]},
            {"name": "ZE", "mf": "tri", "params": [-1.0, 0.0, 1.0]},
            {"name": "PS", "mf": "tri", "params": [0.0, 1.0, 2.0]}]
    out = [{"name": f"o{k}", "mf": "tri", "params": [0.25 * k - 0.25, 0.25 * k, 0.25 * k + 0.25]}
           for k in range(5)]
    rules = [{"if": {"a": p, "b": q}, "then": {"y": f"o{i + j}"}}
             for i, p in enumerate(("NS", "ZE", "PS")) for j, q in enumerate(("NS", "ZE", "PS"))]
    return load_fis({
        "format": "fuzzynav-fis", "version": 1, "name": "bench-2x3", "type": "mamdani",
        "operators": {"and": "min", "or": "max", "implication": "min", "aggregation": "max",
                      "defuzzifier": "centroid"},
        "inputs": [{"name": n, "range": [-1.0, 1.0], "terms": part} for n in ("a", "b")],
        "outputs": [{"name": "y", "range": [0.0, 1.0], "terms": out}], "rules": rules})


def best_time(fn, repeat=5):
    """Smallest wall time of ``repeat`` calls (after one warm-up call)."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


@numba.njit(cache=True)
def _loop(fp, ip, X, y, work):
    acc = 0.0
    for k in range(X.shape[0]):
        eval_compiled(fp, ip, X[k], y, work)
        acc += y[0]
    return acc


def bench_batch(fis, X):
    inputs = {"a": X[:, 0], "b": X[:, 1]}
    t_ours = best_time(lambda: fis.evaluate(inputs))
    ours = fis.evaluate(inputs)["y"]
    cf = fis.compile()
    t_kernel = best_time(lambda: eval_compiled_batch(cf.fparams, cf.iparams, X))
    ref = fis.evaluate({"a": X[:2000, 0], "b": X[:2000, 1]}, engine="python")["y"]
    from skfuzzy import control as ctrl

    sim = ctrl.ControlSystemSimulation(to_skfuzzy(fis, 101))
    sim.input["a"], sim.input["b"] = X[:, 0], X[:, 1]
    t0 = time.perf_counter()
    sim.compute()
    t_sk = time.perf_counter() - t0
    sk = np.asarray(sim.output["y"])
    n = len(X)
    return {"n": n, "ours_rate": n / t_ours, "kernel_rate": n / t_kernel, "sk_rate": n / t_sk,
            "speedup": t_sk / t_ours, "sk_diff": float(np.max(np.abs(sk - ours))),
            "ours_diff": float(np.max(np.abs(ours[:2000] - ref)))}


def bench_single(fis, X):
    cf = fis.compile()
    work = np.empty(cf.work_size)
    y = np.empty(cf.n_outputs)
    t = best_time(lambda: _loop(cf.fparams, cf.iparams, X, y, work))
    from skfuzzy import control as ctrl

    sim = ctrl.ControlSystemSimulation(to_skfuzzy(fis, 101))
    m = 300
    t0 = time.perf_counter()
    for a, b in X[:m]:
        sim.input["a"], sim.input["b"] = a, b
        sim.compute()
    t_sk = (time.perf_counter() - t0) / m
    single = np.array([_one(cf, row, work, y) for row in X[:2000]])
    ref = fis.evaluate({"a": X[:2000, 0], "b": X[:2000, 1]}, engine="python")["y"]
    return {"us": 1e6 * t / len(X), "sk_us": 1e6 * t_sk,
            "diff": float(np.max(np.abs(single - ref)))}


def _one(cf, row, work, y):
    eval_compiled(cf.fparams, cf.iparams, np.ascontiguousarray(row), y, work)
    return y[0]


def machine_line(load: float | None) -> str:
    """The shared machine description plus scipy / scikit-fuzzy versions and the load."""
    import scipy
    import skfuzzy

    busy = "" if load is None else f"; load average {load:.2f} when the run started"
    return (f"{machine()}; scipy {scipy.__version__}, scikit-fuzzy {skfuzzy.__version__}"
            f"{busy}")


def section(batch, single, load) -> str:
    return f"""## Fuzzy engine (`benchmarks/bench_fuzzy.py`)

{machine_line(load)}.
System: 2 inputs x 3 triangular terms, 3 x 3 rules, 5 triangular output terms,
min / max / min implication / max aggregation / centroid.  scikit-fuzzy is measured in the
same run through `to_skfuzzy(fis, 101)` (101-point universes, as usually used).

| figure | fuzzynav | scikit-fuzzy | ratio | max output difference |
|---|---|---|---|---|
| batch of {batch['n']:,} inputs, evaluations/s (`FuzzySystem.evaluate`) | {batch['ours_rate']:,.0f} | {batch['sk_rate']:,.0f} | {batch['speedup']:,.0f}x | skfuzzy vs exact: {batch['sk_diff']:.1e}; fuzzynav vs its Python exact path: {batch['ours_diff']:.1e} |
| same batch, raw serial kernel (`eval_compiled_batch`), evaluations/s | {batch['kernel_rate']:,.0f} | | | |
| one evaluation, µs per call (`eval_compiled` in a numba loop / skfuzzy `compute()`) | {single['us']:.2f} | {single['sk_us']:,.0f} | {single['sk_us'] / single['us']:,.0f}x | vs Python exact path: {single['diff']:.1e} |

Targets of issue 2: >= 1 M evaluations/s and >= 100x scikit-fuzzy on the batch; <= 2 µs per
compiled call.  `FuzzySystem.evaluate` splits batches of 20 000 or more over the cores
(numba `prange`); the serial kernel rate is the single-core figure.  The machine is shared:
rerun on an idle one for clean figures.
"""


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=100_000, help="batch size (default 100000)")
    parser.add_argument("--no-write", action="store_true", help="print, do not write the docs")
    args = parser.parse_args(argv)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    fis = issue_system()
    X = np.random.default_rng(2026).uniform(-1.0, 1.0, (args.n, 2))
    batch = bench_batch(fis, X)
    single = bench_single(fis, X)
    text = section(batch, single, load)
    print(text)
    if not args.no_write:
        write_section("fuzzy", text)
        print(f"wrote {DOC}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
