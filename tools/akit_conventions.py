"""The A-KIT conventions, measured: the numbers behind docs/data.md ("A-KIT AUV recordings").

For each trajectory: the accelerometer z mean; the correlation of each gyro column with the
reference's Euler rates (the file's y column is reversed); the clock map the loader finds
(reference offset at the start, its clock rate, the DVL's offset from the reference); the
reference-point offset; and the DVL against the reference velocity rotated into the body,
the reference interpolated at the DVL's times (forward RMS, lateral RMS before/after the
offset, forward scale fit).
Usage: ``python tools/akit_conventions.py [DIR]`` (default ``$FUZZYNAV_DATA/akit``).
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

from fuzzynav.report import render
from fuzzynav.realdata.loaders import akit_recording as akit

ROOT = Path(__file__).resolve().parents[1]


def _binned(imu, t, col):
    return np.array([imu[(imu[:, 0] >= a - 0.5) & (imu[:, 0] < a + 0.5), col].mean() for a in t])


def row(d: Path, n: int) -> list:
    imu = akit.read_table(d / f"IMU_trajectory{n}.csv", "IMU")
    gt = akit.read_table(d / "corrected" / f"GT_trajectory{n}.csv", "GT")
    rec = akit.load_trajectory(d, n)
    # Euler rates of the reference on the IMU clock (its stamps mapped by the loader)
    t = rec.reference.time_s
    labels = rec.clock.to_label(t)
    rates = [np.gradient(np.interp(labels, gt[:, 0], np.unwrap(gt[:, c])), t) for c in (7, 8, 9)]
    corr = [np.corrcoef(_binned(imu, t, 4 + i), rates[i])[0, 1] for i in range(3)]
    # the reference interpolated at the DVL's times on the IMU clock (not the next epoch)
    dvl = rec.dvl
    vb = akit.body_velocity(akit.reference_on_imu_clock(gt, rec.clock, dvl.time_s))
    d_b = dvl.z - vb
    lat_after = d_b[:, 0] - akit.yaw_rate_at(rec.imu, dvl.time_s) * rec.reference_offset_b[1]
    scale = np.dot(vb[:, 1], dvl.z[:, 1]) / np.dot(vb[:, 1], vb[:, 1])
    rms = lambda x: np.sqrt(np.mean(np.square(x)))  # noqa: E731
    return [n, f"{imu[:, 3].mean():.3f}", " / ".join(f"{c:+.2f}" for c in corr),
            f"{rec.clock.offset_s:+.3f}", f"{rec.clock.rate:.5f}", f"{rec.clock.dvl_offset_s:+.2f}",
            f"{rec.reference_offset_b[1]:.2f}", f"{rms(d_b[:, 1]):.3f}",
            f"{rms(d_b[:, 0]):.3f} → {rms(lat_after):.3f}", f"{rms(d_b[:, 2]):.3f}",
            f"{scale:.4f}"]


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    d = Path(argv[0]) if argv else Path(os.environ.get(
        "FUZZYNAV_DATA", ROOT.parent / "shared" / "datasets")) / "akit"
    head = ["traj", "acc z mean (m/s²)", "corr gyro x,y,z (file) vs roll, pitch, yaw rate",
            "reference offset (s)", "reference clock rate", "DVL − reference (s)",
            "reference point ahead (m)",
            "fwd RMS (m/s)", "lateral RMS (m/s) raw → offset", "vertical RMS (m/s)",
            "fwd scale"]
    print(render(head, [row(d, n) for n in range(1, 9)], markdown=True))


if __name__ == "__main__":
    main()
