"""``fuzzynav run --data KIND:DIR[:SESSION]``: the validation protocol from the command line.

Prints the table of the simulated ``run`` (one column per fed stream: GNSS throughout, with
outages), or JSON with ``--json``; ``--plot DIR`` writes the horizontal error against time
and the trajectory map (first seed).  Heavy imports happen inside :func:`run_recording` so
that building the parser stays cheap.
"""
from __future__ import annotations

import json
import math
import re
import sys
from dataclasses import asdict
from pathlib import Path

from fuzzynav.errors import FuzzynavError

__all__ = ["add_arguments", "given_settings", "refuse_unused_options", "settings_from",
           "load_recording", "streaming_of", "run_recording", "text_summary", "json_summary"]

#: option dest -> ProtocolSettings field (None on the command line = the settings' default)
_SETTINGS = {"noise": "noise_pos_m", "vel_noise": "noise_vel_mps",
             "outage_period": "outage_period_s", "outage_duration": "outage_duration_s",
             "first_outage": "first_outage_s", "gnss_velocity": "velocity",
             "velocity_lag": "velocity_lag_s", "nhc": "nhc_sigma_mps"}


def add_arguments(p) -> None:
    """The ``--data`` options of ``fuzzynav run`` (defaults: :class:`ProtocolSettings`)."""
    g = p.add_argument_group("recordings (with --data; defaults in docs/validation.md)")
    g.add_argument("--noise", type=float, metavar="M",
                   help="white noise added to each fed position axis [m] (default 2)")
    g.add_argument("--vel-noise", type=float, metavar="MPS",
                   help="white noise added to each fed velocity axis [m/s] (default 0)")
    g.add_argument("--outage-period", type=float, metavar="S",
                   help="one simulated outage every S seconds (default 180)")
    g.add_argument("--outage-duration", type=float, metavar="S",
                   help="length of each outage [s] (default 60; 0 = none)")
    g.add_argument("--first-outage", type=float, metavar="S",
                   help="first outage S seconds after the filter starts (default: one period)")
    g.add_argument("--gnss-velocity", choices=("shift", "raw", "inflate", "off"),
                   help="receiver velocities: read --velocity-lag later (shift, default), as "
                        "recorded (raw), with inflated sigma (inflate) or unused (off)")
    g.add_argument("--velocity-lag", type=float, metavar="S",
                   help="how late the receiver's velocities are [s] (default 0.14)")
    g.add_argument("--nhc", type=float, metavar="MPS",
                   help="feed non-holonomic constraints (zero lateral/vertical body "
                        "velocity) with this 1-sigma [m/s] at 10 Hz (default 0 = none)")
    g.add_argument("--mounting", default="auto", metavar="auto|none|NAME|FILE",
                   help="mounting TOML (IMU to body, lever arm) or a shipped one by name "
                        "(rtklib-drive); auto = mounting.toml beside the data if any, else "
                        "none = the IMU frame (default auto)")
    g.add_argument("--imu-delay", type=float, metavar="S",
                   help="IMU sample-to-logger delay [s] (default: the loader's)")
    g.add_argument("--span", metavar="START,END",
                   help="use only this stretch, seconds after the first IMU sample")


#: option dest -> flag of the run settings (:data:`fuzzynav.runpath.RUN_SETTINGS`) a source
#: may refuse
_FLAGS = {**{d: "--" + d.replace("_", "-") for d in _SETTINGS}, "imu_delay": "--imu-delay",
          "span": "--span", "mounting": "--mounting", "t_start": "--t-start", "mc": "--mc",
          "output_rate": "--output-rate", "chunk": "--chunk", "output_dir": "--output-dir"}


def given_settings(args) -> dict:
    """The run settings given on the command line (name -> flag), defaults left out."""
    defaults = {"mounting": "auto", "t_start": 0.0, "mc": 1}
    return {dest: flag for dest, flag in _FLAGS.items()
            if getattr(args, dest, None) not in (None, defaults.get(dest))}


def refuse_unused_options(spec, args) -> None:
    """The run settings of ``args`` that the source ``spec`` names does not use: one error
    naming them (:func:`fuzzynav.runpath.refuse_settings`)."""
    from fuzzynav.realdata.sources import parse_data_spec
    from fuzzynav.runpath import refuse_settings

    refuse_settings(parse_data_spec(spec)[0].source_type(), given_settings(args))


def settings_from(args):
    """:class:`ProtocolSettings` from parsed arguments."""
    from fuzzynav.realdata.protocol import ProtocolSettings

    kw = {field: getattr(args, dest) for dest, field in _SETTINGS.items()
          if getattr(args, dest, None) is not None}
    if getattr(args, "t_start", None):
        kw["t_start_s"] = float(args.t_start)
    try:
        return ProtocolSettings(**kw)
    except FuzzynavError as exc:  # the settings' field names, as the options the user gave
        flags = {field: _FLAGS[dest] for dest, field in {**_SETTINGS,
                                                          "t_start": "t_start_s"}.items()}
        raise FuzzynavError(re.sub(r"\b(" + "|".join(flags) + r")\b",
                                   lambda m: flags[m.group(1)], str(exc))) from None


def _span(text):
    if text is None:
        return None
    try:
        a, b = (float(x) for x in text.split(","))
    except ValueError:
        raise FuzzynavError(f"--span: expected START,END in seconds, got {text!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise FuzzynavError(f"--span: START and END must be finite seconds, got {text!r}")
    if not b > a:
        raise FuzzynavError(f"--span: END must exceed START, got {text!r}")
    return a, b


def load_recording(spec, args, streamed: bool = False):
    """Parse ``--data`` and load the recording with the loader options of ``args``
    (``streamed``: its IMU read from the file chunk by chunk, where its kind can)."""
    from fuzzynav.realdata.sources import data_options, parse_data_spec, resolve_mounting

    source, directory, session = parse_data_spec(spec)
    options = data_options(spec)
    mounting = resolve_mounting(getattr(args, "mounting", "auto"))
    kw = {} if options is None else {"options": options}  # loaders without options still load
    return source.load(directory, mounting=mounting,
                       imu_delay_s=getattr(args, "imu_delay", None),
                       span_s=_span(getattr(args, "span", None)), session=session,
                       streamed=streamed, **kw)


def streaming_of(streaming, rec) -> dict:
    """``run``'s ``chunk_samples`` / ``output_rate_hz``: ``streaming(imu_rate_hz)`` (the
    command line's ``--chunk`` / ``--output-rate``,
    :func:`fuzzynav.cli.nav.streaming_options`) at the rate of the loaded IMU increments
    (of the first recording of several: one kind has one rate); none without
    ``streaming``."""
    if streaming is None:
        return {}
    return streaming((rec[0] if isinstance(rec, list) else rec).imu.rate_hz)


def run_recording(spec, filter_name, options, args, streaming=None) -> int:
    """Load, run the protocol on ``args.mc`` seeds, print the table or JSON, plot if asked.

    ``streaming``, if given, maps the IMU rate [Hz] to ``run``'s streaming options
    (:func:`streaming_of`): each run is then fed in chunks, its output decimated.

    stdout failures (full disk, closed pipe) are handled once, in :func:`fuzzynav.cli.main`.
    """
    from fuzzynav.filters.chunk_files import run_files
    from fuzzynav.realdata.validate import check_finite, metrics_table, validate

    refuse_unused_options(spec, args)
    settings = settings_from(args)
    # streamed runs (--output-rate, --chunk, --output-dir) read an rtklib IMU from its file
    # chunk by chunk
    streamed = any(getattr(args, k, None) is not None
                   for k in ("output_rate", "chunk", "output_dir"))
    rec = load_recording(spec, args, streamed)
    span = max(r.imu.span_s[1] - r.imu.span_s[0]
               for r in (rec if isinstance(rec, list) else [rec]))
    if getattr(args, "t_start", 0.0) and not args.t_start < span:
        raise FuzzynavError(f"--t-start {args.t_start:g} s: the recording runs {span:.0f} s; "
                            "nothing would be scored")
    streaming = streaming_of(streaming, rec)
    if isinstance(rec, list):  # several recordings of one kind (akit trajectories)
        from fuzzynav.realdata.akit_cli import run_akit

        return run_akit(spec, rec, filter_name, options, args, streaming)
    seeds = list(range(args.seed, args.seed + args.mc))
    vals = [validate(rec, filter_name, settings, s, options, **run_files(streaming,
                                                                          filter_name, s))
            for s in seeds]
    check_finite(vals, spec)  # a diverged run: no table at all, exit 3
    check = vals[0].start.coarse.heading_check
    if check.startswith(("turned", "direction not checked")):
        print(f"note: start heading by {vals[0].start.coarse.method}: {check}",
              file=sys.stderr)
    df = metrics_table(vals)
    if args.json:
        print(json.dumps(json_summary(spec, rec, vals, df), indent=2))
    else:
        print(text_summary(spec, rec, vals, df))
    if args.plot:
        from fuzzynav.fileio import say_written
        from fuzzynav.realdata.figures import write_figures

        for path in write_figures(vals[0], rec, Path(args.plot)):
            say_written(path, args.json)
    return 0


def _rows(v):
    rows = [("horizontal position RMS (m)", "rms_pos_h_m"),
            ("  outside the outages (m)", "rms_pos_h_aided_m"),
            ("east position (m)", "rms_pos_e_m"), ("north position (m)", "rms_pos_n_m"),
            ("up position (m)", "rms_pos_u_m"), ("east velocity (m/s)", "rms_vel_e_mps"),
            ("north velocity (m/s)", "rms_vel_n_mps"), ("up velocity (m/s)", "rms_vel_u_mps")]
    done = [d for d in v.runs["outages"].drifts if d.complete]
    rows += [(f"error at end of outage {k} [{d.start_s:.0f}-{d.end_s:.0f} s] (m)",
              f"drift_h_m_{k}") for k, d in enumerate(done, 1)]
    rows += [("  RMS over outages (m)", "drift_h_rms_m"),
             ("  max over outages (m)", "drift_h_max_m"),
             ("largest error inside an outage (m)", "outage_max_h_m")]
    return rows


def _describe(spec, rec, v) -> list:
    s, st = v.settings, v.start.coarse
    vel = {"shift": f"velocities read {s.velocity_lag_s:g} s later", "raw": "velocities as "
           "recorded", "inflate": f"velocity sigma + {s.velocity_inflate_mps:g} m/s",
           "off": "positions only"}[s.velocity]
    n_done = sum(d.complete for d in v.runs["outages"].drifts)
    out = (f"outages {s.outage_duration_s:g} s every {s.outage_period_s:g} s from "
           f"{v.windows[0, 0]:.1f} s ({n_done} complete)" if len(v.windows) else "no outages")
    return [f"recording {spec}: {rec.imu.span_s[0]:.1f}-{rec.imu.span_s[1]:.1f} s, filter "
            f"starts at {v.start.init.time_s:.1f} s (rest {st.rest_s[0]:.1f}-{st.rest_s[1]:.1f}"
            f" s, heading {math.degrees(st.att[2]):.1f} deg by {st.method}"
            + (f": {st.heading_check})" if st.heading_check else ")"),
            f"fed: positions + {s.noise_pos_m:g} m white noise per axis, {vel}; {out}",
            f"scored against the RTK-fixed epochs (antenna); velocity against RTK velocity read "
            f"{s.velocity_lag_s:g} s later"]


def text_summary(spec, rec, vals, df) -> str:
    """The header lines and the table (mean ± 95 % CI over seeds when several)."""
    from fuzzynav.report import comparison_rows, render
    from fuzzynav.realdata.validate import FEEDS

    seeds = [v.seed for v in vals]
    lines = _describe(spec, rec, vals[0])
    lines.append(f"filter {vals[0].filter}, noise seeds {seeds[0]}..{seeds[-1]}"
                 + (" — mean ± 95 % CI over seeds" if len(seeds) > 1 else ""))
    labels = list(FEEDS.values())
    lines.append(render(["metric", *labels], comparison_rows(df, labels, rows=_rows(vals[0]))))
    bad = df[df["completed"] < 1]
    if len(bad):
        lines.append(f"warning: {len(bad)} run(s) stopped early (covariance lost)")
    return "\n".join(lines)


def json_summary(spec, rec, vals, df) -> dict:
    """Everything of the run as JSON-ready data (NaN -> null: only the metrics that may be
    NaN, :func:`~fuzzynav.realdata.validate.required_names`, reach it)."""
    from fuzzynav.fileio import json_ready
    from fuzzynav.metrics import summary_json
    from fuzzynav.realdata.mems import CONSUMER_MEMS
    from fuzzynav.realdata.validate import FEEDS

    v0 = vals[0]
    st = v0.start.coarse
    metric_cols = [c for c in df.columns if c.startswith(("rms_", "max_", "drift_", "outage_",
                                                          "n_outages"))]
    feeds = {}
    for label in FEEDS.values():
        sub = df[df["filter"] == label]
        feeds[label] = {m: summary_json(sub[m]) for m in metric_cols}
    outages = [{"start_s": d.start_s, "end_s": d.end_s, "complete": d.complete,
                "drift_h_m": {FEEDS[f]: [v.runs[f].drifts[i].drift_h_m for v in vals]
                              for f in FEEDS},
                "max_h_m": [v.runs["outages"].drifts[i].max_h_m for v in vals]}
               for i, d in enumerate(v0.runs["outages"].drifts)]
    return json_ready({
        "data": str(spec), "directory": str(rec.directory), "filter": v0.filter,
        "seeds": [v.seed for v in vals], "settings": v0.settings.as_dict(),
        "imu_model": asdict(CONSUMER_MEMS),
        "start": {"time_s": v0.start.init.time_s, "rest_s": list(st.rest_s),
                  "pitch_deg": math.degrees(st.att[0]), "roll_deg": math.degrees(st.att[1]),
                  "heading_deg": math.degrees(st.att[2]), "heading_method": st.method,
                  "heading_check": st.heading_check,
                  "gyro_bias_dps": [math.degrees(x) for x in st.gyro_bias_rps],
                  "options": asdict(rec.start_options) if hasattr(rec, "start_options")
                  else None},
        "outages": outages, "feeds": feeds,
        "status": {FEEDS[f]: [v.runs[f].result.status for v in vals] for f in FEEDS}})
