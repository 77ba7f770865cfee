"""Long recordings (issue 24): peak memory of loading and running a car recording of hours,
read whole, read in blocks of lines and run streamed, and read from its file chunk by chunk.

A synthetic car recording in the rtklib-drive's file format (``imu_1.csv`` at 100 Hz with
its RTKLIB time tag, a 4-Hz ``gnss_1_sf.pos``) is written for each length by the test
suite's writers (``tests/realdata/rtklib_files.py``; the tag vectorised here): a rest, a
drive-off, then 8 m/s with a 90-degree turn each way every two minutes.  It lives in a
temporary directory and is deleted afterwards (never committed).  Fresh processes
(``--child``) then load it and run the validation protocol (``ekf``, noise seed 0, both
feeds) either *whole* (the CSV read and integrated in one block, ``chunk_rows=None``,
every output kept) or *chunked* (the loaders' default blocks of 65 536 lines,
``--output-rate 1 --chunk 300``: 300-s chunks of IMU, the solution kept at 1 Hz, the
errors at the reference epochs formed chunk by chunk) or *from the file* (as chunked, the
recording loaded ``streamed=True``: its IMU rows never held, the increments read again from
the CSV for each use, :mod:`fuzzynav.realdata.loaders.imu_file`; what ``fuzzynav run --data
... --output-rate 1`` does).  Memory is the process's own: *RSS before* (the package and numba
imported), the high-water mark once the recording is loaded (``VmHWM``) and at the end (the
peak); the growth per hour of IMU is the slope between the shortest and longest
recordings.  A short run of each path first fills numba's cache (not reported).

Usage: ``python benchmarks/bench_long_recording.py [--hours 0.5,1,2,4] [--file-hours 24]
[--no-write]`` (``--file-hours``: longer recordings run from the file only).
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(ROOT))
from _report import machine, write_section  # noqa: E402

MODES = ("whole", "chunked", "from the file")
FILTER = "ekf"
CHUNK_S = 300.0
OUTPUT_RATE_HZ = 1.0


def write_long_drive(directory: Path, hours: float) -> int:
    """Write a drive of ``hours`` into ``directory`` (rtklib-drive format); its IMU lines."""
    import numpy as np

    from fuzzynav.sim.segments import Segment
    from tests.realdata import rtklib_files as rf

    cycle = [Segment("turn", 10.0, turn_deg=90.0), Segment("cruise", 50.0),
             Segment("turn", 10.0, turn_deg=-90.0), Segment("cruise", 50.0)]
    n_cycles = max(1, int(round((hours * 3600.0 - 28.0) / 120.0)))
    segments = [Segment("static", 20.0), Segment("accelerate", 8.0, speed_change_mps=8.0),
                *cycle * n_cycles]
    traj, acc_g, gyro = rf.drive_samples(segments)
    t_ms = traj.time_s * 1000.0
    lines = rf.csv_lines(acc_g, gyro, 5000 + np.rint(t_ms))
    (directory / "imu_1.csv").write_bytes("".join(x + "\n" for x in lines).encode())
    # the tag as rf.write_imu makes it (CR LF as logged, a record every 15.5 ms), vectorised
    arrival = rf.DRIVE_LATENCY_MS + t_ms
    ends = np.cumsum([len(x) + 2 for x in lines])
    chunks = np.arange(130.0, arrival[-1] + 15.5, 15.5)
    k = np.searchsorted(arrival, chunks, side="right")
    fpos = np.where(k > 0, ends[np.maximum(k - 1, 0)], 0)
    (directory / "imu_1.csv.tag").write_bytes(
        rf.tag_bytes(zip(chunks, fpos), start=rf.START, tick_f=123) + b"\x01\x02")
    sel = slice(0, None, int(rf.DRIVE_RATE_HZ / 4))
    lla = np.column_stack([np.degrees(traj.lla[sel, :2]), traj.lla[sel, 2]])
    rf.write_pos(directory / "gnss_1_sf.pos", rf.START[0] + rf.START[1] + traj.time_s[sel],
                 lla, traj.vel_n[sel], np.ones(lla.shape[0], dtype=int))
    return len(lines)


def _status_bytes(key: str) -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(key + ":"):
            return float(line.split()[1]) * 1024.0
    return float("nan")


def child(directory: str, mode: str) -> dict:
    """Load and run one recording in this process (``--child``): JSON on stdout."""
    from fuzzynav.realdata.loaders.chunked import DEFAULT_CHUNK_ROWS
    from fuzzynav.realdata.loaders.rtklib import load_rtklib
    from fuzzynav.realdata.protocol import ProtocolSettings
    from fuzzynav.realdata.validate import validate

    rss0 = _status_bytes("VmRSS")
    t0 = time.perf_counter()
    rec = load_rtklib(directory, chunk_rows=None if mode == "whole" else DEFAULT_CHUNK_ROWS,
                      streamed=mode == "from the file")
    t1 = time.perf_counter()
    hwm_load = _status_bytes("VmHWM")
    rate = rec.imu.rate_hz
    streaming = {} if mode == "whole" else {"output_rate_hz": OUTPUT_RATE_HZ,
                                            "chunk_samples": int(round(CHUNK_S * rate))}
    v = validate(rec, FILTER, ProtocolSettings(), 0, **streaming)
    t2 = time.perf_counter()
    return {"samples": int(rec.imu.n_samples), "load_s": t1 - t0, "run_s": t2 - t1,
            "rss0_B": rss0, "hwm_load_B": hwm_load,
            # VmHWM, not ru_maxrss: Linux carries ru_maxrss over an exec from the forking
            # parent (here the writer of a recording of hours), VmHWM is this image's own
            "peak_B": _status_bytes("VmHWM"),
            "kept_rows": int(v.runs["gnss"].result.time_s.size),
            "rms_h_gnss_m": v.runs["gnss"].metrics["rms_pos_h_m"],
            "rms_h_outages_m": v.runs["outages"].metrics["rms_pos_h_m"],
            "ok": all(r.result.ok for r in v.runs.values())}


def measure(*argv) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run([sys.executable, __file__, *map(str, argv)], env=env,
                          capture_output=True, text=True, check=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _warm() -> None:
    """One run of each path on a short recording, not reported: numba's cache of this
    checkout is filled (or loaded) before anything is measured."""
    tmp = Path(tempfile.mkdtemp(prefix="bench_rec_warm_"))
    try:
        measure("--write", tmp, 0.05)
        for mode in MODES:
            measure("--child", tmp, mode)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--hours", default="0.5,1,2,4", help="recording lengths [h]")
    ap.add_argument("--file-hours", default="", help="longer lengths [h] run from the file only")
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    ap.add_argument("--write", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print(json.dumps(child(*args.child)))
        return 0
    if args.write:  # in a process of its own: this one stays small
        print(json.dumps({"lines": write_long_drive(Path(args.write[0]),
                                                    float(args.write[1]))}))
        return 0
    load0 = os.getloadavg()[0]
    _warm()
    rows = []
    lengths = [(float(h), MODES) for h in args.hours.split(",")] + \
        [(float(h), MODES[-1:]) for h in args.file_hours.split(",") if h]
    for hours, modes in lengths:
        tmp = Path(tempfile.mkdtemp(prefix="bench_rec_"))
        try:
            t0 = time.perf_counter()
            n = measure("--write", tmp, hours)["lines"]
            size = (tmp / "imu_1.csv").stat().st_size
            print(f"{hours:g} h: {n} lines, {size / 1e6:.0f} MB written in "
                  f"{time.perf_counter() - t0:.0f} s", flush=True)
            for mode in modes:
                r = measure("--child", tmp, mode)
                r["csv_MB"] = size / 1e6
                rows.append((hours, mode, r))
                print(f"{hours:g} h {mode}: {r}", flush=True)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    body = render(rows, load0, os.getloadavg()[0])
    print(body)
    if not args.no_write:
        write_section("long-recording", body)
    return 0


def _gb(b: float) -> str:
    return f"{b / 2**30:.3f}"


def _slope_mb_per_h(rows, mode, key, hours=None) -> float:
    pts = sorted((h, r[key]) for h, m, r in rows if m == mode and (hours is None or h in hours))
    (h0, a), (h1, b) = pts[0], pts[-1]
    return (b - a) / 2**20 / (h1 - h0) if h1 > h0 else float("nan")


def render(rows, load0, load1) -> str:
    lines = [
        "## Long recordings: loaders in blocks of lines, streamed runs "
        "(`benchmarks/bench_long_recording.py`)",
        "",
        "A synthetic car recording in the rtklib-drive's format (100-Hz IMU CSV with its "
        "time tag, 4-Hz RTK solution; a rest, then 8 m/s with two turns every two minutes), "
        "written to a temporary directory for each length and deleted afterwards; each path "
        f"loads it and runs the validation protocol (`{FILTER}`, noise seed 0, both feeds: "
        "GNSS throughout and with 60-s outages every 180 s) in a fresh process. *whole*: the "
        "CSV read and integrated in one block (`chunk_rows=None`, the whole read) and every "
        "output kept; "
        "*chunked*: the loaders' default blocks of 65,536 lines and "
        f"`--output-rate {OUTPUT_RATE_HZ:g} --chunk {CHUNK_S:g}`; *from the file*: as chunked, "
        "the recording loaded `streamed=True` (what `fuzzynav run --data ... --output-rate` "
        "does): its IMU rows are never held, the increments are read again from the CSV for "
        "each use (the load's checks, the start, each feed's run). Memory is the process's: "
        "*before* its RSS with the package imported, *after loading* its high-water mark "
        "(`VmHWM`) once the recording is loaded, *peak* that mark at the end (not "
        "`ru_maxrss`, which Linux carries over an exec from the forking parent). Machine: "
        f"{machine()}; load average {load0:.2f} at the start, {load1:.2f} at the end "
        "(shared machine: times are indicative). One run of each path on a 3-minute "
        "recording fills numba's cache first and is not reported.",
        "",
        "| recording | IMU samples | CSV (MB) | path | load (s) | run (s) | RSS before (GB) "
        "| after loading (GB) | peak RSS (GB) | kept rows | RMS horizontal, GNSS / outages (m) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for hours, mode, r in rows:
        lines.append(
            f"| {hours:g} h | {r['samples']:,} | {r['csv_MB']:.0f} | {mode} | {r['load_s']:.1f} "
            f"| {r['run_s']:.1f} | {_gb(r['rss0_B'])} | {_gb(r['hwm_load_B'])} "
            f"| {_gb(r['peak_B'])} | {r['kept_rows']:,} | {r['rms_h_gnss_m']!r} / "
            f"{r['rms_h_outages_m']!r} |")
    shared = sorted({h for h, m, _ in rows if m == MODES[0]})
    lines += ["", "Growth per hour of IMU (100 Hz, 360,000 samples), from the shortest to "
              "the longest recording run all three ways: " + "; ".join(
                  f"{mode}: {_slope_mb_per_h(rows, mode, 'hwm_load_B', shared):.0f} MB/h after "
                  f"loading, {_slope_mb_per_h(rows, mode, 'peak_B', shared):.0f} MB/h at the "
                  "peak" for mode in MODES) + ".",
              "",
              "Whole and chunked reach their peak while loading: what grows is what the loader "
              "keeps and returns, the parsed rows (56 bytes per sample), each line's length "
              "and index (16 bytes, for the time tag), the timing columns of the clock fit "
              "and the increments (56 bytes). From the file, the load keeps the ticks and the "
              "line lengths and indices only while it fits the clocks (about 80 bytes a line "
              "at the clock fits' peak, `imu_file.SCAN_BYTES_PER_LINE`) and returns no IMU "
              "array; what the run then adds with the recording's length is its GNSS rate, "
              "not its IMU rate: the 4-Hz fixes and reference, their degraded copies, each "
              "feed's errors at the reference epochs and its kept rows (about 20 and 26 "
              "bytes per IMU line at 100 Hz, measured with tracemalloc, "
              "`benchmarks/bench_recording_kept.py`; the filter's event "
              "logs are made and let go chunk by chunk, `chunk_feed.EpochsByChunk`, where "
              "they were 8 more). The price is time: "
              "the CSV is parsed five times (the load's timing, physics and gyro-scale "
              "checks, and each feed's run)."]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
