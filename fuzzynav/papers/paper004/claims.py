"""Paper 004's published results, printed beside ours — never asserted in tests.

Wang Di, Wang Bing et al., adaptive-PSO SINS/DVL integration, J. Chinese Inertial Technology
2023 (see ../shared/seeds/DIGEST.md).  The figures are from the authors' 1 050-s lake test
(IMU 200 Hz, DVL 1 Hz, reference RTK + fibre-optic SINS), not from a simulation: our
``paper004`` scenarios imitate its conditions, they do not reproduce its data.  The paper
gives APSO's improvement over KF (-49.39 %) and over Huber (-36.98 %) on the mean error.
"""
from __future__ import annotations

from fuzzynav.papers.claims import PaperClaims, register

__all__ = ["PAPER004_LAKE", "PAPER004_IMPROVEMENT"]

#: lake test: (KF, Huber, APSO) horizontal error [m]
PAPER004_LAKE = {
    "mean_pos_h_m": (3.30, 2.65, 1.67),
    "max_pos_h_m": (6.82, 5.85, 3.44),
}
#: the paper's stated improvements of APSO on the mean horizontal error [%]
PAPER004_IMPROVEMENT = {"vs KF": -49.39, "vs Huber": -36.98}


def _cells(kf, huber, apso):
    # the same sign as our improvement columns: positive = smaller error than the KF
    return (f"{kf:g}", f"{huber:g}", f"{apso:g}", f"{100.0 * (kf - apso) / kf:+.1f} %")


register(PaperClaims(
    prefix="paper004",
    labels=("paper KF (claim)", "paper Huber (claim)", "paper APSO (claim)",
            "paper APSO impr. (claim)"),
    table={k: _cells(*v) for k, v in PAPER004_LAKE.items()},
    rows=(("mean horizontal error (m)", "mean_pos_h_m"),
          ("max horizontal error (m)", "max_pos_h_m"),
          ("RMS horizontal error (m)", "rms_pos_h_m"),
          ("RMS velocity (m/s)", "rms_vel_mps"),
          ("heading (deg)", "rms_heading_deg")),
))
