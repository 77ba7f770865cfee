"""Trials per minute of ``studies/paper000_tune.toml`` with 1 and 2 workers.

Runs the study's configuration (both paper-000 controllers, 9 training runs per trial,
Wilcoxon pruning) in a temporary directory for a fixed number of trials, after simulating the
training logs and compiling the kernels once (the cached state a user has after the first
study), and reports trials per minute and filter runs per second.  The 2-worker figure pays
for starting the worker processes.  Usage: ``python benchmarks/bench_study.py [--trials 60]``.
"""
from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_section  # noqa: E402

from fuzzynav.tuning.config import load_study_config  # noqa: E402
from fuzzynav.tuning.run import prepare_cache, run_study  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def _config_copy(tmp: Path, name: str) -> Path:
    src = (ROOT / "studies" / "paper000_tune.toml").read_text()
    src = src.replace('name = "paper000_tune"', f'name = "{name}"')
    src = src.replace('"../rules/', f'"{ROOT / "rules"}/')
    path = tmp / f"{name}.toml"
    path.write_text(src)
    return path


def measure(trials: int, workers: int, cache: Path, tmp: Path):
    cfg = load_study_config(_config_copy(tmp, f"bench_w{workers}"))
    t0 = time.perf_counter()
    study = run_study(cfg, trials, workers, None, cache, progress=False)
    secs = time.perf_counter() - t0
    runs = sum(t.user_attrs.get("n_runs", 0) for t in study.trials)
    return trials / secs * 60.0, runs / secs, secs


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, default=60)
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="bench-study-"))
    cache = tmp / "cache"
    try:
        warm = load_study_config(_config_copy(tmp, "warm"))
        prepare_cache(warm, cache)
        run_study(warm, 3, 1, None, cache, progress=False)   # compile once
        rows = [(w,) + measure(args.trials, w, cache, tmp) for w in (1, 2)]
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    lines = ["## Study throughput (`benchmarks/bench_study.py`)", "",
             f"`studies/paper000_tune.toml` (both controllers, 9 training runs of 755 s per "
             f"trial, Wilcoxon pruning), {args.trials} trials, data simulated and kernels "
             f"compiled beforehand. Machine: {machine()}; load average "
             f"{os.getloadavg()[0]:.2f} at the end.", "",
             "| workers | trials/min | filter runs/s | wall time (s) |", "|---|---|---|---|"]
    lines += [f"| {w} | {tpm:.0f} | {rps:.1f} | {secs:.1f} |" for w, tpm, rps, secs in rows]
    lines += ["", "Pruned trials stop early, so trials/min exceeds (filter runs/s x 60 / 9). "
              "Two workers include the start-up of two processes (a few seconds)."]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        write_section("study", text)


if __name__ == "__main__":
    main()
