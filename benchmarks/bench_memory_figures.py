"""The memory figures the size checks are built on, measured with tracemalloc.

Each figure is the growth of a traced peak between two lengths of the same run, so the
fixed costs (imports, compiled kernels, rule systems) cancel:

* a car recording's load (``load_rtklib`` on synthetic drives in the rtklib format, both
  longer than one parse block): bytes per IMU line, against
  ``imu_csv.HELD_BYTES_PER_LINE``, and the block's share against ``BLOCK_BYTES_PER_LINE``;
* an alignment run (paper002-gusts, align-fuzzy) whole: bytes per IMU sample, against
  ``align.run_size.BYTES_PER_SAMPLE``; in 6 000-sample chunks: bytes per filter epoch,
  against ``BYTES_PER_EPOCH``, and the rest of the run against ``BASE_BYTES``;
* a filter run on a loaded A-KIT recording at its full output rate: bytes per kept output
  row (events included), against ``sim.budget.BYTES_PER_OUTPUT_ROW``.

Usage: ``python benchmarks/bench_memory_figures.py [--no-write]`` (about 3 minutes).
"""
from __future__ import annotations

import dataclasses
import sys
import tracemalloc
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import bench_parser, machine, measured_section  # noqa: E402


def _peak(fn):
    fn()                                   # caches and compiled kernels first
    tracemalloc.start()
    fn()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def car_load(tmp: Path) -> dict:
    from fuzzynav.realdata.loaders import chunked
    from fuzzynav.realdata.loaders.rtklib import load_rtklib
    from fuzzynav.sim.segments import Segment
    from tests.realdata.rtklib_files import DRIVE_SEGMENTS, write_drive

    out = {}
    for extra_s in (1000.0, 3000.0):
        d = tmp / f"drive{int(extra_s)}"
        d.mkdir()
        write_drive(d, segments=list(DRIVE_SEGMENTS) + [Segment("cruise", extra_s)])
        out[extra_s] = (chunked.count_lines(d / "imu_1.csv"),
                        _peak(lambda d=d: load_rtklib(d)))
    (n0, p0), (n1, p1) = out.values()
    per_line = (p1 - p0) / (n1 - n0)
    return {"lines": (n0, n1), "peaks": (p0, p1), "per_line": per_line,
            "block_per_line": (p0 - n0 * per_line) / chunked.DEFAULT_CHUNK_ROWS}


def alignment() -> dict:
    from fuzzynav.align import alignment_run as R
    from fuzzynav.align.scenario import load_alignment_scenario

    base = load_alignment_scenario("paper002-gusts")
    peaks = {}
    for dur in (400.0, 1600.0):
        scn = dataclasses.replace(base, duration_s=dur)
        for chunk in (None, 6000):
            peaks[(dur, chunk)] = _peak(
                lambda scn=scn, chunk=chunk: R.seed_runs(scn, chunk_samples=chunk)(0)(
                    "align-fuzzy"))
    rate = base.imu.rate_hz
    per_sample = (peaks[(1600.0, None)] - peaks[(400.0, None)]) / (1200.0 * rate)
    per_epoch = (peaks[(1600.0, 6000)] - peaks[(400.0, 6000)]) / 1200.0
    base_bytes = peaks[(400.0, 6000)] - 400.0 * per_epoch - 6000 * per_sample
    return {"peaks": peaks, "per_sample": per_sample, "per_epoch": per_epoch,
            "base": base_bytes}


def outputs(tmp: Path) -> dict:
    from fuzzynav.realdata.akit import AkitSource
    from fuzzynav.realdata.loaders.akit_recording import load_trajectory
    from fuzzynav.runpath import run
    from tests.realdata.akit_files import auv_trajectory, write_akit

    res = {}
    for dur in (300.0, 900.0):
        d = tmp / f"auv{int(dur)}"
        d.mkdir()
        write_akit(d, auv_trajectory(dur), n=1, lag=1.0)
        src = AkitSource(load_trajectory(d, 1))
        rows = run(src, "ekf").result.time_s.size
        res[dur] = (rows, _peak(lambda src=src: run(src, "ekf")))
    (r0, p0), (r1, p1) = res.values()
    return {"rows": (r0, r1), "per_row": (p1 - p0) / (r1 - r0)}


def report(args, got, load, secs) -> str:
    from fuzzynav.align import run_size
    from fuzzynav.realdata.loaders import imu_csv
    from fuzzynav.sim import budget

    car, al, out = got["car"], got["align"], got["outputs"]
    rows = [
        ("car recording load, per IMU line", f"{car['per_line']:.0f} B",
         f"`imu_csv.HELD_BYTES_PER_LINE` = {imu_csv.HELD_BYTES_PER_LINE} B",
         f"drives of {car['lines'][0]:,} and {car['lines'][1]:,} lines"),
        ("car recording load, per line of the parse block", f"{car['block_per_line']:.0f} B",
         f"`imu_csv.BLOCK_BYTES_PER_LINE` = {imu_csv.BLOCK_BYTES_PER_LINE} B",
         "the shorter drive's peak less its lines, over 65 536"),
        ("alignment whole, per IMU sample", f"{al['per_sample']:.0f} B",
         f"`run_size.BYTES_PER_SAMPLE` = {run_size.BYTES_PER_SAMPLE} B",
         "paper002-gusts 400 s and 1 600 s, align-fuzzy"),
        ("alignment in 6 000-sample chunks, per filter epoch", f"{al['per_epoch']:.0f} B",
         f"`run_size.BYTES_PER_EPOCH` = {run_size.BYTES_PER_EPOCH} B", "the same, chunked"),
        ("alignment, the rest of a run", f"{al['base'] / 2**20:.1f} MB",
         f"`run_size.BASE_BYTES` = {run_size.BASE_BYTES / 2**20:.0f} MB",
         "the 400-s chunked peak less its epochs and chunk"),
        ("filter run on a recording, per kept output row (events in)",
         f"{out['per_row']:.0f} B",
         f"`budget.BYTES_PER_OUTPUT_ROW` = {budget.BYTES_PER_OUTPUT_ROW} B",
         f"synthetic A-KIT 300 s and 900 s, ekf, {out['rows'][1]:,} rows at 10 Hz"),
    ]
    lines = ["## Memory figures of the size checks (`benchmarks/bench_memory_figures.py`)", "",
             "Each figure is the growth of tracemalloc's peak between two lengths of the same "
             "run (after one untraced run fills the caches), so fixed costs cancel; the "
             "checks use the figure rounded up. Machine: "
             f"{machine()}; load average {load[0]:.2f} at the start, {load[1]:.2f} at the "
             f"end; {secs / 60:.1f} min in all.", "",
             "| what | measured | the check uses | runs |", "|---|---|---|---|"]
    lines += [f"| {a} | {b} | {c} | {d} |" for a, b, c, d in rows]
    return "\n".join(lines)


def main(argv=None):
    args = bench_parser(__doc__).parse_args(argv)

    def measure_all(tmp):
        return {"car": car_load(tmp), "align": alignment(), "outputs": outputs(tmp)}

    measured_section("memory-figures", args, measure_all, report)


if __name__ == "__main__":
    main()
