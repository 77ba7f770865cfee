"""Cost of filter banks against the single filter on the same data.

One ``paper000`` log (755 s at 100 Hz, 1-Hz GPS, 5-Hz imaging polarization): ``ekf`` (the
bank of one), ``centralized`` (the same, named as a bank), ``federated-reset`` and
``federated`` (GPS | polarization, equal shares, fused after every update) and ``federated``
fused once a second (``federated-1s``).  Best of several runs each, one core.

Usage: ``python benchmarks/bench_bank.py [--filters ekf,federated] [--no-write]``
(``--filters ekf`` also runs on revisions without banks, to compare against them).
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_section  # noqa: E402
from bench_filter import timed  # noqa: E402
from _fusion_columns import fuse_by_columns, repeat_fusions  # noqa: E402

import numpy as np  # noqa: E402

from fuzzynav.experiment import perturbed_initial_state, setup_for  # noqa: E402
from fuzzynav.filters.bank_fusion import fuse, fusion_work  # noqa: E402
from fuzzynav.filters.runner import run_filter  # noqa: E402
from fuzzynav.sim.sensor_log import simulate  # noqa: E402
from fuzzynav.sim.scenario import load_scenario  # noqa: E402

CASES = {"ekf": ("ekf", {}), "centralized": ("centralized", {}),
         "federated-reset": ("federated-reset", {}), "federated": ("federated", {}),
         "federated-1s": ("federated", {"fusion_period_s": 1.0})}


def best_time(log, name, options, repeat):
    setup = setup_for(log, name, options)
    args = (log.imu, setup.sensors_for(log.sensors), perturbed_initial_state(log, setup),
            setup.config, setup.adapters)
    run_filter(*args)  # compile / warm
    return timed(lambda: run_filter(*args), repeat)[0]


def fusion_table(repeat, n=15, n_local=2, times=2000):
    """The fusion alone, shipped (triangular inverses) against the column inverses it
    replaced, alternating, on two locals' covariances of a ``federated`` run's shape."""
    rng = np.random.default_rng(0)
    scale = np.r_[np.full(3, 1e-2), np.full(3, 1e-1), np.full(3, 3.0), np.full(6, 1e-4)]
    P = np.empty((n_local, n, n))
    for k in range(n_local):
        B = rng.normal(size=(n, n))
        P[k] = scale[:, None] * (B @ B.T / n + 0.2 * np.eye(n)) * scale[None, :]
    x = rng.normal(size=(n_local, n)) * scale
    out = {}
    for name, fn in (("column solves (before)", fuse_by_columns), ("triangular inverse", fuse)):
        Pg, xg = np.zeros((n, n)), np.zeros(n)
        out[name] = (fn, Pg, xg)
        repeat_fusions(fn, P, x, Pg, xg, fusion_work(n), 1)  # compile
    best = dict.fromkeys(out, np.inf)
    for _ in range(repeat):
        for name, (fn, Pg, xg) in out.items():
            t = timed(lambda: repeat_fusions(fn, P, x, Pg, xg, fusion_work(n), times), 1)[0]
            best[name] = min(best[name], t / times)
    (_, P0, x0), (_, P1, x1) = out.values()
    rel = np.abs(P1 - P0).max() / np.abs(P0).max()
    old, new = best.values()
    return ["", f"The fusion alone ({n_local} locals, {n} states, {times} fusions in a compiled "
            f"loop, best of {repeat}, alternating): column solves {old * 1e6:.2f} µs, "
            f"triangular inverse {new * 1e6:.2f} µs ({old / new:.2f}x faster); largest "
            f"difference of the fused covariances {rel:.1e} of its largest entry."]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--filters", default=",".join(CASES))
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--no-write", action="store_true", help="do not update docs/benchmarks.md")
    args = ap.parse_args(argv)
    log = simulate(load_scenario("paper000"), 0, tempfile.mkdtemp())
    n = log.imu.n_samples
    times = {}
    for case in args.filters.split(","):
        name, options = CASES[case]
        times[case] = best_time(log, name, options, args.repeat)
        print(f"{case}: {times[case] * 1e3:.1f} ms", flush=True)
    base = times.get("ekf", next(iter(times.values())))
    lines = ["## Filter banks against the single filter (`benchmarks/bench_bank.py`)", "",
             f"`paper000`, seed 0: {n} IMU samples (1-Hz GPS, 5-Hz imaging polarization), one "
             f"core, best of {args.repeat}. Machine: {machine()}.", "",
             "| filter | run time (ms) | relative |", "|---|---|---|"]
    lines += [f"| {case} | {t * 1e3:.1f} | {t / base:.2f} |" for case, t in times.items()]
    lines += fusion_table(args.repeat)
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        write_section("bank", text)


if __name__ == "__main__":
    main()
