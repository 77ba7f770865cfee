"""Plain-text and Markdown tables of navigation metrics (CLI output, docs)."""
from __future__ import annotations

import numpy as np
import pandas as pd

from fuzzynav.metrics import improvement_ci, mean_ci

__all__ = ["NAV_ROWS", "comparison_rows", "render"]

#: (row label, metric key) in the order of the papers' tables
NAV_ROWS = (
    ("east position (m)", "rms_pos_e_m"), ("north position (m)", "rms_pos_n_m"),
    ("up position (m)", "rms_pos_u_m"), ("east velocity (m/s)", "rms_vel_e_mps"),
    ("north velocity (m/s)", "rms_vel_n_mps"), ("up velocity (m/s)", "rms_vel_u_mps"),
    ("pitch (deg)", "rms_pitch_deg"), ("roll (deg)", "rms_roll_deg"),
    ("heading (deg)", "rms_heading_deg"),
)


def _cell(values) -> str:
    est = mean_ci(values)
    if not np.isfinite(est.mean):
        return "—"
    return f"{est.mean:.4f}" if est.n < 2 else f"{est.mean:.4f} ± {est.half_width:.4f}"


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
        cells = [_cell(piv[f].to_numpy()) if f in piv else "—" for f in filters]
        imps = []
        if baseline is not None:
            for f in filters:
                if f == baseline or f not in piv:
                    continue
                imp = improvement_ci(piv[baseline].to_numpy(), piv[f].to_numpy())
                imps.append(f"{imp.mean:+.1f} %" if imp.n < 2
                            else f"{imp.mean:+.1f} % [{imp.lo:+.1f}, {imp.hi:+.1f}]")
        claim = list((claims or {}).get(key, ()))
        out.append([label, *cells, *imps, *claim])
    return out


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
