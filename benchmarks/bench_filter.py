"""Speed of the closed-loop 15-state GNSS/INS filter against a straightforward numpy loop.

1 h of a manoeuvring trajectory at 100 Hz with 1-Hz GNSS position and velocity.  Measures
IMU samples per second on one core for

* fuzzynav's compiled loop (covariance propagated over each GNSS interval with the mean F),
* the same compiled loop propagating every sample (``max_prop_dt_s = 0.01``),
* the numpy reference filter (``numpy_reference_filter.py``, per-sample propagation),

and checks that the position and attitude RMS of the fast loop match the per-sample numpy
reference within 1 %.  Usage: ``python benchmarks/bench_filter.py [--minutes 60]``.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_section  # noqa: E402

from fuzzynav import units  # noqa: E402
from fuzzynav.filters.config import FilterConfig  # noqa: E402
from fuzzynav.filters.result import FilterResult  # noqa: E402
from fuzzynav.filters.runner import InitialState, run_filter  # noqa: E402
from fuzzynav.metrics import errors_vs_trajectory, rms_metrics  # noqa: E402
from fuzzynav.nav import attitude, earth  # noqa: E402
from fuzzynav.sim.segments import manoeuvring_profile  # noqa: E402
from fuzzynav.sim.sensors import SensorData  # noqa: E402
from fuzzynav.sim.trajectory import generate  # noqa: E402

CONFIG = FilterConfig(init_att_sigma_deg=(0.1, 0.1, 1.0), gyro_sigma_dph=(20.0,),
                      accel_sigma_ug=(500.0,), arw_dpsh=0.05, vrw_ug_psqrthz=50.0)


def make_data(minutes: float, seed: int = 1):
    tr = generate(np.array([np.deg2rad(38.0178), np.deg2rad(112.4447), 825.0]),
                  manoeuvring_profile(60.0 * minutes), 100.0, 0.0, 0.3)
    rng = np.random.default_rng(seed)
    dt = 0.01
    bg = np.array([10.0, -10.0, 5.0]) * units.DPH
    ba = np.array([200.0, -100.0, 300.0]) * units.UG
    imu = SimpleNamespace(
        time_s=tr.time_s,
        dtheta_b=tr.dtheta_b + bg * dt + rng.normal(0, 0.05 * units.DPSH * 0.1, tr.dtheta_b.shape),
        dv_b=tr.dv_b + ba * dt + rng.normal(0, 50 * units.UG * 0.1, tr.dv_b.shape))
    idx = np.arange(0, tr.n_samples + 1, 100)
    sp, sv = np.array([1.0, 1.0, 2.0]), np.array([0.05, 0.05, 0.1])
    e = rng.normal(0, 1, (idx.size, 3)) * sp
    rm, rn = earth.radii(tr.lla[idx, 0])
    h = tr.lla[idx, 2]
    z = np.column_stack([tr.lla[idx, 0] + e[:, 1] / (rm + h),
                         tr.lla[idx, 1] + e[:, 0] / ((rn + h) * np.cos(tr.lla[idx, 0])),
                         h + e[:, 2], tr.vel_n[idx] + rng.normal(0, 1, (idx.size, 3)) * sv])
    gnss = SensorData("gnss", tr.time_s[idx], z, np.tile(np.r_[sp, sv], (idx.size, 1)))
    init = InitialState(0.0, tr.lla[0], tr.vel_n[0],
                        attitude.euler_to_quat(tr.att[0] + np.deg2rad([0.05, -0.05, 0.5])))
    return tr, imu, gnss, init


def timed(fn, repeat):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--minutes", type=float, default=60.0)
    ap.add_argument("--no-write", action="store_true", help="do not update docs/benchmarks.md")
    args = ap.parse_args(argv)
    tr, imu, gnss, init = make_data(args.minutes)
    n = tr.n_samples
    cfg_ref = CONFIG.with_(out_rate_hz=1.0)
    run_filter(imu, {"gnss": gnss}, init, cfg_ref)  # compile (cached on disk after)
    t_fast, fast = timed(lambda: run_filter(imu, {"gnss": gnss}, init, cfg_ref), 5)
    t_every, every = timed(lambda: run_filter(imu, {"gnss": gnss}, init,
                                              cfg_ref.with_(max_prop_dt_s=0.01)), 2)
    # imported here: _ekf_worker.py reuses make_data with trees older than the numpy peer
    import numpy_reference_filter as ref

    t0 = time.perf_counter()
    ts, lla, vel, q = ref.run(imu, gnss, init, CONFIG.P0(), CONFIG.q_diag(), 100)
    t_np = time.perf_counter() - t0
    np_res = FilterResult(ts, lla, vel, q, np.zeros((ts.size, 6)), np.zeros((ts.size, 15)), ())
    rows, metr = [], {}
    for name, res, secs in (("fuzzynav, propagation per GNSS interval", fast, t_fast),
                            ("fuzzynav, propagation every sample", every, t_every),
                            ("numpy reference, per sample", np_res, t_np)):
        m = rms_metrics(errors_vs_trajectory(res, tr), t_start_s=100.0)
        metr[name] = m
        rows.append((name, n / secs, m["rms_pos_m"], m["rms_att_deg"]))
    base = metr["numpy reference, per sample"]
    fast_m = metr["fuzzynav, propagation per GNSS interval"]
    d_pos = 100 * abs(fast_m["rms_pos_m"] / base["rms_pos_m"] - 1)
    d_att = 100 * abs(fast_m["rms_att_deg"] / base["rms_att_deg"] - 1)
    lines = [f"## Closed-loop 15-state GNSS/INS filter (`benchmarks/bench_filter.py`)", "",
             f"{args.minutes:g} min at 100 Hz ({n} IMU samples), 1-Hz GNSS position + velocity, "
             f"one core. Machine: {machine()}.", "",
             "| implementation | IMU samples/s | speed-up vs numpy | RMS 3-D position (m) | "
             "RMS attitude (deg) |", "|---|---|---|---|---|"]
    for name, rate, p, a in rows:
        lines.append(f"| {name} | {rate:,.0f} | {rate / rows[-1][1]:,.0f}x | {p:.4f} | {a:.5f} |")
    lines += ["", f"Accuracy of the fast loop against the per-sample numpy reference: position RMS "
              f"differs by {d_pos:.2f} %, attitude RMS by {d_att:.2f} % (goal: within 1 %).",
              "The fast loop propagates the covariance once per GNSS interval with the mean "
              "attitude and specific force of the interval (second-order transition matrix); "
              "the mechanization itself always runs at the IMU rate."]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        write_section("filter", text)


if __name__ == "__main__":
    main()
