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

from fuzzynav.experiment import perturbed_initial_state, setup_for  # noqa: E402
from fuzzynav.filters.runner import run_filter  # noqa: E402
from fuzzynav.sim.log import simulate  # noqa: E402
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
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        write_section("bank", text)


if __name__ == "__main__":
    main()
