"""Trials per minute of ``studies/paper000_tune.toml`` run whole, streamed on held logs and
streamed on logs simulated again for every run (its ``[streaming]`` table), in one run.

Each measurement is one ``run_study`` of a fresh study (one worker, random sampler with the
study's seed, no pruning: every trial runs all 9 training runs, the same candidates in the
three ways) in its own Python process, after the training logs were simulated into the
cache and the kernels compiled.  *whole*: the study as it is; *streamed, held*: with
``[streaming] chunk_s = 300, output_rate_hz = 10`` (the filter's own output rate: nothing
decimated), each run's log held and, its outputs fitting ``hold_log_mb``, filtered in one
piece with its metrics streamed (cut into chunks it gives the same values to the bit:
``fuzzynav.block_sums``); *streamed, long*: the same with
``hold_log_mb = 0``, every run simulated again chunk by chunk (what a study does with runs
too long to hold).  The measurements of a round are interleaved, in reversed order every
other round; medians over the rounds.  The trial values are compared across the three ways.

Then ``--paired-rounds`` pairs of a whole and a held study of ``--paired-trials`` trials,
alternated in one process, give the held way's rate without the spread between processes.

Usage: ``python benchmarks/bench_study_stream.py [--trials 40] [--long-trials 3]
[--rounds 3] [--paired-rounds 8] [--paired-trials 15]`` (about 8 minutes on the 2-core
machine).
"""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import bench_parser, machine, measured_section  # noqa: E402
from bench_study import config_copy  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: the measured program: one study, its time and its trial values
RUNNER = """
import json, sys, time
from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.study_run import run_study
cfg = load_study_config(sys.argv[1])
t0 = time.perf_counter()
study = run_study(cfg, int(sys.argv[2]), 1, None, sys.argv[3], progress=False)
secs = time.perf_counter() - t0
print(json.dumps({"secs": secs, "values": [t.value for t in study.trials]}))
"""
#: the paired program: whole and held studies alternated in one process, their times
PAIRED = """
import json, sys, time
from fuzzynav.tuning.study_config import load_study_config
from fuzzynav.tuning.study_run import run_study
files, trials, rounds, cache = sys.argv[1:3], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
out = {"whole": [], "held": []}
for r in range(-1, rounds):  # round -1 warms the process up and is not kept
    ways = [("whole", files[0]), ("held", files[1])]
    for way, path in (ways if r % 2 == 0 else ways[::-1]):
        cfg = load_study_config(path.replace(".toml", f"_{r + 1}.toml"))
        t0 = time.perf_counter()
        run_study(cfg, trials, 1, None, cache, progress=False)
        if r >= 0:
            out[way].append(time.perf_counter() - t0)
print(json.dumps(out))
"""
#: the three ways: the [streaming] table appended to the study file (None: whole)
WAYS = {"whole": None,
        "streamed, held": "[streaming]\nchunk_s = 300.0\noutput_rate_hz = 10.0\n",
        "streamed, long": "[streaming]\nchunk_s = 300.0\noutput_rate_hz = 10.0\n"
                          "hold_log_mb = 0.0\n"}


def study_file(tmp: Path, name: str, way: str) -> Path:
    """paper000_tune.toml with a random sampler, no pruning and ``way``'s table."""
    path = config_copy(ROOT, tmp, name)
    text = path.read_text().replace('sampler = "tpe"', 'sampler = "random"')
    text = text.replace('pruner = "wilcoxon"', 'pruner = "none"')
    table = WAYS[way]
    if table:  # before the [[controllers]] tables: a top-level table of its own
        head, sep, tail = text.partition("[[controllers]]")
        text = head + table + "\n" + sep + tail
    path.write_text(text)
    return path


def measure(tmp: Path, name: str, way: str, trials: int) -> dict:
    """One study of ``trials`` trials, ``way``, in a fresh process."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), PYTHONWARNINGS="ignore")
    out = subprocess.run([sys.executable, "-c", RUNNER, str(study_file(tmp, name, way)),
                          str(trials), str(tmp / "cache")], env=env, cwd=tmp, check=True,
                         capture_output=True, text=True)
    res = json.loads(out.stdout.strip().splitlines()[-1])
    return dict(res, tpm=len(res["values"]) / res["secs"] * 60.0)


def run_rounds(tmp: Path, trials: dict, rounds: int) -> list:
    out = []
    for r in range(rounds):
        res = {}
        for way in (list(WAYS) if r % 2 == 0 else list(WAYS)[::-1]):
            res[way] = measure(tmp, f"bench_{r}_{len(res)}", way, trials[way])
            print(f"round {r}: {way:15s} {res[way]['tpm']:7.1f} trials/min", flush=True)
        out.append(res)
    return out


def measure_paired(tmp: Path, trials: int, rounds: int) -> dict:
    """``rounds`` pairs of whole and held studies of ``trials`` trials in one process, the
    order reversed every other pair: the ratio of their rates pair by pair."""
    stems = {}
    for way, key in (("whole", "whole"), ("streamed, held", "held")):
        for r in range(rounds + 1):  # a study of its own per pair: nothing resumed
            study_file(tmp, f"paired_{key}_{r}", way)  # tmp/paired_KEY_R.toml
        stems[key] = str(tmp / f"paired_{key}.toml")
    env = dict(os.environ, PYTHONPATH=str(ROOT), PYTHONWARNINGS="ignore")
    out = subprocess.run([sys.executable, "-c", PAIRED, stems["whole"], stems["held"],
                          str(trials), str(rounds), str(tmp / "cache")], env=env, cwd=tmp,
                         check=True, capture_output=True, text=True)
    got = json.loads(out.stdout.strip().splitlines()[-1])
    return {"trials": trials, "ratios": [w / h for w, h in zip(got["whole"], got["held"])]}


def paired_line(paired: dict) -> str:
    """The paired measurement's sentence."""
    q = paired["ratios"]
    return (f"**In one process** (`--paired-rounds`: the imports, numba's cache and the "
            f"process's memory layout shared by both ways), {len(q)} pairs of "
            f"{paired['trials']}-trial studies, whole and held alternated: the held way's "
            f"rate is {statistics.median(q):.3f} of the whole way's (pairs: min "
            f"{min(q):.3f}, max {max(q):.3f}): the gap without the processes' own spread.")


def agreement(rounds: list) -> str:
    """How the trial values of the three ways agree (the same candidates, trial by trial)."""
    def rel(a, b):
        return max(abs(x - y) / abs(y) for x, y in zip(a, b))

    held = [rel(r["streamed, held"]["values"], r["whole"]["values"]) for r in rounds]
    equal = all(r["streamed, held"]["values"] == r["whole"]["values"] for r in rounds)
    same = all(r["streamed, long"]["values"] == r["whole"]["values"][
        :len(r["streamed, long"]["values"])] for r in rounds)
    return (f"The trial values of the held streamed study equal the whole study's to the bit: "
            f"{equal} (largest relative difference {max(held):.1e}); the long study's "
            f"trials are the whole study's first trials to the bit: {same}.")


def report(args, rounds: list, load: tuple, secs: float) -> str:
    lines = ["## A study streamed: trials per minute (`benchmarks/bench_study_stream.py`)", "",
             "`studies/paper000_tune.toml` (both controllers, 9 training runs of 755 s at "
             "100 Hz per trial) with a random sampler and no pruning, one worker, each study "
             "a fresh process, logs simulated into the cache and kernels compiled beforehand; "
             f"{args.rounds} rounds, the three ways interleaved (order reversed every other "
             f"round), {args.trials} trials (the long way {args.long_trials}). Machine: "
             f"{machine()}; load average {load[0]:.2f} at the start, {load[1]:.2f} at the "
             f"end; {secs / 60:.1f} min in all.", "",
             "| way | trials/min (median) | per round | / whole (median) |", "|---|---|---|---|"]
    for way in WAYS:
        tpm = [r[way]["tpm"] for r in rounds["fresh"]]
        ratio = statistics.median(r[way]["tpm"] / r["whole"]["tpm"] for r in rounds["fresh"])
        lines.append(f"| {way} | {statistics.median(tpm):.1f} | "
                     + ", ".join(f"{v:.1f}" for v in tpm) + f" | {ratio:.2f} |")
    lines += ["", agreement(rounds["fresh"]), "", paired_line(rounds["paired"]), "",
              "Each study's time includes its start-up in the process: loading the nine logs "
              "(from the cache; the long way makes each run's first chunk instead) and the "
              "baseline's nine runs. The long way simulates every run again for every trial, "
              "so its rate is the simulation's, not the filter's: it is what a study on runs "
              "too long to hold costs, memory bounded by the chunk."]
    return "\n".join(lines)


def main(argv=None):
    args = bench_parser(__doc__, trials=40, long_trials=3, rounds=3, paired_rounds=8,
                        paired_trials=15).parse_args(argv)
    trials = {"whole": args.trials, "streamed, held": args.trials,
              "streamed, long": args.long_trials}

    def measure_all(tmp):
        for i, way in enumerate(WAYS):  # simulate the logs, load or compile the kernels
            measure(tmp, f"warm_{i}", way, 1)
        return {"fresh": run_rounds(tmp, trials, args.rounds),
                "paired": measure_paired(tmp, args.paired_trials, args.paired_rounds)}

    measured_section("study-stream", args, measure_all, report)

if __name__ == "__main__":
    main()
