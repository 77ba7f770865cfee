"""Paper 004's APSO study: particle-iterations per minute with warm kernels and loaded data.

Runs the swarm of ``studies/paper004_apso.toml`` (a baseline study on the PSO sampler,
:func:`fuzzynav.tuning.study_run.run_study`, as ``fuzzynav study run`` does) with its
particles and iterations set to make ``--budget`` particle-iterations (10 x 10 for 100),
after the training recordings were loaded and the kernels compiled: the state of a user's
second run.  Each particle-iteration is one fitness, i.e. one run of the SINS/DVL EKF on
every training recording (A-KIT trajectories 1-4, 400 s at 100 Hz each).  Skips with a
message when the recordings are absent (``$FUZZYNAV_DATA``, docs/studies.md).

Usage: ``python benchmarks/bench_apso.py [--budget 100] [--no-write]``.
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_section  # noqa: E402

from fuzzynav.errors import DataMissingError, FuzzynavError  # noqa: E402
from fuzzynav.tuning.baseline_config import load_baseline_config  # noqa: E402
from fuzzynav.tuning.kinds.baseline_studies import BaselinePlan  # noqa: E402
from fuzzynav.tuning.study_run import run_study  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "studies" / "paper004_apso.toml"
#: the A-KIT IMU rate (docs/data.md): converts the recordings' duration to IMU samples
AKIT_IMU_RATE_HZ = 100.0


def shaped(bcfg, budget: int):
    """The config with about ``budget`` particle-iterations, as square as whole numbers go."""
    particles = max(2, round(math.sqrt(budget)))
    iterations = max(1, round(budget / particles))
    pso = dataclasses.replace(bcfg.study.pso, particles=particles, iterations=iterations)
    study = dataclasses.replace(bcfg.study, pso=pso, trials=particles * iterations)
    return dataclasses.replace(bcfg, study=study)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--budget", type=int, default=100, help="particle-iterations")
    ap.add_argument("--no-write", action="store_true", help="print, leave docs/ alone")
    args = ap.parse_args(argv)
    bcfg = shaped(load_baseline_config(CONFIG), args.budget)
    plan = BaselinePlan(bcfg)
    ev = plan.evaluator
    t0 = time.perf_counter()
    try:
        logs = [ev.log(sc, sd) for sc, sd in bcfg.study.train]
    except (DataMissingError, FuzzynavError) as exc:
        print(f"bench_apso: skipped: {exc}")
        return 0
    t_logs = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        # (random: a PSO study would run a whole swarm; the same objective, the same kernels)
        warm = dataclasses.replace(plan.config("apso"), name="warm", sampler="random")
        run_study(warm, 2, 1, f"journal:{tmp}/warm.journal", plan=plan, part="apso",
                  progress=False)   # kernels compiled
        t_warm = time.perf_counter() - t0 - t_logs
        load0, c0, t1 = os.getloadavg()[0], time.process_time(), time.perf_counter()
        study = run_study(plan.config("apso"), None, 1, f"journal:{tmp}/bench.journal",
                          plan=plan, part="apso", progress=False)
        secs, cpu = time.perf_counter() - t1, time.process_time() - c0
        best = study.best_value
    n_pi = bcfg.study.pso.particles * bcfg.study.pso.iterations
    run_s = sum(log.duration_s for log in logs)    # recordings expose no IMU array
    samples = n_pi * run_s * AKIT_IMU_RATE_HZ
    text = "\n".join([
        "## APSO study of paper 004 (`benchmarks/bench_apso.py`)", "",
        f"`studies/paper004_apso.toml` (a baseline study on the PSO sampler) with "
        f"{bcfg.study.pso.particles} particles x {bcfg.study.pso.iterations} iterations = "
        f"{n_pi} particle-iterations, each a fitness of {len(logs)} training recordings "
        f"(A-KIT 1-4, {run_s:.0f} s, {samples / n_pi:,.0f} IMU samples in all), one process, through "
        f"`run_study` as `fuzzynav study run` does; recordings loaded ({t_logs:.1f} s) and "
        f"kernels warm ({t_warm:.1f} s) beforehand. Machine: {machine()}; load average "
        f"{load0:.2f} at the start, {os.getloadavg()[0]:.2f} at the end.", "",
        "| particle-iterations | wall time (s) | CPU time (s) | particle-iterations/min "
        "| IMU samples/s | best fitness (position RMS / EKF's) |", "|---|---|---|---|---|---|",
        f"| {n_pi} | {secs:.1f} | {cpu:.1f} | {n_pi / secs * 60:.0f} | "
        f"{samples / secs:,.0f} | {best:.3f} |", "",
        "Target of issue 10: 100 particle-iterations in under a minute. The CPU time is what "
        "an idle core would need; on a loaded machine the wall time is longer."])
    print(text)
    if not args.no_write:
        write_section("apso", text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
