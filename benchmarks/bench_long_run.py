"""Long ship runs (issue 24): paper003 from 20 min to 24 h at 50 Hz and 24 h at 200 Hz,
peak memory and throughput of the whole-run path against the streamed one.

Each run is made in a fresh process (``--child``) that first runs the same path on a 10-s
cut of paper003 (imports and numba's cache loaded, not timed; its high-water mark is the
*baseline* RSS), then, timed, simulates seed 0 and runs ``ekf``:

* *whole*: :func:`fuzzynav.sim.sensor_log.simulate` (no cache) then
  :func:`fuzzynav.runpath.run` on the whole log (what ``fuzzynav run`` does without the
  long-run options); a run :mod:`fuzzynav.sim.budget` cannot hold whole is refused, and
  the refusal with its estimates is reported;
* *streamed, 1-Hz output*: :func:`fuzzynav.streamrun.run_streamed` with chunks of 300 s of
  IMU and the solution kept at 1 Hz (``fuzzynav run --output-rate 1``): simulation, filter
  and metrics chunk by chunk.

Peak RSS is the process's ``ru_maxrss``; times are wall seconds of simulate + filter +
score, best of ``--repeat`` (the paths interleaved: whole, streamed, whole, ...; runs over
4 h once).  Throughput is IMU samples per second of that time, against the 20-min run of
the same path.

Usage: ``python benchmarks/bench_long_run.py [--repeat 2] [--hours 0.333,4,24,24@200]
[--no-write]``.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_section  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MODES = ("whole", "streamed, 1-Hz output")
FILTER = "ekf"
CHUNK_S = 300.0
def scenario_file(hours: float, directory: Path, rate_hz: float | None = None) -> Path:
    """paper003 cut to ``hours`` (under its 30 min: the first segments and a cruise) or
    extended by one cruise segment, its IMU at ``rate_hz`` if given; written as a TOML
    over ``base = "paper003"``."""
    from fuzzynav.sim.scenario import load_scenario

    base = load_scenario("paper003")
    total = hours * 3600.0
    segs, t = [], 0.0
    for s in base.segments:
        if t + s.duration_s > total + 1e-9:
            break
        segs.append(f'[[segments]]\nkind = "{s.kind}"\nduration_s = {s.duration_s!r}\n'
                    + "".join(f"{k} = {_toml(v)}\n" for k, v in _extras(s).items()))
        t += s.duration_s
    if total - t > 1e-9:
        segs.append(f'[[segments]]\nkind = "cruise"\nduration_s = {total - t!r}\n')
    name = f"paper003-{hours:g}h" + (f"-{rate_hz:g}hz" if rate_hz else "")
    imu = f"[imu]\nrate_hz = {float(rate_hz)!r}\n\n" if rate_hz else ""
    path = directory / f"{name}.toml"
    path.write_text(f'base = "paper003"\nname = "{name}"\n\n{imu}' + "\n".join(segs))
    return path


def _toml(v) -> str:
    return ("true" if v else "false") if isinstance(v, bool) else repr(v)


def _extras(seg) -> dict:
    """The segment's own keys besides kind and duration (turn_deg, n_turns, ...)."""
    import dataclasses

    out = {}
    for f in dataclasses.fields(seg):
        v = getattr(seg, f.name)
        if f.name in ("kind", "duration_s") or v is None or v == f.default:
            continue
        out[f.name] = v
    return out


def _vm_hwm_bytes() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return float(line.split()[1]) * 1024.0
    return float("nan")


def _one(scn, mode: str):
    """Simulate and run ``FILTER`` on ``scn`` by ``mode``: (outcome, simulate seconds)."""
    from fuzzynav.experiment import SimulatedSource
    from fuzzynav.runpath import run
    from fuzzynav.sim.sensor_log import simulate
    from fuzzynav.streamrun import run_streamed

    if mode == "whole":
        t0 = time.perf_counter()
        log = simulate(scn, 0)
        sim_s = time.perf_counter() - t0
        return run(SimulatedSource(log), FILTER), sim_s
    return run_streamed(scn, 0, FILTER, chunk_samples=int(round(CHUNK_S * scn.imu.rate_hz)),
                        output_rate_hz=1.0), float("nan")


def child(path: str, mode: str, warm: str) -> dict:
    """One measurement in this process (``--child``): a warm-up on ``warm``, then timed."""
    from fuzzynav.errors import FuzzynavError
    from fuzzynav.sim.scenario import load_scenario

    _one(load_scenario(warm), mode)
    base = _vm_hwm_bytes()
    scn = load_scenario(path)
    t0 = time.perf_counter()
    try:
        out, sim_s = _one(scn, mode)
    except FuzzynavError as exc:  # the file's name only: its directory is a temporary one
        return {"refused": str(exc).replace(str(Path(path).parent) + os.sep, "")}
    total = time.perf_counter() - t0
    return {"samples": int(round(scn.duration_s * scn.imu.rate_hz)), "total_s": total,
            "sim_s": sim_s, "base_B": base,
            "peak_B": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0,
            "kept_rows": int(out.result.time_s.size),
            "rms_pos_h_m": out.metrics["rms_pos_h_m"], "ok": bool(out.result.ok)}


def measure(*argv) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run([sys.executable, __file__, *map(str, argv)], env=env,
                          capture_output=True, text=True, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _gb(b: float) -> str:
    return f"{b / 2**30:.2f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--hours", default="0.3333333333333333,4,24,24@200",
                    help="run lengths [h], HOURS@HZ for another IMU rate")
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print(json.dumps(child(*args.child)))
        return 0
    load0 = os.getloadavg()[0]
    runs_asked = [(float(a), float(b[0]) if b else None)
                  for a, *b in (h.split("@") for h in args.hours.split(","))]
    rows, tmp = [], Path(tempfile.mkdtemp(prefix="bench_long_"))
    warm = scenario_file(10.0 / 3600.0, tmp)
    for h, rate in runs_asked:
        path = scenario_file(h, tmp, rate)
        repeat = args.repeat if h <= 4.0 else 1  # a day's run: once
        got = {m: [] for m in MODES}
        for _ in range(repeat):
            for m in MODES:  # interleaved: the machine's drift hits both paths alike
                got[m].append(measure("--child", path, m, warm))
                print(f"{h:g} h {rate or ''} {m}: {got[m][-1]}", flush=True)
        for m in MODES:
            best = dict(got[m][0])
            for r in got[m][1:]:
                if "refused" in r:
                    continue
                for k in ("total_s", "sim_s"):
                    best[k] = min(best[k], r[k])
                best["peak_B"] = max(best["peak_B"], r["peak_B"])
            rows.append(((h, rate), m, best))
    load1 = os.getloadavg()[0]
    body = render(rows, args.repeat, load0, load1)
    print(body)
    if not args.no_write:
        write_section("long-run", body)
    return 0


def render(rows, repeat, load0, load1) -> str:
    ok = [(h, m, r) for h, m, r in rows if "refused" not in r]
    ref = {}
    for h, m, r in ok:
        ref.setdefault(m, r["samples"] / r["total_s"])
    lines = [
        "## Long ship runs: streamed simulation and filter (`benchmarks/bench_long_run.py`)",
        "",
        "`paper003` (ship, 50-Hz IMU, EM log at 50 Hz, NHC and neutral point at 10 Hz) cut "
        "to 20 min and extended by one cruise segment to 4 h and 24 h, and the 24 h with "
        f"its IMU at 200 Hz (17.3 M samples); seed 0, `{FILTER}`. Each run is a fresh "
        "process that first runs its path on a 10-s cut (imports and numba's cache: "
        "*baseline RSS*), then simulates and runs, timed (*simulate + filter + score*). "
        "*whole*: `simulate` then the run on the whole log (`fuzzynav run` without the "
        "long-run options, no cache); *streamed, 1-Hz output*: `fuzzynav.streamrun."
        f"run_streamed`, chunks of {CHUNK_S:g} s, solution kept at 1 Hz (`fuzzynav run "
        "--output-rate 1`). Best of "
        f"{repeat} (times; the paths interleaved) / largest (memory), runs over 4 h once. "
        "Peak RSS is the process's `ru_maxrss`. Machine: "
        f"{machine()}; load average {load0:.2f} at the start, {load1:.2f} at the end "
        "(the machine is shared with other jobs, run under `nice`: times are indicative, "
        "peak RSS is not affected).",
        "",
        "| run | IMU samples | path | simulate (s) | simulate + filter + score (s) | "
        "samples/s (vs 20 min) | baseline RSS (GB) | peak RSS (GB) | kept rows | "
        "RMS horizontal position (m) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for (h, rate), m, r in rows:
        name = (f"{h * 60:.0f} min" if h < 1 else f"{h:g} h") + (f" at {rate:g} Hz" if rate else "")
        if "refused" in r:
            lines.append(f"| {name} | | {m} | refused: {r['refused']} | | | | | | |")
            continue
        tput = r["samples"] / r["total_s"]
        sim = "" if r["sim_s"] != r["sim_s"] else f"{r['sim_s']:.1f}"
        lines.append(
            f"| {name} | {r['samples']:,} | {m} | {sim} | {r['total_s']:.1f} | "
            f"{tput:,.0f} ({tput / ref[m]:.2f}) | {_gb(r['base_B'])} | {_gb(r['peak_B'])} | "
            f"{r['kept_rows']:,} | {r['rms_pos_h_m']!r} |")
    lines += [
        "",
        "The streamed run simulates the trajectory, the IMU errors and the log, NHC and "
        "neutral-point streams chunk by chunk (each random term its own generator drawn in "
        "order, its state carried: the whole log's numbers to the last bit, "
        "`tests/sim/test_stream.py`) and feeds each chunk and its epochs to the filter; "
        "the metrics are streamed at the filter's 10 Hz (the whole run's to the last bit: "
        "the sums are cut into blocks counted from the run's start, not at the chunks, "
        "`fuzzynav/block_sums.py`; the RMS column is printed in full to show it). What it "
        "holds beyond the baseline is one chunk, the streamed sensors' epoch indices "
        "(8 B an epoch) and the kept rows.",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
