"""``fuzzynav run --data akit:DIR:N`` — tables and JSON in the layout of ``--data rtklib``.

One column per trajectory plus ``all`` (mean ± 95 % CI over the trajectories); ``--json``
gives, per column, every metric as ``{"mean", "ci95", "values"}`` like the rtklib feeds.
"""
from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pandas as pd

from fuzzynav.errors import FuzzynavError
from fuzzynav.runpath import check_outcomes

__all__ = ["POOLED", "text_summary", "json_summary", "run_akit"]

POOLED = "all"


def _pooled(df):
    """The per-trajectory rows again under the column :data:`POOLED` (seed = trajectory)."""
    out = df.copy()
    out["filter"] = POOLED
    return out


def _labels(df):
    return list(dict.fromkeys(df["filter"])) + ([POOLED] if len(df) > 1 else [])


def text_summary(spec, recs, filter_name, df) -> str:
    """Header lines and the table."""
    from fuzzynav.report import comparison_rows, render
    from fuzzynav.realdata.akit import INIT_OPTIONS, ROWS

    labels = _labels(df)
    lines = [f"recording {spec}: trajectories {', '.join(str(r.trajectory) for r in recs)}, "
             f"filter {filter_name}, DVL-aided from the reference at the start "
             f"(attitude sigma {INIT_OPTIONS['init_att_sigma_deg']} deg, position "
             f"{INIT_OPTIONS['init_pos_sigma_m']} m)",
             "reference stamps - IMU time [s] at the start " + ", ".join(
                 f"{r.trajectory}: {r.clock.offset_s:+.3f}" for r in recs)
             + "; reference point " + ", ".join(f"{r.reference_offset_b[1]:.2f}" for r in recs)
             + " m ahead of the IMU",
             "scored against the post-processed reference (Delph INS) at its 1-Hz epochs"
             + (f"; column {POOLED}: mean ± 95 % CI over trajectories" if len(df) > 1 else "")]
    full = df if len(df) < 2 else pd.concat([df, _pooled(df)], ignore_index=True)
    lines.append(render(["metric", *labels], comparison_rows(full, labels, rows=ROWS)))
    bad = df[df["completed"] < 1]
    if len(bad):
        lines.append(f"warning: {len(bad)} run(s) stopped early (covariance lost)")
    return "\n".join(lines)


def json_summary(spec, recs, filter_name, df) -> dict:
    """Everything of the run as JSON-ready data (the rtklib layout: columns of metrics)."""
    from fuzzynav.fileio import json_ready
    from fuzzynav.metrics import summary_json
    from fuzzynav.realdata.akit import INIT_OPTIONS

    metric_cols = [c for c in df.columns if c.startswith(("rms_", "max_", "mean_", "end_"))
                   or c == "distance_m"]
    full = df if len(df) < 2 else pd.concat([df, _pooled(df)], ignore_index=True)
    feeds = {}
    for label in _labels(df):
        sub = full[full["filter"] == label]
        feeds[label] = {m: summary_json(sub[m]) for m in metric_cols}
    return json_ready({"data": str(spec), "directory": str(recs[0].directory),
                   "filter": filter_name, "trajectories": [r.trajectory for r in recs],
                   "settings": {k: list(v) if isinstance(v, tuple) else v
                                for k, v in INIT_OPTIONS.items()},
                   "start": {str(r.trajectory): {"reference_offset_s": r.clock.offset_s,
                                                 "reference_clock_rate": r.clock.rate,
                                                 "dvl_offset_s": r.clock.dvl_offset_s,
                                                 "reference_offset_b_m": list(r.reference_offset_b)}
                             for r in recs},
                   "feeds": feeds,
                   "status": {f"traj {r.trajectory}": s for r, s in
                              zip(recs, ["ok" if c >= 1 else "stopped" for c in df["completed"]])}})


def run_akit(spec, recs, filter_name, options, args, streaming=None) -> int:
    """Run, print the table or JSON; ``--plot DIR`` writes a trajectory and error figure
    (``streaming``: ``chunk_samples`` / ``output_rate_hz`` of every run, the metrics those
    of the whole run)."""
    from fuzzynav.realdata.akit import outcomes_table, run_outcomes

    from fuzzynav.filters.chunk_files import run_files

    # --output-dir: DIR/FILTER-seed0/trajN (nothing is drawn: one seed)
    outcomes = run_outcomes(recs, filter_name, options,
                            **run_files(dict(streaming or {}), filter_name, 0))
    # the guarantee every source keeps: non-finite metrics print nothing and exit 3 (the
    # attitude is not scored against the reference here: its RMS columns are NaN by design)
    check_outcomes([replace(o, filter=filter_name, scenario=f"{spec} (traj {r.trajectory})",
                            seed=r.trajectory)
                    for r, o in zip(recs, outcomes)], "recording")
    df, results = outcomes_table(recs, outcomes)
    if (df["completed"] < 1).any():
        raise FuzzynavError(f"{spec}: the filter stopped early on some trajectory "
                            "(covariance lost)")
    if args.json:
        print(json.dumps(json_summary(spec, recs, filter_name, df), indent=2))
    else:
        print(text_summary(spec, recs, filter_name, df))
    if args.plot:
        from fuzzynav.fileio import say_written
        from fuzzynav.realdata.akit_figures import write_figures

        for path in write_figures(recs, results, Path(args.plot), filter_name):
            say_written(path, args.json)
    return 0
