"""Trials per minute of ``studies/paper000_tune.toml`` run whole, streamed on held logs and
streamed on logs simulated again for every run (its ``[streaming]`` table), in one run.

Each measurement is one ``run_study`` of a fresh study (one worker, random sampler with the
study's seed, no pruning: every trial runs all 9 training runs, the same candidates in the
three ways) in its own Python process, after the training logs were simulated into the
cache and the kernels compiled.  *whole*: the study as it is; *streamed, held*: with
``[streaming] chunk_s = 300, output_rate_hz = 10`` (the filter's own output rate: nothing
decimated), each run's log held and cut into chunks; *streamed, long*: the same with
``hold_log_mb = 0``, every run simulated again chunk by chunk (what a study does with runs
too long to hold).  The measurements of a round are interleaved, in reversed order every
other round; medians over the rounds.  The trial values are compared across the three ways.

Usage: ``python benchmarks/bench_study_stream.py [--trials 40] [--long-trials 3]
[--rounds 3]`` (about 6 minutes on the 2-core machine).
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


def agreement(rounds: list) -> str:
    """How the trial values of the three ways agree (the same candidates, trial by trial)."""
    def rel(a, b):
        return max(abs(x - y) / abs(y) for x, y in zip(a, b))

    held = [rel(r["streamed, held"]["values"], r["whole"]["values"]) for r in rounds]
    same = all(r["streamed, long"]["values"] == r["streamed, held"]["values"][
        :len(r["streamed, long"]["values"])] for r in rounds)
    return (f"The trial values of the held streamed study differ from the whole study's by "
            f"at most {max(held):.1e} relative (the order of the RMS sums); the long "
            f"study's trials are the held study's first trials to the bit: {same}.")


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
        tpm = [r[way]["tpm"] for r in rounds]
        ratio = statistics.median(r[way]["tpm"] / r["whole"]["tpm"] for r in rounds)
        lines.append(f"| {way} | {statistics.median(tpm):.1f} | "
                     + ", ".join(f"{v:.1f}" for v in tpm) + f" | {ratio:.2f} |")
    lines += ["", agreement(rounds), "",
              "Each study's time includes its start-up in the process: loading the nine logs "
              "(from the cache; the long way makes each run's first chunk instead) and the "
              "baseline's nine runs. The long way simulates every run again for every trial, "
              "so its rate is the simulation's, not the filter's: it is what a study on runs "
              "too long to hold costs, memory bounded by the chunk."]
    return "\n".join(lines)


def main(argv=None):
    args = bench_parser(__doc__, trials=40, long_trials=3, rounds=3).parse_args(argv)
    trials = {"whole": args.trials, "streamed, held": args.trials,
              "streamed, long": args.long_trials}

    def measure_all(tmp):
        for i, way in enumerate(WAYS):  # simulate the logs, load or compile the kernels
            measure(tmp, f"warm_{i}", way, 1)
        return run_rounds(tmp, trials, args.rounds)

    measured_section("study-stream", args, measure_all, report)

if __name__ == "__main__":
    main()
