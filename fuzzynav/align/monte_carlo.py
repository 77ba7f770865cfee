"""Monte-Carlo alignment runs and their metrics.

The metric that matters is the **azimuth alignment time**: the first epoch after which the
azimuth error stays within the threshold (scenario ``threshold_arcmin``, 10 arcmin by
default) to the end of the run.  A run whose final error is outside never aligned: its
time is censored at the run length and ``aligned_pct`` (100 or 0 per run) says how many did.
Final errors are absolute values at the last epoch [arcmin].
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from fuzzynav import units
from fuzzynav.align import alignment_run as R
from fuzzynav.align.alignment_states import EAST, NORTH, UP
from fuzzynav.align.scenario import AlignScenario

__all__ = ["ALIGN_ROWS", "alignment_time", "metrics", "monte_carlo_alignment"]

#: (row label, metric key) of the comparison table
ALIGN_ROWS = (
    ("azimuth alignment time [s]", "align_time_s"),
    ("final |azimuth error| [arcmin]", "final_azimuth_arcmin"),
    ("final |east level error| [arcmin]", "final_level_e_arcmin"),
    ("final |north level error| [arcmin]", "final_level_n_arcmin"),
)


def alignment_time(time_s, err_u, threshold_rad) -> float:
    """First time after which ``|err_u| <= threshold`` to the end (NaN: never)."""
    bad = np.flatnonzero(np.abs(err_u) > threshold_rad)
    if bad.size == 0:
        return float(time_s[0])
    if bad[-1] == time_s.size - 1:
        return float("nan")
    return float(time_s[bad[-1] + 1])


def metrics(run: R.AlignRun, threshold_arcmin: float) -> dict:
    """The metrics of one run."""
    e = run.error
    t = run.result.time_s
    t_al = alignment_time(t, e[:, UP], threshold_arcmin * units.ARCMIN)
    return {"align_time_s": float(t[-1]) if np.isnan(t_al) else t_al,
            "aligned_pct": 0.0 if np.isnan(t_al) else 100.0,
            "final_azimuth_arcmin": abs(e[-1, UP]) / units.ARCMIN,
            "final_level_e_arcmin": abs(e[-1, EAST]) / units.ARCMIN,
            "final_level_n_arcmin": abs(e[-1, NORTH]) / units.ARCMIN}


def monte_carlo_alignment(scn: AlignScenario, filters, seeds, rules=None,
                          threshold_arcmin=None, progress=False) -> pd.DataFrame:
    """One row per (filter, seed) with :func:`metrics`; each seed is simulated once.

    Parameters
    ----------
    scn : AlignScenario
    filters : list of str
        Named alignment filters (:data:`fuzzynav.align.alignment_run.ALIGN_FILTERS`).
    seeds : iterable of int
    rules : str, optional
        Rule file for the fuzzy filters (default: the paper's).
    threshold_arcmin : float, optional
        Overrides the scenario's threshold.
    """
    for f in filters:
        R.get_align_filter(f)
    thr = scn.threshold_arcmin if threshold_arcmin is None else threshold_arcmin
    rows = []
    for i, seed in enumerate(seeds):
        log = R.simulate(scn, seed)
        ep = R.epochs(scn, log, seed)
        for f in filters:
            out = R.run_align_filter(f, scn, log, ep, rules=rules)
            rows.append({"filter": f, "seed": seed, **metrics(out, thr)})
        if progress:
            print(f"\r  seed {i + 1}", end="", flush=True)
    if progress:
        print("\r" + " " * 24 + "\r", end="", flush=True)
    return pd.DataFrame(rows)
