"""One 400-s A-KIT AUV run (``--data akit:DIR:N``): IMU samples per second on one core.

The run is what ``fuzzynav run --data akit:DIR:N`` does for one trajectory (filter set-up,
the compiled loop over 40 000 IMU samples with 400 DVL updates, scoring against the
reference), timed as the best of several runs after a warm-up, for ``ekf`` and ``ekf-st``
alternately.  The peer, timed in the same run on the same IMU log: the numpy reference
filter of ``numpy_reference_filter.py`` (mechanization and covariance propagation every
sample, the way such a filter is usually written; it has no DVL model, so it runs unaided,
over the first ``--peer-samples`` samples).

Usage: ``python benchmarks/bench_auv.py [--data akit:DIR:1] [--repeat 7] [--no-write]``.
Without the recordings (not shipped: see ``../shared/datasets/README.md``) it says so and
exits with 0.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from types import SimpleNamespace

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_section  # noqa: E402
import numpy_reference_filter as ref  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: where the shared recordings usually are, relative to a checkout (main or a worktree)
CANDIDATES = (ROOT.parent / "shared" / "datasets" / "akit",
              ROOT.parent.parent / "shared" / "datasets" / "akit")
FILTERS = ("ekf", "ekf-st")


def default_spec() -> str | None:
    for d in CANDIDATES:
        if (d / "IMU_trajectory1.csv").is_file():
            return f"akit:{d}:1"
    return None


def load(spec: str):
    """The recording of ``akit:DIR:N`` (one trajectory), or None with a message."""
    from fuzzynav.errors import FuzzynavError
    from fuzzynav.realdata.sources import parse_data_spec
    from fuzzynav.realdata.loaders.akit_recording import load_akit

    try:
        source, directory, session = parse_data_spec(spec)
        recs = load_akit(directory, session or "1")
    except FuzzynavError as exc:
        print(f"bench_auv: skipped: {exc}")
        return None
    if source.kind != "akit" or len(recs) != 1:
        print(f"bench_auv: skipped: {spec} is not one A-KIT trajectory")
        return None
    return recs[0]


def time_filters(rec, repeat: int) -> dict:
    """Best wall time of ``run_trajectory`` per filter, alternating; and the metrics."""
    from fuzzynav.realdata.akit import run_trajectory

    best, metrics = dict.fromkeys(FILTERS, np.inf), {}
    for name in FILTERS:
        run_trajectory(rec, name)  # compile or load the kernels
    for _ in range(repeat):
        for name in FILTERS:
            t0 = time.perf_counter()
            res, m = run_trajectory(rec, name)
            best[name] = min(best[name], time.perf_counter() - t0)
            metrics[name] = (m, res.ok)
    return {k: (best[k], *metrics[k]) for k in FILTERS}


def time_peer(rec, n: int) -> float:
    """Seconds per IMU sample of the numpy reference filter over the first ``n`` samples."""
    from fuzzynav.filters.config import FilterConfig

    imu = SimpleNamespace(time_s=rec.imu.time_s[:n + 1], dtheta_b=rec.imu.dtheta_b[:n],
                          dv_b=rec.imu.dv_b[:n])
    none = SimpleNamespace(time_s=np.zeros(0), z=np.zeros((0, 6)), sigma=np.zeros((0, 6)))
    r = rec.reference
    init = SimpleNamespace(lla=r.lla[0], vel_n=r.vel_n[0], q_bn=r.q_bn[0])
    cfg = FilterConfig()  # its noise values do not change the work done
    t0 = time.perf_counter()
    ref.run(imu, none, init, cfg.P0(), cfg.q_diag(), 100)
    return (time.perf_counter() - t0) / n


def report(spec, rec, runs, peer_s, load, repeat, n_peer) -> str:
    n = rec.imu.dtheta_b.shape[0]
    dur = float(rec.imu.time_s[-1] - rec.imu.time_s[0])
    lines = ["## One AUV run on a recording (`benchmarks/bench_auv.py`)", "",
             f"`--data {spec}`: A-KIT trajectory {rec.trajectory}, {dur:.0f} s, {n:,} IMU "
             f"samples at 100 Hz, {rec.dvl.time_s.size} DVL epochs; the whole run as "
             "`fuzzynav run --data akit` does it (set-up, compiled loop, scoring), best of "
             f"{repeat}, filters alternating, one core. Machine: {machine()}; load average "
             f"{load[0]:.2f} at the start, {load[1]:.2f} at the end.", "",
             "| filter | run time (ms) | IMU samples/s | horizontal RMS (m) | end error (% of "
             "distance) |", "|---|---|---|---|---|"]
    for name, (t, m, ok) in runs.items():
        lines.append(f"| `{name}` | {t * 1e3:.1f} | {n / t:,.0f} | {m['rms_pos_h_m']:.2f} | "
                     f"{m['end_pos_h_pct']:.2f}{'' if ok else ' (stopped)'} |")
    lines.append(f"| numpy reference filter, unaided, per-sample propagation (first {n_peer:,} "
                 f"samples) | {peer_s * n * 1e3:,.0f} (extrapolated) | {1 / peer_s:,.0f} | | |")
    lines += ["", "Target of issue 10: >= 1 M IMU samples/s on one core for a 400-s AUV run. "
              "The numpy peer shows what the same data costs written the usual way; the "
              "machine is shared: rerun on an idle one for clean figures."]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default=None, help="akit:DIR:N (default: the shared recordings)")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--peer-samples", type=int, default=2000)
    ap.add_argument("--no-write", action="store_true", help="print, leave docs/ alone")
    args = ap.parse_args(argv)
    spec = args.data or default_spec()
    if spec is None:
        print("bench_auv: skipped: no A-KIT recordings found (pass --data akit:DIR:N; "
              f"looked in {', '.join(str(c) for c in CANDIDATES)})")
        return 0
    rec = load(spec)
    if rec is None:
        return 0
    load0 = os.getloadavg()[0]
    runs = time_filters(rec, args.repeat)
    peer_s = time_peer(rec, args.peer_samples)
    text = report(spec, rec, runs, peer_s, (load0, os.getloadavg()[0]), args.repeat,
                  args.peer_samples)
    print(text)
    if not args.no_write:
        write_section("auv", text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
