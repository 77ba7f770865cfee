"""Is the A-KIT reference on the IMU's clock?  Before and after the clock map (docs/paper004.md).

For each trajectory the gyros alone are integrated from the reference attitude at the start
(epoch 1) and at the end (30 s before the last epoch) of the trajectory, with the reference
read ``shift`` seconds later on the IMU clock than it is placed (earth rate ignored: 0.1 deg
in 30 s); the RMS heading difference over 30 s is printed as placed and for the best shift
(-0.8 ... +0.8 s).  A navigation-grade gyro integrated for 30 s follows the reference to a
few hundredths of a degree; a timing error shows as heading error where the turn rate
changes.  *Before*: the reference placed by the earlier loader (the yaw rate of the reference
against the z gyro x cos roll in 1-s bins, whole-trajectory lag of 0-3 samples, reproduced
below); *after*: the loader's clock map (``fuzzynav.realdata.loaders.akit_timing``).  Usage:
``python tools/akit_reference_timing.py`` (reads ``$FUZZYNAV_DATA/akit``).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from fuzzynav.nav import attitude
from fuzzynav.realdata.loaders import akit_recording as akit
from fuzzynav.realdata.loaders.akit_timing import parabola_min

ROOT = Path(__file__).resolve().parents[1]
SECONDS = 30
SHIFTS = np.round(np.arange(-0.8, 0.81, 0.1), 1)


def heading_rms(imu, ref, shift: float, j0: int, secs: int = SECONDS) -> float:
    """RMS up-axis attitude difference [deg] over ``secs`` from reference epoch ``j0``:
    gyro integration vs the reference read ``shift`` s later on the IMU clock."""
    dt = float(np.median(np.diff(imu.time_s)))
    k_at = lambda t: int(round((t + shift - imu.time_s[0]) / dt))  # noqa: E731
    base = k0 = k_at(ref.time_s[j0])
    C, err = attitude.quat_to_dcm(ref.q_bn[j0]), []
    inc = attitude.rotvec_to_dcm(imu.dtheta_b[k0:k_at(ref.time_s[j0 + secs])])
    for j in range(j0 + 1, j0 + secs):
        k1 = k_at(ref.time_s[j])
        for k in range(k0, k1):
            C = C @ inc[k - base]
        k0 = k1
        err.append(np.rad2deg(attitude.attitude_error(C, attitude.quat_to_dcm(ref.q_bn[j])))[2])
    return float(np.sqrt(np.mean(np.square(err))))


def old_lag_s(imu, gt) -> float:
    """The earlier loader's reference lag [s] (yaw rate of the reference vs gyro, >= 0)."""
    t = gt[:, 0]
    yaw_rate = np.gradient(np.unwrap(gt[:, 9]), t)
    edges = np.concatenate([[t[0] - 0.5 * (t[1] - t[0])], 0.5 * (t[1:] + t[:-1]),
                            [t[-1] + 0.5 * (t[-1] - t[-2])]])
    which = np.searchsorted(edges, imu[:, 0]) - 1
    ok = (which >= 0) & (which < t.size)
    gz = np.bincount(which[ok], imu[ok, 6], t.size) / np.maximum(
        np.bincount(which[ok], None, t.size), 1) * np.cos(gt[:, 7])
    cost = [np.mean((gz[:t.size - s] - yaw_rate[s:]) ** 2) for s in range(4)]
    return max(parabola_min(cost), 0.0) * float(np.median(np.diff(t)))


def before(directory: Path, n: int):
    """The reference as the earlier loader placed it, and its lag [s]."""
    imu = akit.read_table(directory / f"IMU_trajectory{n}.csv", "IMU")
    gt = akit.read_table(directory / "corrected" / f"GT_trajectory{n}.csv", "GT")
    lag = old_lag_s(imu, gt)
    dt_ref = float(np.median(np.diff(gt[:, 0])))
    t_ref = np.arange(imu[0, 0], gt[-1, 0] - lag + 1e-9, dt_ref)
    ref = akit.reference_at(gt, t_ref + lag)
    return akit.Reference(t_ref, ref.lla, ref.vel_n, ref.q_bn), lag


def imu_from_zero(directory: Path, n: int):
    """The IMU from its first sample (the loader may drop a few before the reference)."""
    imu = akit.read_table(directory / f"IMU_trajectory{n}.csv", "IMU")
    return akit.imu_increments(imu[:, 0], imu[:, 1:4], imu[:, 4:7])


def _cells(imu, ref) -> str:
    out = []
    for j0 in (1, ref.time_s.size - SECONDS - 2):
        r = [heading_rms(imu, ref, s, j0) for s in SHIFTS]
        i = int(np.argmin(r))
        out.append(f"{r[SHIFTS.size // 2]:.2f} ({SHIFTS[i]:+.1f} s: {r[i]:.2f})")
    return " | ".join(out)


def main():
    data = Path(os.environ.get("FUZZYNAV_DATA", ROOT.parent / "shared" / "datasets")) / "akit"
    print("| traj | before: lag (s) | start: heading RMS (deg), as placed (best shift: RMS) "
          "| end: same | after: offset (s), rate, DVL − reference (s) | start | end |")
    print("|---|---|---|---|---|---|---|")
    for n in range(1, 9):
        rec = akit.load_trajectory(data, n)
        ref0, lag = before(data, n)
        c = rec.clock
        print(f"| {n} | {lag:.2f} | {_cells(imu_from_zero(data, n), ref0)} | "
              f"{c.offset_s:+.3f}, {c.rate:.5f}, {c.dvl_offset_s:+.2f} | "
              f"{_cells(rec.imu, rec.reference)} |", flush=True)


if __name__ == "__main__":
    main()
