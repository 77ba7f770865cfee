"""Trials per minute of ``studies/paper000_tune.toml`` with 1 and 2 workers, side by side
against a base revision, in one run.

Each measurement is one ``run_study`` of a fresh study for a fixed number of trials, in its
own Python process (``PYTHONPATH`` = this tree or the base revision's tree, extracted with
``git archive``), after the training logs were simulated and the kernels compiled once per
tree (the state a user has after the first study).  The four measurements of a round (base
and this tree, 1 and 2 workers) are interleaved, in reversed order every other round, so
that a change of the machine's load hits both trees alike; the ratios are taken per round
and their median reported.  Two workers include everything a user waits for: starting the
worker processes, loading logs and kernels, running the baseline.

Usage: ``python benchmarks/bench_study.py [--base 98740c8] [--trials 60] [--rounds 3]``
(about 5 minutes on the idle 2-core machine once both trees' kernels are compiled; a cold
kernel cache adds about a minute and a half per tree).
"""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

import optuna

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import bench_parser, machine, measured_section  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
STUDY = "paper000_tune.toml"
#: the measured program, run with PYTHONPATH = the tree under test
RUNNER = """
import json, sys, time
import fuzzynav
from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.study_run import run_study
cfg = load_study_config(sys.argv[1])
t0 = time.perf_counter()
study = run_study(cfg, int(sys.argv[2]), int(sys.argv[3]), None, sys.argv[4], progress=False)
secs = time.perf_counter() - t0
runs = sum(t.user_attrs.get("n_runs", 0) for t in study.trials)
print(json.dumps({"secs": secs, "trials": len(study.trials), "runs": runs,
                  "package": fuzzynav.__file__}))
"""


def config_copy(tree: Path, tmp: Path, name: str) -> Path:
    """The tree's paper000_tune.toml renamed ``name``, its rule files named absolutely."""
    src = (tree / "studies" / STUDY).read_text()
    src = src.replace('name = "paper000_tune"', f'name = "{name}"')
    src = src.replace('"../rules/', f'"{tree / "rules"}/')
    path = tmp / f"{name}.toml"
    path.write_text(src)
    return path


def measure(tree: Path, tmp: Path, name: str, trials: int, workers: int) -> dict:
    """One study of ``trials`` trials with ``workers`` workers, in a fresh process."""
    cfg = config_copy(tree, tmp, name)
    env = dict(os.environ, PYTHONPATH=str(tree), PYTHONWARNINGS="ignore")
    out = subprocess.run([sys.executable, "-c", RUNNER, str(cfg), str(trials), str(workers),
                          str(tmp / f"cache-{tree.name}")], env=env, cwd=tmp, check=True,
                         capture_output=True, text=True)
    res = json.loads(out.stdout.strip().splitlines()[-1])
    if not Path(res["package"]).resolve().is_relative_to(tree.resolve()):
        raise RuntimeError(f"{name} imported fuzzynav from {res['package']}, not {tree}")
    return dict(res, tpm=res["trials"] / res["secs"] * 60.0, rps=res["runs"] / res["secs"])


def base_tree(rev: str, tmp: Path) -> Path:
    """The base revision's files, extracted into ``tmp/base``."""
    dest = tmp / "base"
    dest.mkdir()
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev], check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
    return dest


def run_rounds(trees: dict, tmp: Path, trials: int, rounds: int) -> list:
    """``rounds`` rounds of the four interleaved measurements: ``[{(tree, workers): res}]``."""
    order = [(t, w) for w in (1, 2) for t in trees]
    out = []
    for r in range(rounds):
        res = {}
        for label, w in (order if r % 2 == 0 else order[::-1]):
            res[(label, w)] = measure(trees[label], tmp, f"bench_{label}_w{w}_r{r}", trials, w)
            print(f"round {r}: {label:4s} {w} worker(s): {res[(label, w)]['tpm']:6.0f} "
                  f"trials/min", flush=True)
        out.append(res)
    return out


def ratios(rounds: list) -> dict:
    """Median over rounds of the ratios the issue asks about."""
    def med(f):
        vals = [f(r) for r in rounds]
        return statistics.median(vals), vals

    return {
        "2 workers / 1 worker, this tree": med(lambda r: r[("new", 2)]["tpm"]
                                               / r[("new", 1)]["tpm"]),
        "2 workers / 1 worker, base": med(lambda r: r[("base", 2)]["tpm"]
                                          / r[("base", 1)]["tpm"]),
        "this tree / base, 2 workers": med(lambda r: r[("new", 2)]["tpm"]
                                           / r[("base", 2)]["tpm"]),
        "this tree / base, 1 worker": med(lambda r: r[("new", 1)]["tpm"]
                                          / r[("base", 1)]["tpm"]),
    }


def report(args, rounds: list, load: tuple, secs: float) -> str:
    lines = ["## Study throughput (`benchmarks/bench_study.py`)", "",
             f"`studies/{STUDY}` (both controllers, 9 training runs of 755 s per trial, "
             f"Wilcoxon pruning), {args.trials} trials per study, this tree against "
             f"`{args.base}` in the same run: {args.rounds} rounds of the four studies "
             "interleaved (order reversed every other round), each in a fresh process, data "
             "simulated and kernels compiled beforehand. Machine: "
             f"{machine()}; Optuna {optuna.__version__} (what `pip install` resolves on "
             f"this date; both trees on it); load average {load[0]:.2f} at the start, {load[1]:.2f} at the end; "
             f"{secs / 60:.1f} min in all.", "",
             "| tree | workers | trials/min (median) | filter runs/s (median) | per round |",
             "|---|---|---|---|---|"]
    for label, name in (("base", f"`{args.base}`"), ("new", "this tree")):
        for w in (1, 2):
            tpm = [r[(label, w)]["tpm"] for r in rounds]
            rps = [r[(label, w)]["rps"] for r in rounds]
            lines.append(f"| {name} | {w} | {statistics.median(tpm):.0f} | "
                         f"{statistics.median(rps):.1f} | "
                         + ", ".join(f"{v:.0f}" for v in tpm) + " |")
    lines += ["", "| ratio | median | per round |", "|---|---|---|"]
    for what, (m, vals) in ratios(rounds).items():
        lines.append(f"| {what} | {m:.2f} | " + ", ".join(f"{v:.2f}" for v in vals) + " |")
    if max(load) > (os.cpu_count() or 1):
        lines += ["", f"**The machine was loaded** (load average above its {os.cpu_count()} "
                  "cores): a second worker finds no free core, so the ratios of 2 to 1 workers "
                  "say nothing about scaling; rerun on an idle machine."]
    lines += ["", "Pruned trials stop early, so trials/min exceeds filter runs/s x 60 / 9, and "
              "the pruning pattern differs between one and two workers (trials finish in "
              "another order). Two workers include their start-up: forked from the warm "
              "parent in this tree, new interpreters that load kernels, logs and baselines "
              "in the base."]
    return "\n".join(lines)


def main(argv=None):
    ap = bench_parser(__doc__, trials=60, rounds=3)
    ap.add_argument("--base", default="98740c8", help="git revision to compare against")
    args = ap.parse_args(argv)

    def measure_all(tmp):
        trees = {"base": base_tree(args.base, tmp), "new": ROOT}
        for label, tree in trees.items():  # simulate the logs, load or compile the kernels
            measure(tree, tmp, f"warm_{label}", 3, 1)
        return run_rounds(trees, tmp, args.trials, args.rounds)

    measured_section("study", args, measure_all, report)


if __name__ == "__main__":
    main()
