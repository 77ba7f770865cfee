"""Paper 003's published results, printed beside ours — never asserted in tests.

Ma Hao, Xiong Jian et al., J. Applied Optics 2016 (../shared/seeds/DIGEST.md): over 1 800 s
the heading error "settles at" 0.6 deg, the horizontal velocity error stays below 0.7 m/s
and the horizontal position error is "about 10 m".  Only the integrated filter's figures
are given (no per-filter comparison), and they are read from the paper's curves: our RMS
and final values are the closest comparable numbers.
"""
from __future__ import annotations

from fuzzynav.papers.claims import PaperClaims, register

__all__ = ["PAPER003"]

PAPER003 = {
    "rms_heading_deg": "0.6 (settled)",
    "rms_vel_h_mps": "< 0.7",
    "rms_pos_h_m": "~10",
    "final_pos_h_m": "~10",
}

register(PaperClaims(
    prefix="paper003",
    labels=("paper 003 (claim)",),
    table={k: (v,) for k, v in PAPER003.items()},
    rows=(("heading (deg)", "rms_heading_deg"), ("horizontal velocity (m/s)", "rms_vel_h_mps"),
          ("horizontal position (m)", "rms_pos_h_m"),
          ("final horizontal position (m)", "final_pos_h_m"),
          ("pitch (deg)", "rms_pitch_deg"), ("roll (deg)", "rms_roll_deg")),
))
