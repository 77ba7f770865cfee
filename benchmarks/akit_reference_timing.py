"""Is the A-KIT reference on the IMU's clock after the loader's lag correction?  (docs/paper004.md)

For each trajectory the gyros alone are integrated from the reference attitude at the start
(earth rate ignored: 0.1 deg in 30 s), with the reference read ``shift`` seconds later on the
IMU clock than the loader places it; the RMS heading difference over the first 30 s is
printed for the loaded timing and for the best shift.  A navigation-grade gyro integrated
for 30 s should follow the reference to a few hundredths of a degree; a timing error shows
as heading error proportional to the turn rate.  Usage:
``python benchmarks/akit_reference_timing.py`` (reads ``$FUZZYNAV_DATA/akit``).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from fuzzynav.nav import attitude
from fuzzynav.sim.loaders.akit import load_trajectory

ROOT = Path(__file__).resolve().parents[1]
SECONDS = 30
SHIFTS = np.round(np.arange(0.0, 1.01, 0.1), 1)


def heading_rms(rec, shift: float, secs: int = SECONDS) -> float:
    """RMS up-axis attitude difference [deg]: gyro integration vs the reference read
    ``shift`` s later on the IMU clock."""
    imu, ref = rec.imu, rec.reference
    k0 = int(round(shift / np.median(np.diff(imu.time_s))))
    C, out = attitude.quat_to_dcm(ref.q_bn[0]), {}
    for k in range(k0, k0 + secs * 100):
        C = C @ attitude.rotvec_to_dcm(imu.dtheta_b[k])
        out[k + 1] = C
    err = []
    for j in range(1, secs - 1):
        k = k0 + int(round((ref.time_s[j] - ref.time_s[0]) * 100))
        if k in out:
            err.append(np.rad2deg(attitude.attitude_error(
                out[k], attitude.quat_to_dcm(ref.q_bn[j])))[2])
    return float(np.sqrt(np.mean(np.square(err))))


def main():
    data = Path(os.environ.get("FUZZYNAV_DATA", ROOT.parent / "shared" / "datasets")) / "akit"
    print("| traj | loader's lag (reference samples) | best further shift (s) | "
          "heading RMS, first 30 s (deg): as loaded → shifted |")
    print("|---|---|---|---|")
    for n in range(1, 9):
        rec = load_trajectory(data, n)
        r = [heading_rms(rec, s) for s in SHIFTS]
        i = int(np.argmin(r))
        print(f"| {n} | {rec.lag_samples:.2f} | {SHIFTS[i]:+.1f} | {r[0]:.2f} → {r[i]:.2f} |")


if __name__ == "__main__":
    main()
