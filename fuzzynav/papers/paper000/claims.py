"""Paper 000's published results, printed beside ours — never asserted in tests.

Each entry maps a metric key to the paper's ``(EKF, FAKF, improvement %)`` as printed in the
paper (see ../shared/seeds/DIGEST.md).  They come from the authors' own simulation, whose
trajectory, noise and tuning are not published; they are references, not targets.
"""
from __future__ import annotations

from fuzzynav.papers.claims import PaperClaims, register

__all__ = ["PAPER000_TABLE2"]

#: Paper 000, Table 2 (RMS, EKF -> FAKF).  Roll is not simulated there.
PAPER000_TABLE2 = {
    "rms_pos_e_m": (5.7305, 2.4751, 56.81),
    "rms_pos_n_m": (9.0379, 3.1476, 65.17),
    "rms_pos_u_m": (2.5892, 1.3984, 45.99),
    "rms_vel_e_mps": (0.5799, 0.3074, 46.99),
    "rms_vel_n_mps": (0.7949, 0.3656, 54.01),
    "rms_vel_u_mps": (0.0849, 0.0477, 43.82),
    "rms_pitch_deg": (0.0031, 0.0013, 58.01),
    "rms_heading_deg": (0.2682, 0.1345, 53.58),
}


register(PaperClaims(
    prefix="paper000",
    labels=("paper EKF (claim)", "paper FAKF (claim)", "paper impr. (claim)"),
    table={k: (f"{e:g}", f"{f:g}", f"{i:+.1f} %") for k, (e, f, i) in PAPER000_TABLE2.items()},
))
