"""Paper 001's published results, printed beside ours — never asserted in tests.

Paper 001 (Ma Wei, Li Yuan et al., federated polarization/SINS/BDS/geomagnetic filter; see
../shared/seeds/DIGEST.md) prints the combined (federated, no-reset) solution's east and north
position errors and states, without figures we could quote, that the SINS/BDS +
polarization pair beats the two pairs with the magnetometer.  They come from the authors'
vehicle run, whose IMU, BDS and magnetometer figures are not published; they are
references, not targets.
"""
from __future__ import annotations

from fuzzynav.papers.claims import PaperClaims, register

__all__ = ["PAPER001_COMBINED", "PAIRWISE"]

#: the combined solution's errors [m]
PAPER001_COMBINED = {"rms_pos_e_m": 3.2305, "rms_pos_n_m": 3.7419}
#: the pairwise statement, on the rows it is about
PAIRWISE = "pol pair best"

register(PaperClaims(
    prefix="paper001",
    labels=("paper combined (claim)", "paper pairs (claim)"),
    table={"rms_pos_e_m": (f"{PAPER001_COMBINED['rms_pos_e_m']:g}", PAIRWISE),
           "rms_pos_n_m": (f"{PAPER001_COMBINED['rms_pos_n_m']:g}", PAIRWISE),
           "rms_heading_deg": ("—", PAIRWISE)},
))
