"""Loading long A-KIT-format recordings: this checkout against a base revision's loader.

A synthetic AUV trajectory in the A-KIT layout (100-Hz IMU CSV, 1-Hz DVL and reference,
the reference 0.7 s late and 1.8 m ahead; ``tests/realdata/akit_files.write_akit``) of each
length is written to a temporary directory; each revision loads it
(``load_trajectory``) in a fresh process, the two taking turns.  Reported per length and
revision: the load's wall time, the process's peak RSS (``VmHWM``) and, once, the memory
traced by ``tracemalloc`` over the load (its peak and what the recording keeps), per IMU
line.  Every loaded array of the two revisions is compared (sha1): they must be the same.

    git worktree add /tmp/akit-base BASE_REV
    python benchmarks/bench_akit_long.py --base /tmp/akit-base --hours 0.5,1,2,4 --day

``--day`` also loads a 24-h recording with this checkout only (the base revision's loader
took windows x samples for its pitch check: hours on a day).  Without ``--no-write`` the
figures replace the ``akit-long`` section of docs/benchmarks.md.

    python benchmarks/bench_akit_long.py --drift 1.0025 --hours 0.25,1

loads, with this checkout only, files whose reference and DVL clock runs ``--drift`` times
the IMU's (as the real files', both on one clock): past 800 s at 0.25 % the clock search
must follow the drift.  Reported: the load's time and peak RSS, and the largest error of
the measured map over the reference stamps (section ``akit-drift``).
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from _report import machine, measured_section  # noqa: E402

#: the measured program: load one trajectory, its figures and the arrays' digests
CHILD = """
import hashlib, json, sys, time, tracemalloc
import numpy as np
from fuzzynav.realdata.loaders import akit_recording as ar
traced = sys.argv[2] == "traced"
def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key + ":"):
            return float(line.split()[1]) * 1024.0
def digest(*arrays):
    h = hashlib.sha1()
    for a in arrays:
        h.update(np.ascontiguousarray(np.asarray(a, float)).tobytes())
    return h.hexdigest()
if traced:
    tracemalloc.start()
rss0 = status("VmRSS")
t0 = time.perf_counter()
rec = ar.load_trajectory(sys.argv[1], 1)
secs = time.perf_counter() - t0
out = {"secs": secs, "rss0_B": rss0, "peak_B": status("VmHWM"), "lines": int(rec.imu.time_s.size),
       "clock": [rec.clock.offset_s, rec.clock.rate, rec.clock.dvl_offset_s],
       "digest": digest(rec.imu.time_s, rec.imu.dtheta_b, rec.imu.dv_b, rec.dvl.time_s, rec.dvl.z,
                        rec.reference.time_s, rec.reference.lla, rec.reference.vel_n,
                        rec.reference.q_bn, rec.reference_offset_b,
                        [rec.clock.offset_s, rec.clock.rate, rec.clock.dvl_offset_s])}
if traced:
    kept, peak = tracemalloc.get_traced_memory()
    out.update(traced_peak_B=peak, traced_kept_B=kept)
print(json.dumps(out))
"""


#: the synthetic reference's lag behind the IMU [s]
LAG_S = 0.7


def write_recording(directory: Path, hours: float, rate: float = 1.0) -> tuple[int, object]:
    """A synthetic A-KIT trajectory 1 of ``hours`` in ``directory`` (the reference's and,
    unless ``rate`` is 1, the DVL's clock ``rate`` times the IMU's); its IMU lines and the
    reference's stamps."""
    sys.path.insert(0, str(ROOT))
    from fuzzynav.sim.segments import Segment
    from fuzzynav.sim.trajectory import generate
    from tests.realdata import akit_files

    cycle = [Segment("turn", 20, turn_deg=60), Segment("cruise", 20),
             Segment("turn", 20, turn_deg=-90), Segment("climb", 30, pitch_deg=-5),
             Segment("turn", 30, turn_deg=30)]
    tr = generate(akit_files.START, cycle * max(1, int(round(hours * 3600 / 120))), 100.0,
                  2.0, 0.5)
    idx = akit_files.write_akit(directory, tr, 1, lag=LAG_S, rate=rate, lever_y=1.8,
                                dvl_on_imu_clock=rate == 1.0)
    return int(tr.time_s.size), tr.time_s[idx]


def load(checkout: Path, directory: Path, traced: bool) -> dict:
    """One load in a fresh process importing ``checkout``'s package."""
    env = dict(os.environ, PYTHONPATH=str(checkout))
    out = subprocess.run([sys.executable, "-c", CHILD, str(directory),
                          "traced" if traced else "plain"], env=env, cwd=str(checkout),
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


@contextmanager
def recording(tmp: Path, hours: float, rate: float = 1.0):
    """:func:`write_recording` in a directory below ``tmp``, removed after use (a day's
    files are a gigabyte): yields ``(directory, lines, stamps)``."""
    d = Path(tempfile.mkdtemp(prefix="akit-", dir=tmp))
    try:
        yield (d, *write_recording(d, hours, rate))
    finally:
        shutil.rmtree(d, ignore_errors=True)


def measure(tmp: Path, ways: dict, hours: list, day: bool, rounds: int) -> list:
    """Rows of figures: each length, each way (name -> checkout), ``rounds`` plain loads
    (best time, largest peak) and one traced."""
    rows = []
    plan = [(h, list(ways)) for h in hours] + ([(24.0, ["this checkout"])] if day else [])
    for h, names in plan:
        with recording(tmp, h) as (d, lines, _):
            runs = {n: [] for n in names}
            for r in range(rounds):
                for n in (names if r % 2 == 0 else names[::-1]):
                    runs[n].append(load(ways[n], d, False))
            for n in names:
                traced = load(ways[n], d, True)
                rows.append({"hours": h, "way": n, "lines": lines,
                             "secs": min(x["secs"] for x in runs[n]),
                             "rss0_B": min(x["rss0_B"] for x in runs[n]),
                             "peak_B": max(x["peak_B"] for x in runs[n]),
                             "traced_peak_B": traced["traced_peak_B"],
                             "traced_kept_B": traced["traced_kept_B"],
                             "digest": traced["digest"]})
                print(json.dumps(rows[-1]), flush=True)
    return rows


def _slope(rows, way):
    """Growth of the traced peak per IMU line [B], from the shortest to the longest run."""
    mine = sorted((r for r in rows if r["way"] == way), key=lambda r: r["lines"])
    if len(mine) < 2:
        return float("nan")
    a, b = mine[0], mine[-1]
    return (b["traced_peak_B"] - a["traced_peak_B"]) / (b["lines"] - a["lines"])


def render(rows, base_rev: str, load: tuple) -> str:
    """The docs section."""
    same = all(len({r["digest"] for r in rows if r["hours"] == h}) == 1
               for h in {r["hours"] for r in rows})
    lines = [
        "## Long A-KIT recordings: the loader (`benchmarks/bench_akit_long.py`)",
        "",
        "A synthetic AUV trajectory in the A-KIT layout (100-Hz IMU CSV, 1-Hz DVL and "
        "reference, the reference 0.7 s late and 1.8 m ahead of the IMU) of each length, "
        f"loaded by `load_trajectory` in fresh processes: this checkout and the base revision "
        f"{base_rev} taking turns (best of the rounds for the time, largest peak RSS), then "
        "once under `tracemalloc`. Machine: " + machine() +
        f"; load average {load[0]:.2f} at the start, {load[1]:.2f} at the end.",
        "",
        "| recording | IMU lines | loader | load (s) | peak RSS (GB) | RSS before (GB) | traced peak (B/line) | kept (B/line) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        n = r["lines"]
        lines.append(f"| {r['hours']:g} h | {n:,} | {r['way']} | {r['secs']:.1f} | "
                     f"{r['peak_B'] / 1e9:.2f} | {r['rss0_B'] / 1e9:.2f} | "
                     f"{r['traced_peak_B'] / n:.0f} | {r['traced_kept_B'] / n:.0f} |")
    ways = sorted({r["way"] for r in rows})
    lines += ["", "Growth of the traced peak per IMU line, shortest to longest: " +
              ", ".join(f"{w} {_slope(rows, w):.0f} B" for w in ways) + ". "
              f"Every loaded array (increments, DVL, reference, clock map, reference offset) "
              f"the same for both loaders at every length: {same}."]
    return "\n".join(lines)


def measure_drift(tmp: Path, hours: list, rate: float, rounds: int) -> list:
    """Rows of figures of this checkout's loads of drifting recordings."""
    rows = []
    for h in hours:
        with recording(tmp, h, rate) as (d, lines, stamps):
            runs = [load(ROOT, d, False) for _ in range(rounds)]
            offset, r, _ = runs[0]["clock"]
            truth = (stamps - LAG_S) / rate
            rows.append({"hours": h, "lines": lines, "secs": min(x["secs"] for x in runs),
                         "peak_B": max(x["peak_B"] for x in runs),
                         "end_offset_s": float(stamps[-1] - truth[-1]),
                         "error_s": float(max(abs((stamps - offset) / r - truth)))})
            print(json.dumps(rows[-1]), flush=True)
    return rows


def render_drift(rows, rate: float, load: tuple) -> str:
    """The docs section of the drifting recordings."""
    lines = ["## Drifting A-KIT clocks: the clock search following "
             "(`benchmarks/bench_akit_long.py --drift`)", "",
             f"Synthetic A-KIT trajectories as above, their reference and DVL clock running "
             f"{rate:g} times the IMU's (both on one clock, as the real files'), stamped "
             f"{LAG_S:g} s late; loaded by this checkout in fresh processes (best time, "
             "largest peak RSS of the rounds). Map error: the largest difference between "
             "the IMU time the loaded clock map gives a reference stamp and the time it "
             "was written for. Machine: " + machine() +
             f"; load average {load[0]:.2f} at the start, {load[1]:.2f} at the end.", "",
             "| recording | IMU lines | offset at the end (s) | load (s) | peak RSS (GB) | "
             "map error (ms) |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['hours']:g} h | {r['lines']:,} | {r['end_offset_s']:+.1f} | "
                     f"{r['secs']:.1f} | {r['peak_B'] / 1e9:.2f} | {1e3 * r['error_s']:.1f} |")
    lines += ["", "Where the stamps' offset passes 1.95 s the map leaves the +-2 s searched "
              "about zero, and the search is made again following it "
              "(`akit_timing.followed_clock`): twice the search's time."]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", type=Path, help="a checkout of the base revision")
    ap.add_argument("--drift", type=float, help="the reference clock's rate: drifting files, "
                    "this checkout only")
    ap.add_argument("--hours", default="0.5,1,2,4")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--day", action="store_true", help="also 24 h, this checkout only")
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args(argv)
    hours = [float(h) for h in args.hours.split(",")]
    if args.drift is not None:
        measured_section("akit-drift", args,
                         lambda tmp: measure_drift(tmp, hours, args.drift, args.rounds),
                         lambda a, rows, load, secs: render_drift(rows, a.drift, load))
        return 0
    if args.base is None:
        ap.error("--base is needed unless --drift")
    base_rev = subprocess.run(["git", "-C", str(args.base), "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True).stdout.strip() or str(args.base)
    ways = {"this checkout": ROOT, f"base {base_rev}": args.base}
    measured_section("akit-long", args,
                     lambda tmp: measure(tmp, ways, hours, args.day, args.rounds),
                     lambda a, rows, load, secs: render(rows, base_rev, load)
                     + f" {secs / 60:.1f} min in all.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
