"""Plain-text and Markdown tables of navigation metrics (CLI output, docs)."""
from __future__ import annotations

import numpy as np
import pandas as pd

from fuzzynav.metrics import improvement_ci, mean_ci, summary_json

__all__ = ["NAV_ROWS", "ci_cell", "diff_cell", "improvement_cell", "comparison_rows",
           "pooled_rows", "scenario_rows", "render", "summary_document"]

#: (row label, metric key) in the order of the papers' tables
NAV_ROWS = (
    ("east position (m)", "rms_pos_e_m"), ("north position (m)", "rms_pos_n_m"),
    ("up position (m)", "rms_pos_u_m"), ("east velocity (m/s)", "rms_vel_e_mps"),
    ("north velocity (m/s)", "rms_vel_n_mps"), ("up velocity (m/s)", "rms_vel_u_mps"),
    ("pitch (deg)", "rms_pitch_deg"), ("roll (deg)", "rms_roll_deg"),
    ("heading (deg)", "rms_heading_deg"),
)


def ci_cell(values, fmt: str = ".4f", half_fmt: str | None = None) -> str:
    """One table cell ``mean ± half width`` of the Student-t 95 % interval over runs.

    Parameters
    ----------
    values : array_like
        Per-run values (non-finite ones are dropped, as :func:`~fuzzynav.metrics.mean_ci`).
    fmt : str
        Format spec of the mean (``".4f"``, ``".3g"``, ...).
    half_fmt : str, optional
        Format spec of the half width (default ``fmt``).

    Returns
    -------
    str
        ``"—"`` without a finite value, the bare mean from one value, else ``"m ± h"``.
    """
    est = mean_ci(np.asarray(values, float))
    if not np.isfinite(est.mean):
        return "—"
    if est.n < 2:
        return f"{est.mean:{fmt}}"
    return f"{est.mean:{fmt}} ± {est.half_width:{half_fmt or fmt}}"


def diff_cell(est, fmt: str = "+.3f", bound_fmt: str | None = None) -> str:
    """A paired difference as ``"+m [lo, hi]"``: its mean and 95 % interval.

    Parameters
    ----------
    est : Estimate
        :func:`~fuzzynav.metrics.mean_ci` of the per-run differences (``mean``, ``lo``,
        ``hi``).
    fmt : str
        Format spec of the mean (``"+.3f"``, ``"+.3g"``, ...); give the sign (``+``) so
        that a gain and a loss read apart.
    bound_fmt : str, optional
        Format spec of the two bounds (default ``fmt``), e.g. fewer significant digits
        than the mean: ``diff_cell(est, "+.3g", "+.2g")``.

    Returns
    -------
    str
        The cell, whatever ``est.n`` (callers that print one pair bare test it).
    """
    bound_fmt = bound_fmt or fmt
    return f"{est.mean:{fmt}} [{est.lo:{bound_fmt}}, {est.hi:{bound_fmt}}]"


def improvement_cell(base, cand) -> str:
    """The paired change of ``cand`` against ``base`` (same runs), ``"+m % [lo, hi]"``:
    :func:`~fuzzynav.metrics.improvement_ci` (positive = ``cand`` smaller); from one pair
    the bare ``"+m %"``."""
    imp = improvement_ci(np.asarray(base, float), np.asarray(cand, float))
    if imp.n < 2:
        return f"{imp.mean:+.1f} %"
    return f"{imp.mean:+.1f} % [{imp.lo:+.1f}, {imp.hi:+.1f}]"



def pooled_rows(piv: pd.DataFrame, filters, baseline: str, subset=None, *,
                fmt: str = ".2f", label=str) -> list:
    """Rows of a table of per-run values, pooled, with the paired change against a baseline.

    Parameters
    ----------
    piv : DataFrame
        One row per run (trajectory, seed), one column per filter.
    filters : sequence of str
        The columns of ``piv`` given a row, in order.
    baseline : str
        The column the changes are against (its own change cells are empty).
    subset : array_like of bool, optional
        A mask over ``piv``'s rows (e.g. all but an outlier run): the pooled value and the
        change again on those runs alone.
    fmt : str
        Format spec of the per-run values and of the pooled ``mean ± half width``.
    label : callable
        Filter column -> the name printed first in its row.

    Returns
    -------
    list of list
        Per filter: its label, one value per row of ``piv``, then :func:`ci_cell` and
        :func:`improvement_cell` over all runs, and over ``subset`` if given.
    """
    rows = []
    for f in filters:
        col = piv[f]
        cells = [f"{v:{fmt}}" for v in col]
        for runs in ([slice(None)] if subset is None else [slice(None), subset]):
            cells += [ci_cell(col[runs], fmt),
                      "" if f == baseline else improvement_cell(piv[baseline][runs], col[runs])]
        rows.append([label(f), *cells])
    return rows

def summary_document(df: pd.DataFrame, scenario: str, filters, seeds,
                     prefixes=("rms_", "max_"), label=None) -> dict:
    """The ``--json`` document of a table of runs: ``{"scenario", "seeds", "filters": {F:
    {metric: summary_json}}}``, the metrics those of ``df``'s columns starting with one of
    ``prefixes``; ``label(f)`` names filter ``f``'s entry (default ``f``)."""
    metrics = [c for c in df.columns if c.startswith(tuple(prefixes))]
    out = {"scenario": scenario, "seeds": list(seeds), "filters": {}}
    for f in filters:
        sub = df[df["filter"] == f]
        out["filters"][f if label is None else label(f)] = {m: summary_json(sub[m])
                                                            for m in metrics}
    return out


def comparison_rows(df: pd.DataFrame, filters, baseline=None, rows=NAV_ROWS, claims=None):
    """Rows of a comparison table: label, one cell per filter, improvements, claims.

    ``df`` has one row per (filter, seed) with metric columns.  Cells are ``mean ± 95 % CI``
    over seeds; improvements are paired (same seeds) with a bootstrap 95 % interval.
    ``claims`` maps a metric key to a tuple of published values to print beside ours.
    """
    out = []
    for label, key in rows:
        if key not in df or df[key].isna().all():
            continue
        piv = df.pivot_table(index="seed", columns="filter", values=key)
        cells = [ci_cell(piv[f].to_numpy()) if f in piv else "—" for f in filters]
        imps = []
        if baseline is not None:
            for f in filters:
                if f == baseline or f not in piv:
                    continue
                imps.append(improvement_cell(piv[baseline].to_numpy(), piv[f].to_numpy()))
        claim = list((claims or {}).get(key, ()))
        out.append([label, *cells, *imps, *claim])
    return out


def ratio_table(dfs: dict, filters: dict, keys, names: str, ref: str = "ekf") -> str:
    """Markdown table: per filter (label -> spec) and scenario (``dfs``: name -> runs), the
    mean over seeds of each metric's ratio to ``ref`` on the same seed, as ``"a / b / c"``
    in the order of ``keys`` (``names`` heads the columns, e.g. ``"pos / vel / att"``)."""
    rows = []
    for label, spec in filters.items():
        cells = []
        for df in dfs.values():
            parts = []
            for key in keys:
                piv = df.pivot_table(index="seed", columns="filter", values=key)
                parts.append(f"{mean_ci((piv[spec] / piv[ref]).to_numpy()).mean:.2f}")
            cells.append(" / ".join(parts))
        rows.append([label, *cells])
    return render(["filter"] + [f"{s}: {names}" for s in dfs], rows, markdown=True)


def render(header, rows, markdown=False) -> str:
    """Render rows as an aligned text table or a Markdown table (short rows padded)."""
    rows = [list(r) + ["—"] * (len(header) - len(r)) for r in rows]
    if markdown:
        lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
        return "\n".join(lines)
    cols = list(zip(*([header] + [list(map(str, r)) for r in rows])))
    widths = [max(len(c) for c in col) for col in cols]
    fmt = "  ".join(f"{{:<{w}}}" if i == 0 else f"{{:>{w}}}" for i, w in enumerate(widths))
    lines = [fmt.format(*header), fmt.format(*("-" * w for w in widths))]
    lines += [fmt.format(*map(str, r)) for r in rows]
    return "\n".join(lines)


def scenario_rows(df: pd.DataFrame, candidates, others=(), value: str = "score"):
    """Per-scenario rows of a run table: one row per (scenario, candidate filter).

    ``df`` has one row per (scenario, seed, filter) and a ``value`` column that is already
    a ratio to the reference filter (the EKF: 1 on every run by construction), as
    :func:`fuzzynav.tuning.evaluate.run_table` writes it.  A row is ``scenario, filter,
    runs, mean ± 95 % CI`` (:func:`ci_cell`, over that scenario's seeds), the paired change
    against the reference (:func:`improvement_cell` against ones) and against each of
    ``others`` on the same seeds (``"—"`` where that filter did not run, and against
    itself).
    """
    rows = []
    for scenario, sub in df.groupby("scenario", sort=False):
        piv = sub.pivot_table(index="seed", columns="filter", values=value, dropna=False)
        for cand in candidates:
            if cand not in piv:
                continue
            c = piv[cand].to_numpy(float)
            cells = [improvement_cell(np.ones_like(c), c)]
            cells += [improvement_cell(piv[o].to_numpy(float), c)
                      if o in piv and o != cand else "—" for o in others]
            rows.append([scenario, cand, int(np.isfinite(c).sum()), ci_cell(c, ".3f"),
                         *cells])
    return rows
