"""An alignment run whole against the same run simulated and mechanized in chunks.

``fuzzynav compare SCN --filters align-kf,align-fuzzy --json`` (whole) against the same
with ``--chunk 60`` (streamed), ``SCN`` paper002-gusts (swaying base, gusts: every term of
the simulation at work) lengthened to each duration, at 100 Hz; each run a fresh process,
the pair interleaved (order reversed every other round), medians over the rounds.  Peak
memory is the process's high-water mark (``VmHWM``); the JSON tables of the two ways are
compared for equality (the streamed run promises the whole run's metrics to the bit).

Usage: ``python benchmarks/bench_align_stream.py [--rounds 2]`` (about 4 minutes on the
2-core machine).
"""
from __future__ import annotations

import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import bench_parser, machine, measured_section  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: run lengths [s]: paper002's own 400 s, then an hour and two
DURATIONS_S = (400.0, 3600.0, 7200.0)
WAYS = {"whole": (), "chunked (--chunk 60)": ("--chunk", "60")}
#: the measured program: the command, then its process's peak memory
RUNNER = """
import sys
from fuzzynav.cli import main
code = main(sys.argv[1:])
for line in open("/proc/self/status"):
    if line.startswith("VmHWM:"):
        print("VMHWM", int(line.split()[1]) * 1024, file=sys.stderr)
sys.exit(code)
"""


def scenario(tmp: Path, duration_s: float) -> Path:
    path = tmp / f"align_{int(duration_s)}.toml"
    path.write_text(f'kind = "alignment"\nbase = "paper002-gusts"\n'
                    f'name = "gusts-{int(duration_s)}s"\nduration_s = {duration_s}\n')
    return path


def measure(tmp: Path, duration_s: float, way: str) -> dict:
    """One ``compare`` in a fresh process: wall and CPU time, peak memory, its table."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), PYTHONWARNINGS="ignore")
    argv = ["compare", str(scenario(tmp, duration_s)), "--filters", "align-kf,align-fuzzy",
            "--json", *WAYS[way]]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", RUNNER, *argv], env=env, cwd=tmp, check=True,
                         capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    hwm = [int(x.split()[1]) for x in out.stderr.splitlines() if x.startswith("VMHWM")]
    return {"wall": wall, "cpu": cpu, "peak": hwm[-1], "table": json.loads(out.stdout)}


def measure_all(tmp: Path, rounds: int) -> dict:
    measure(tmp, 400.0, "whole")          # numba's cache and the imports warmed
    res = {(d, w): [] for d in DURATIONS_S for w in WAYS}
    for r in range(rounds):
        for d in DURATIONS_S:
            for way in (list(WAYS) if r % 2 == 0 else list(WAYS)[::-1]):
                res[(d, way)].append(measure(tmp, d, way))
                print(f"round {r}: {d:6.0f} s {way:22s} {res[(d, way)][-1]['wall']:6.1f} s "
                      f"{res[(d, way)][-1]['peak'] / 2**20:7.0f} MiB", flush=True)
    return res


def report(args, res: dict, load: tuple, secs: float) -> str:
    lines = ["## An alignment streamed: whole against chunked "
             "(`benchmarks/bench_align_stream.py`)", "",
             "`fuzzynav compare SCN --filters align-kf,align-fuzzy --json` against the same "
             "with `--chunk 60`, SCN paper002-gusts (swaying base, gusts) lengthened to each "
             "duration, IMU at 100 Hz, one seed; each run a fresh process (start-up "
             f"included), {args.rounds} rounds interleaved, medians; peak memory the "
             f"process's high-water mark. Machine: {machine()}; load average {load[0]:.2f} "
             f"at the start, {load[1]:.2f} at the end; {secs / 60:.1f} min in all.", "",
             "| run | IMU samples | way | wall (s) | CPU (s) | peak RSS (MiB) | table |",
             "|---|---|---|---|---|---|---|"]
    for d in DURATIONS_S:
        whole = res[(d, "whole")][0]["table"]
        for way in WAYS:
            runs = res[(d, way)]
            same = all(r["table"] == whole for r in runs)
            lines.append(f"| {d:.0f} s | {int(d * 100):,} | {way} | "
                         f"{statistics.median(r['wall'] for r in runs):.1f} | "
                         f"{statistics.median(r['cpu'] for r in runs):.1f} | "
                         f"{statistics.median(r['peak'] for r in runs) / 2**20:.0f} | "
                         + ("the whole run's" if same else "DIFFERS") + " |")
    lines += ["", "The chunked run holds one 60-s chunk of samples (and the grid's mid-points) "
              "and the filter's epochs, one a second; the whole run holds every sample's grid "
              "points, truth and increments (`align/run_size.py`: 1 kB a sample, 4 kB an epoch)."]
    return "\n".join(lines)


def main(argv=None):
    args = bench_parser(__doc__, rounds=2).parse_args(argv)
    measured_section("align-stream", args, lambda tmp: measure_all(tmp, args.rounds), report)


if __name__ == "__main__":
    main()
