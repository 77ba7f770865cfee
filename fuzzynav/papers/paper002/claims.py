"""Paper 002's published results, printed beside ours — never asserted in tests.

Paper 002 (Wang Yuegang et al. 2013) states that the fuzzy adaptive filter aligns with the
accuracy of the plain KF and cuts the azimuth alignment time from over 300 s to under
150 s (with the fast azimuth estimate); it prints no threshold and no error table
(see ../shared/seeds/DIGEST.md).
"""
from __future__ import annotations

from fuzzynav.papers.claims import PaperClaims, register

register(PaperClaims(
    prefix="paper002",
    labels=("paper KF (claim)", "paper fuzzy+fast (claim)"),
    table={"align_time_s": ("> 300", "< 150"),
           "final_azimuth_arcmin": ("same as fuzzy", "same as KF")},
))
