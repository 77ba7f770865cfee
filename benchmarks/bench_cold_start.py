"""A fuzzynav command on a cold kernel cache, side by side with the same command warm.

Each repeat makes an empty numba cache directory and an empty simulation cache (what a
fresh machine has), runs the command in a child process (cold: every kernel it uses is
compiled), then runs it again on the caches the first run filled (warm).  Reported per
case: min and median wall and CPU (user + system) seconds over the repeats; for the cold
runs also the kernels compiled and the top list of compile times per kernel (from numba's
``"numba:compile"`` event; exclusive: a kernel's own time, without the kernels it caused to
be compiled; first repeat).

    python benchmarks/bench_cold_start.py --repeat 3 -- run paper000 --filter ekf

The child prints the command's own output to /dev/null; the numbers go to stdout (and with
``--json FILE`` to a file).
"""
from __future__ import annotations

import argparse
import collections
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time


def _child(argv, out_path):
    """Run ``fuzzynav ARGV`` here, recording each compilation; write the records."""
    from numba.core import event

    stack, recs = [], []

    class Timer(event.Listener):
        def on_start(self, ev):
            stack.append([time.perf_counter(), 0.0])

        def on_end(self, ev):
            start, inner = stack.pop()
            dt = time.perf_counter() - start
            if stack:
                stack[-1][1] += dt
            f = ev.data["dispatcher"].py_func
            recs.append((f"{f.__module__}.{f.__qualname__}", str(ev.data["args"]), dt - inner,
                         len(stack)))

    event.register("numba:compile", Timer())
    t0 = time.perf_counter()
    import fuzzynav  # noqa: F401  (the import, keyed cache included, is part of the run)
    from fuzzynav.cli import main

    code = main(argv)
    with open(out_path, "w", encoding="utf-8") as f:
        json.dump({"code": code, "in_process_s": time.perf_counter() - t0, "compiles": recs}, f)
    return code


def _run(argv, env):
    """One child run: ``(wall s, cpu s, records)``."""
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as tmp:
        out = tmp.name
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, __file__, "--child", out, "--", *argv], env=env,
                   stdout=subprocess.DEVNULL, check=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    with open(out, encoding="utf-8") as f:
        rec = json.load(f)
    os.unlink(out)
    return wall, cpu, rec


def _summary(xs):
    return {"min": min(xs), "median": statistics.median(xs), "runs": len(xs)}


def top_kernels(compiles, n):
    """``[(seconds, count, name)]`` of the ``n`` kernels with the most exclusive compile time."""
    own, count = collections.defaultdict(float), collections.Counter()
    for name, _args, seconds, _depth in compiles:
        own[name] += seconds
        count[name] += 1
    return sorted(((s, count[k], k) for k, s in own.items()), reverse=True)[:n]


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--top", type=int, default=15)
    p.add_argument("--json", help="also write the figures to this file")
    p.add_argument("--child", help=argparse.SUPPRESS)
    p.add_argument("argv", nargs="+", help="the fuzzynav command (after --)")
    a = p.parse_args()
    if a.child:
        sys.exit(_child(a.argv, a.child))
    cold, warm, first = [], [], None
    for _ in range(a.repeat):
        with tempfile.TemporaryDirectory() as numba_dir, tempfile.TemporaryDirectory() as sim:
            env = dict(os.environ, NUMBA_CACHE_DIR=numba_dir, FUZZYNAV_CACHE=sim)
            env.pop("FUZZYNAV_NUMBA_CACHE", None)  # the keyed cache, as installed
            cold.append(_run(a.argv, env))
            warm.append(_run(a.argv, env))
        first = first or cold[0][2]
    res = {"command": "fuzzynav " + " ".join(a.argv), "cpu_count": os.cpu_count(),
           "python": sys.version.split()[0]}
    import numba

    res["numba"] = numba.__version__
    for name, runs in (("cold", cold), ("warm", warm)):
        res[name] = {"wall_s": _summary([r[0] for r in runs]),
                     "cpu_s": _summary([r[1] for r in runs]),
                     "compiles": statistics.median(len(r[2]["compiles"]) for r in runs)}
    res["compile_s"] = sum(r[2] for r in first["compiles"])
    res["top"] = top_kernels(first["compiles"], a.top)
    print(f"{res['command']}  ({res['cpu_count']} cores, Python {res['python']}, "
          f"numba {res['numba']}; min / median of {a.repeat})")
    for name in ("cold", "warm"):
        r = res[name]
        print(f"  {name}: wall {r['wall_s']['min']:.1f} / {r['wall_s']['median']:.1f} s, "
              f"cpu {r['cpu_s']['min']:.1f} / {r['cpu_s']['median']:.1f} s, "
              f"{r['compiles']:.0f} compilations")
    print(f"  compile time (first cold run, exclusive sum): {res['compile_s']:.1f} s; top kernels:")
    for s, c, k in res["top"]:
        print(f"    {s:6.2f} s  x{c}  {k}")
    if a.json:
        with open(a.json, "w", encoding="utf-8") as f:
            json.dump(res, f, indent=2)


if __name__ == "__main__":
    main()
