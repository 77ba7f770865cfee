"""A fuzzynav command on a cold kernel cache, side by side with the same command warm.

Each repeat makes an empty numba cache directory and an empty simulation cache (what a
fresh machine has), runs the command in a child process (cold: every kernel it uses is
compiled), then runs it again on the caches the first run filled (warm).  Reported per
case: min and median wall and CPU (user + system) seconds over the repeats; for the cold
runs also the kernels compiled and the top list of compile times per kernel (from numba's
``"numba:compile"`` event; exclusive: a kernel's own time, without the kernels it caused to
be compiled; first repeat).

    python benchmarks/bench_cold_start.py --repeat 3 -- run paper000 --filter ekf
    git worktree add /tmp/base BASE_REV
    python benchmarks/bench_cold_start.py --base /tmp/base --write -- run paper000 --filter ekf

``--base`` measures a checkout of another revision too, the two taking turns.  The command's
own output goes to /dev/null; the figures to stdout, with ``--json FILE`` to a file and with
``--write`` into the ``cold-start`` section of docs/benchmarks.md.  Under load, read the CPU
seconds: a cold run is compilation, which is CPU-bound, and its wall time mostly measures
what else the machine runs.
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
    wall = time.perf_counter() - t0
    try:
        from fuzzynav.filters import precompile
    except ImportError:  # a base revision without the helper
        precompile = None
    helper = getattr(precompile, "_HELPER", None)
    if helper is not None:
        helper.stop()
    own = resource.getrusage(resource.RUSAGE_SELF)
    with open(out_path, "w", encoding="utf-8") as f:
        json.dump({"code": code, "in_process_s": wall, "compiles": recs,
                   "own_cpu_s": own.ru_utime + own.ru_stime,
                   "helper_cpu_s": None if helper is None else helper.cpu_s,
                   "waited_s": None if helper is None else helper.waited_s}, f)
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


def _median_or_none(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else None


def _fmt(x):
    return "–" if x is None else f"{x:.1f}"


def top_kernels(compiles, n):
    """``[(seconds, count, name)]`` of the ``n`` kernels with the most exclusive compile time."""
    own, count = collections.defaultdict(float), collections.Counter()
    for name, _args, seconds, _depth in compiles:
        own[name] += seconds
        count[name] += 1
    return sorted(((s, count[k], k) for k, s in own.items()), reverse=True)[:n]


def measure(argv, repeat, trees):
    """Cold then warm runs of ``argv`` per tree (``{label: source dir or None}``: None the
    installed/imported fuzzynav), the trees taking turns within each repeat."""
    runs = {label: {"cold": [], "warm": []} for label in trees}
    for _ in range(repeat):
        for label, src in trees.items():
            with tempfile.TemporaryDirectory() as nb_dir, tempfile.TemporaryDirectory() as sim:
                env = dict(os.environ, NUMBA_CACHE_DIR=nb_dir, FUZZYNAV_CACHE=sim)
                env.pop("FUZZYNAV_NUMBA_CACHE", None)  # the keyed cache, as installed
                if src is not None:
                    env["PYTHONPATH"] = os.pathsep.join([src, env.get("PYTHONPATH", "")])
                runs[label]["cold"].append(_run(argv, env))
                runs[label]["warm"].append(_run(argv, env))
    out = {}
    for label, r in runs.items():
        res = {}
        for case in ("cold", "warm"):
            rs = r[case]
            res[case] = {"wall_s": _summary([x[0] for x in rs]),
                         "cpu_s": _summary([x[1] for x in rs]),
                         "compiles": statistics.median(len(x[2]["compiles"]) for x in rs),
                         "compile_s": statistics.median(sum(c[2] for c in x[2]["compiles"])
                                                        for x in rs),
                         "own_cpu_s": statistics.median(x[2]["own_cpu_s"] for x in rs),
                         "helper_cpu_s": _median_or_none(x[2].get("helper_cpu_s") for x in rs),
                         "waited_s": _median_or_none(x[2].get("waited_s") for x in rs)}
        res["top"] = top_kernels(r["cold"][0][2]["compiles"], 10 ** 6)
        out[label] = res
    return out


def report(command, results, top, repeat) -> str:
    """The figures as markdown: a table of the cases, then each tree's top kernels."""
    lines = [f"`fuzzynav {command}`, empty numba and simulation caches (cold) and then the "
             f"same caches again (warm); min / median of {repeat} run(s) each, whole "
             "process (wall and CPU = user + system seconds, helper process included); "
             "compile = the compilations' own times summed (numba's `numba:compile` event); "
             "main CPU = the command's process alone; helper = the CPU seconds of the "
             "process compiling the covariance kernels meanwhile "
             "(`fuzzynav/filters/precompile.py`), waited = the seconds the command waited "
             "for it (medians).", "",
             "| tree | case | wall (s) | CPU (s) | compilations | compile (s) | main CPU (s) "
             "| helper CPU (s) | waited (s) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for label, res in results.items():
        for case in ("cold", "warm"):
            r = res[case]
            lines.append(f"| {label} | {case} | {r['wall_s']['min']:.1f} / "
                         f"{r['wall_s']['median']:.1f} | {r['cpu_s']['min']:.1f} / "
                         f"{r['cpu_s']['median']:.1f} | {r['compiles']:.0f} | "
                         f"{r['compile_s']:.1f} | {_fmt(r.get('own_cpu_s'))} | "
                         f"{_fmt(r.get('helper_cpu_s'))} | {_fmt(r.get('waited_s'))} |")
    for label, res in results.items():
        lines += ["", f"Top kernels by own compile time, {label} (first cold run):", "",
                  "| s | compilations | kernel |", "|---|---|---|"]
        lines += [f"| {s:.2f} | {c} | `{k}` |" for s, c, k in res["top"][:top]]
    return "\n".join(lines)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--top", type=int, default=15)
    p.add_argument("--base", help="also measure this source tree (a checkout of the base "
                   "revision), taking turns with this one")
    p.add_argument("--json", help="also write the figures to this file")
    p.add_argument("--write", action="store_true",
                   help="write the section of docs/benchmarks.md")
    p.add_argument("--child", help=argparse.SUPPRESS)
    p.add_argument("argv", nargs="+", help="the fuzzynav command (after --)")
    a = p.parse_args()
    if a.child:
        sys.exit(_child(a.argv, a.child))
    trees = {"this tree": None} if a.base is None else {"base": a.base, "this tree": None}
    results = measure(a.argv, a.repeat, trees)
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from _report import machine, write_section

    text = report(" ".join(a.argv), results, a.top, a.repeat)
    print(machine())
    print(text)
    if a.json:
        with open(a.json, "w", encoding="utf-8") as f:
            json.dump({"machine": machine(), "results": results}, f, indent=2)
    if a.write:
        write_section("cold-start", "## A run on a cold kernel cache "
                      "(`benchmarks/bench_cold_start.py`)\n\n" + machine() + "\n\n" + text)


if __name__ == "__main__":
    main()
