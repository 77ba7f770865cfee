"""``fuzzynav run/compare SCENARIO --segments``: the errors per motion segment.

The runs' ``seg<j>_...`` metrics (:mod:`fuzzynav.metrics_segments`, accumulated chunk by
chunk on a streamed run) as a second table under the usual one, a row per segment of the
scenario, or as the ``segments`` list of the ``--json`` document.

Imported by the command line's parser: the table's imports wait for a table.
"""
from __future__ import annotations

from fuzzynav.errors import FuzzynavError

__all__ = ["add_segments_argument", "refuse_segments", "segment_table", "segment_document",
           "segment_spans"]

#: the table's columns per filter: (header, metric, format); of several filters, the first
#: and the last only (the JSON has every metric)
_COLUMNS = (("h RMS (m)", "rms_pos_h_m", ".3f"), ("h at end (m)", "end_pos_h_m", ".3f"),
            ("heading RMS (deg)", "rms_heading_deg", ".3f"))


def add_segments_argument(p) -> None:
    p.add_argument("--segments", action="store_true",
                   help="simulated scenarios: also report the errors per motion segment "
                        "(the scenario's [[segments]]: horizontal RMS, largest and final "
                        "horizontal error, vertical, velocity and heading RMS), whole or "
                        "streamed (accumulated chunk by chunk); --plot marks them on the "
                        "error curves")


def refuse_segments(args, why: str) -> None:
    """Refuse ``--segments`` by name where it does not apply (``why``: where that is)."""
    if getattr(args, "segments", False):
        raise FuzzynavError(f"--segments: {why}")


def _spans(scn):
    from fuzzynav.metrics_segments import scenario_edges_s

    edges = scenario_edges_s(scn)
    return [(j, seg.kind, float(edges[j]), float(edges[j + 1]))
            for j, seg in enumerate(scn.segments)]


def segment_spans(scn) -> list:
    """``(start_s, end_s, "j kind")`` of each segment: the marks of the error curves."""
    return [(t0, t1, f"{j + 1} {kind}") for j, kind, t0, t1 in _spans(scn)]


def _pivot(df, metric):
    return df.pivot_table(index="seed", columns="filter", values=metric, dropna=False)


def segment_table(df, scn, filters, baseline=None) -> str:
    """The per-segment table of runs ``df`` (one row per filter and seed, with the
    ``seg<j>_...`` columns) on ``scn``: mean ± 95 % CI over seeds; with a ``baseline``, the
    paired improvement of the horizontal RMS over it."""
    import numpy as np

    from fuzzynav.metrics_segments import key
    from fuzzynav.report import ci_cell, improvement_cell, render

    columns = _COLUMNS if len(filters) == 1 else (_COLUMNS[0], _COLUMNS[-1])
    header = ["segment", "from-to (s)"]
    header += [f"{f} {h}" for f in filters for h, _, _ in columns]
    others = [f for f in filters if baseline is not None and f != baseline]
    header += [f"{f} vs {baseline} h RMS" for f in others]
    rows = []
    for j, kind, t0, t1 in _spans(scn):
        row = [f"{j + 1} {kind}", f"{t0:g}-{t1:g}"]
        for f in filters:
            for _, metric, fmt in columns:
                piv = _pivot(df, key(j, metric))
                row.append(ci_cell(piv[f].to_numpy(), fmt) if f in piv else "—")
        piv = _pivot(df, key(j, "rms_pos_h_m"))
        for f in others:
            base, cand = piv[baseline].to_numpy(), piv[f].to_numpy()
            ok = np.isfinite(base) & np.isfinite(cand)
            row.append(improvement_cell(base[ok], cand[ok]) if ok.any() else "—")
        rows.append(row)
    return (f"per motion segment ({len(rows)} segments of {scn.name}"
            + (", mean ± 95 % CI over seeds" if df["seed"].nunique() > 1 else "")
            + "; — : no epoch scored)\n" + render(header, rows))


def segment_document(df, scn, filters, label=None) -> list:
    """The ``segments`` list of the ``--json`` document: per segment its index, kind, span
    and, per filter (``label(f)`` names it), every metric's :func:`summary_json`."""
    from fuzzynav.metrics import summary_json
    from fuzzynav.metrics_segments import SEGMENT_METRICS, key

    out = []
    for j, kind, t0, t1 in _spans(scn):
        entry = {"segment": j + 1, "kind": kind, "start_s": t0, "end_s": t1, "filters": {}}
        for f in filters:
            sub = df[df["filter"] == f]
            entry["filters"][f if label is None else label(f)] = {
                m: summary_json(sub[key(j, m)]) for m in SEGMENT_METRICS}
        out.append(entry)
    return out
