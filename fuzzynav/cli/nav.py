"""``fuzzynav scenarios`` and ``fuzzynav run``: simulate or load data, run a filter, score it."""
from __future__ import annotations

import json
import os
from pathlib import Path

from fuzzynav.cli.segment_table import add_segments_argument, refuse_segments
from fuzzynav.cli.values import check_common, check_t_start
from fuzzynav.errors import FuzzynavError
from fuzzynav.fileio import safe_stem, say_written

__all__ = ["default_cache_dir", "register", "add_source_arguments", "add_recording_arguments",
           "DEFAULT_CHUNK_S", "add_streaming_arguments", "streaming_options",
           "add_common_arguments", "data_sources", "filter_options", "check_rules",
           "run_scenario_filters", "plot_traces"]


def default_cache_dir() -> Path:
    """Simulation cache: ``$FUZZYNAV_CACHE`` or ``~/.cache/fuzzynav``."""
    return Path(os.environ.get("FUZZYNAV_CACHE", Path.home() / ".cache" / "fuzzynav"))


def register(sub) -> None:
    p = sub.add_parser("scenarios", help="list built-in scenarios, data sources and filters")
    p.set_defaults(func=_cmd_scenarios)
    p = sub.add_parser("run", help="run one filter on a scenario (or a recording) and print RMS")
    add_source_arguments(p)
    p.add_argument("--filter", default="ekf", help="named filter (see `fuzzynav scenarios`)")
    p.add_argument("--align", metavar="ALIGN_FILTER",
                   help="align on the scenario's opening rest with this alignment filter "
                        "(align-kf, align-fuzzy, ...; align-fuzzy@FILE with its own rule "
                        "file, align-kf-tuned@FILE with its tuned-parameter file) and start "
                        "the navigation from it")
    add_common_arguments(p)
    add_streaming_arguments(p)
    add_recording_arguments(p)
    p.set_defaults(func=_cmd_run)
    p = sub.add_parser("compare", help="compare filters on a scenario (the papers' table layout)")
    p.add_argument("scenario", help="built-in scenario name or scenario TOML file")
    p.add_argument("--filters", default="ekf,fakf",
                   help="comma-separated named filters (NAME@RULES[+RULES] runs a filter with "
                        "its own rule files); the first is the baseline of the improvement "
                        "column (default: %(default)s)")
    add_common_arguments(p)
    add_streaming_arguments(p)
    p.add_argument("--align-threshold", type=float, metavar="ARCMIN",
                   help="alignment scenarios: azimuth threshold of the alignment time "
                        "(default: the scenario's, 10 arcmin)")
    p.set_defaults(func=_cmd_compare, data=None)


def add_source_arguments(p) -> None:
    p.add_argument("scenario", nargs="?", help="built-in scenario name or scenario TOML file")
    p.add_argument("--data", metavar="KIND:DIR[:SESSION]",
                   help="a recording instead of a scenario, e.g. rtklib:path/to/drive, or a "
                        "dataset of fuzzynav data list: rtklib-drive, akit:3 (after fuzzynav "
                        "data fetch NAME); SESSION picks one of several recordings in DIR "
                        "(the <id> of imu_<id>.csv)")


def add_recording_arguments(p) -> None:
    """Options of the real-data protocol (``--data``), if that part is installed."""
    try:
        from fuzzynav.realdata.cli import add_arguments
    except ImportError:  # pragma: no cover - real-data support not installed
        return
    add_arguments(p)


#: IMU seconds per chunk of a run with ``--output-rate`` and no ``--chunk``: a few minutes,
#: so a chunk's output arrays stay small whatever the run's length
DEFAULT_CHUNK_S = 300.0


def add_streaming_arguments(p) -> None:
    """``--output-rate``, ``--chunk`` and ``--output-dir`` of ``fuzzynav run`` (a simulated
    scenario or a recording, ``--data``) and ``fuzzynav compare``."""
    g = p.add_argument_group("long runs (simulated scenarios, recordings, alignment: --chunk)")
    g.add_argument("--output-rate", type=float, metavar="HZ",
                   help="keep the filter's recorded solution at this rate only (its output "
                        "rate, 10 Hz by default, divided by a whole number: 5, 2, 1, 0.1 ...); the "
                        "metrics are then accumulated chunk by chunk at the full output rate "
                        "(running sums for the RMS, exact maxima), equal to a whole-run "
                        "report up to rounding (a few ulps). Default: keep every output")
    g.add_argument("--chunk", type=float, metavar="S",
                   help="simulate the scenario and run the filter in chunks of S seconds of "
                        "IMU, carrying the sensors' random processes and the filter's whole "
                        "state across: the same data and filter arithmetic as a whole run, "
                        "with nothing of the run's length held, so a day-long run fits in a "
                        f"few hundred MB (default {DEFAULT_CHUNK_S:g} s with --output-rate "
                        "or --output-dir; without any of the three the log is simulated "
                        "whole and cached). An alignment scenario (compare paper002 ...) is "
                        "simulated and mechanized in chunks of S seconds (whole epochs), "
                        "its metrics those of the whole run to the last bit")
    g.add_argument("--output-dir", metavar="DIR",
                   help="write each chunk's kept solution (at --output-rate) and its event "
                        "logs (innovations, S, NIS, flags, adaptation traces) to "
                        "DIR/FILTER-seedK/chunk-NNNNNN.npz (each written to a temporary "
                        "file, then renamed); on an rtklib recording (read from its file) "
                        "DIR/FILTER-seedK/FEED/chunk-NNNNNN.npz for each feed of the "
                        "protocol (gnss, outages), on A-KIT DIR/FILTER-seed0/trajN/. Read "
                        "back with fuzzynav.filters.chunk_files.read_chunks. A DIR already "
                        "holding chunk files of an "
                        "earlier run is refused before anything runs")


def streaming_options(args, imu_rate_hz: float) -> dict:
    """``run``'s ``chunk_samples`` / ``output_rate_hz`` from ``--chunk`` / ``--output-rate``
    (empty when neither is given); refuses a non-positive or non-finite value."""
    rate, chunk = getattr(args, "output_rate", None), getattr(args, "chunk", None)
    out_dir = getattr(args, "output_dir", None)
    out = {} if out_dir is None else {"output_dir": out_dir}
    if out_dir is not None:  # before any run of the table writes
        from fuzzynav.filters.chunk_files import refuse_earlier_chunks

        refuse_earlier_chunks(out_dir)
    for flag, value in (("--output-rate", rate), ("--chunk", chunk)):
        if value is not None and not (0.0 < value < float("inf")):
            raise FuzzynavError(f"{flag} must be a positive number, got {value:g}")
    if rate is not None:
        out["output_rate_hz"] = float(rate)
    if (rate is not None or out_dir is not None) and chunk is None:
        chunk = DEFAULT_CHUNK_S
    if chunk is not None:
        out["chunk_samples"] = max(1, int(round(chunk * imu_rate_hz)))
    return out


def add_common_arguments(p) -> None:
    p.add_argument("--rules", action="append", metavar="FILE",
                   help="fuzzy rule file(s) for fuzzy filters (repeatable)")
    p.add_argument("--seed", type=int, default=0, help="first seed (default 0)")
    p.add_argument("--mc", type=int, default=1, metavar="K", help="Monte-Carlo runs (seeds)")
    p.add_argument("--t-start", type=float, default=0.0, metavar="S",
                   help="skip the first S seconds in the RMS (initial convergence)")
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.add_argument("--plot", metavar="DIR", help="write error-curve figures into DIR")
    p.add_argument("--cache", metavar="DIR", help="simulation cache (default: %(default)s)",
                   default=str(default_cache_dir()))
    add_segments_argument(p)


def _cmd_scenarios(args) -> int:
    from fuzzynav.filters.named import list_filters
    from fuzzynav.sim.scenario import list_scenarios, load_scenario

    print("built-in scenarios:")
    for name in list_scenarios():
        scn = load_scenario(name)
        print(f"  {name:<24} {scn.duration_s:7.0f} s  {scn.description}")
    print("\ndata sources (--data KIND:DIR[:SESSION], or a dataset NAME[:SESSION] of "
          "fuzzynav data list):")
    for kind, desc in data_sources().items():
        print(f"  {kind:<24} {desc}")
    print("\nfilters (--filter NAME):")
    for f in list_filters():
        print(f"  {f.name:<24} {f.description}")
    from fuzzynav.align.compare_cli import describe_alignment

    print(describe_alignment())
    return 0


def data_sources() -> dict:
    """Recording kinds usable with ``--data``."""
    try:
        from fuzzynav.realdata import SOURCES
    except ImportError:  # pragma: no cover - real-data support not installed
        return {}
    return {k: v.description for k, v in SOURCES.items()}


def filter_options(args) -> dict:
    """Filter options from the command line."""
    opts = {}
    if args.rules:
        opts["rules"] = list(args.rules)
    return opts


def check_rules(args, filters, option: str) -> None:
    """Refuse rule files that no filter would read, and missing ones, before any work.

    ``--rules`` goes to every filter of the run and ``NAME@RULES`` to one; a filter that
    takes no rule files would silently run without them.
    """
    from fuzzynav.filters.catalog import find_rule_file
    from fuzzynav.filters.named import get_filter, list_filters, parse_filter_spec

    takers = ", ".join(f.name for f in list_filters() if f.takes_rules)
    specs = [parse_filter_spec(f) for f in filters]
    for spec, (name, own) in zip(filters, specs):
        if own.get("rules") and not get_filter(name).takes_rules:
            raise FuzzynavError(f"{option} {spec}: filter {name!r} takes no rule files "
                                f"(filters that do: {takers})")
    if args.rules and not any(get_filter(name).takes_rules for name, _ in specs):
        names = ", ".join(repr(name) for name, _ in specs)
        raise FuzzynavError(f"--rules: filter{'s' if len(specs) > 1 else ''} {names} "
                            f"take{'' if len(specs) > 1 else 's'} no rule files (filters "
                            f"that do: {takers})")
    for path in [*(args.rules or []), *(r for _, own in specs for r in own.get("rules", []))]:
        find_rule_file(path)


def _cmd_run(args) -> int:
    if args.data is not None and not args.data.strip():
        raise FuzzynavError("--data is empty: give KIND:DIR, KIND:DIR:SESSION or a dataset "
                            "NAME (fuzzynav data list)")
    if (args.scenario is None) == (args.data is None):
        raise FuzzynavError("give either a SCENARIO or --data KIND:DIR")
    check_common(args)
    if args.data and args.align:
        raise FuzzynavError("--align: only with a simulated SCENARIO, not with --data")
    if args.data:
        refuse_segments(args, "only with a simulated SCENARIO (a recording has no motion "
                              "segments; its outages are tabled one by one)")
    if args.align:
        refuse_segments(args, "not with --align (the navigation starts inside the first "
                              "segment, at the alignment's end)")
    check_rules(args, [args.filter], "--filter")
    if args.data:
        from fuzzynav.realdata.cli import run_recording

        return run_recording(args.data, args.filter, filter_options(args), args,
                             lambda rate_hz: streaming_options(args, rate_hz))
    from fuzzynav.experiment import SimulatedSource
    from fuzzynav.realdata.cli import given_settings
    from fuzzynav.runpath import refuse_settings

    refuse_settings(SimulatedSource, given_settings(args))
    if args.align:
        from fuzzynav.align.compare_cli import run_with_alignment

        return run_with_alignment(args, lambda rate_hz: streaming_options(args, rate_hz),
                                  plot_traces)
    return run_scenario_filters(args, [args.filter], baseline=None)


def _cmd_compare(args) -> int:
    from fuzzynav.papers.claims import claims_for, rows_for

    filters = [f.strip() for f in args.filters.split(",")]
    if "" in filters:  # a doubled or trailing comma: a filter the user meant may be missing
        raise FuzzynavError(f"--filters {args.filters!r}: an empty filter name (a doubled or "
                            "trailing comma)")
    if len(filters) < 2:
        raise FuzzynavError("--filters needs at least two comma-separated filter names")
    twice = sorted({f for f in filters if filters.count(f) > 1})
    if twice:  # the columns (and the claims beside them) would no longer line up
        raise FuzzynavError(f"--filters names {', '.join(twice)} twice")
    check_common(args)
    labels, claims = claims_for(str(args.scenario))
    from fuzzynav.align.scenario import is_alignment_scenario

    if is_alignment_scenario(str(args.scenario)):  # alignment filters: their own runner
        from fuzzynav.align.compare_cli import compare_alignment

        refuse_segments(args, "not for alignment scenarios (one rest, no motion segments)")
        return compare_alignment(args, filters, claims, labels, rows_for(str(args.scenario)),
                                 lambda rate_hz: streaming_options(args, rate_hz))
    if args.align_threshold is not None:
        raise FuzzynavError("--align-threshold: only for alignment scenarios (paper002...)")
    check_rules(args, filters, "--filters")
    return run_scenario_filters(args, filters, baseline=filters[0], claims=claims,
                                claim_labels=labels, rows=rows_for(str(args.scenario)))


def run_scenario_filters(args, filters, baseline=None, claims=None, claim_labels=(),
                         rows=()) -> int:
    """Simulate, run ``filters`` on ``args.mc`` seeds, print the table, plot if asked."""
    from fuzzynav.experiment import monte_carlo
    from fuzzynav.report import NAV_ROWS, comparison_rows, render, summary_document
    from fuzzynav.sim.scenario import load_scenario

    scn = load_scenario(args.scenario)
    check_t_start(args.t_start, scn.duration_s)
    seeds = list(range(args.seed, args.seed + args.mc))
    # a diverged run: no table at all, exit 3
    df = monte_carlo(scn, filters, seeds, filter_options(args), args.cache, args.t_start,
                     progress=not args.json and args.mc > 1, refuse_diverged=True,
                     streaming=streaming_options(args, scn.imu.rate_hz),
                     segments=args.segments)
    if args.json:
        doc = summary_document(df, scn.name, filters, seeds)
        if args.segments:  # a segment before --t-start has no epoch scored: null
            from fuzzynav.cli.segment_table import segment_document
            from fuzzynav.fileio import json_ready

            doc["segments"] = json_ready(segment_document(df, scn, filters))
        print(json.dumps(doc, indent=2, allow_nan=False))
    else:
        header = ["RMS error", *filters]
        if baseline is not None:
            header += [f"{f} vs {baseline}" for f in filters if f != baseline]
        header += list(claim_labels)
        bad = df[df["completed"] < 1]
        print(f"scenario {scn.name} ({scn.duration_s:.0f} s), seeds "
              f"{seeds[0]}..{seeds[-1]}"
              + (" — mean ± 95 % CI over seeds" if len(seeds) > 1 else "") + "\n"
              + render(header, comparison_rows(df, filters, baseline, rows=rows or NAV_ROWS,
                                              claims=claims))
              + (f"\nwarning: {len(bad)} run(s) stopped early (covariance lost)"
                 if len(bad) else ""))
        if args.segments:
            from fuzzynav.cli.segment_table import segment_table

            print("\n" + segment_table(df, scn, filters, baseline))
    if args.plot:
        _plot_first_seed(scn, filters, seeds[0], args)
    return 0


def _plot_first_seed(scn, filters, seed, args) -> None:
    streaming = streaming_options(args, scn.imu.rate_hz)
    traces = (_streamed_traces if streaming else _whole_traces)(scn, filters, seed, args,
                                                                streaming)
    spans = ()
    if args.segments:
        from fuzzynav.cli.segment_table import segment_spans

        spans = segment_spans(scn)
    plot_traces(traces, scn.name, seed, args.plot, streaming.get("output_rate_hz"), args.json,
                spans)


def plot_traces(traces, name: str, seed: int, out_dir, output_rate_hz=None,
                json_on_stdout: bool = False, segments=()) -> None:
    """Write ``<name>_errors.png`` (and ``<name>_adaptation.png`` when a filter adapts) into
    ``out_dir`` (``--plot DIR``) from ``traces``: label -> (errors, event logs) of the runs
    on seed ``seed``, at ``output_rate_hz`` when their outputs were decimated
    (``json_on_stdout``: the notices of the files go to stderr, :func:`~fuzzynav.fileio.
    say_written`; ``segments``: ``(start_s, end_s, label)`` marked on the error curves)."""
    from fuzzynav import plots

    out_dir, stem = Path(out_dir), safe_stem(name)
    errs = {f: errors for f, (errors, _) in traces.items()}
    title = f"{name}, seed {seed}" + (f" ({output_rate_hz:g}-Hz output)"
                                      if output_rate_hz else "")
    path = plots.save(plots.error_curves(errs, title, segments),
                      out_dir / f"{stem}_errors.png")
    say_written(path, json_on_stdout)
    series = {}
    for f, (_, events) in traces.items():
        for sensor, ev in events.items():
            for nm in ev.diag_names:
                series[f"{f} {sensor} {nm}"] = (ev.time_s, ev.diagnostic(nm))
    if series:
        path = plots.save(plots.adaptation_curves(series, "adaptation"),
                          out_dir / f"{stem}_adaptation.png")
        say_written(path, json_on_stdout)


def _whole_traces(scn, filters, seed, args, _streaming) -> dict:
    """Filter -> (errors, event logs) of runs on the whole simulated log."""
    from fuzzynav.experiment import run_on_log
    from fuzzynav.filters.named import parse_filter_spec
    from fuzzynav.metrics import errors_vs_trajectory
    from fuzzynav.sim.sensor_log import simulate

    log = simulate(scn, seed, args.cache)
    out = {}
    for f in filters:
        name, own = parse_filter_spec(f)
        res = run_on_log(log, name, {**filter_options(args), **own}).result
        out[f] = (errors_vs_trajectory(res, log.truth), res.events)
    return out


def _streamed_traces(scn, filters, seed, args, streaming) -> dict:
    """Filter -> (errors, event logs) of streamed runs, at their output rate
    (:class:`fuzzynav.streamtrace.StreamTrace`): nothing of the run's length is held."""
    from fuzzynav.experiment import streamed_run

    kw = {k: v for k, v in streaming.items() if k != "output_dir"}  # written by the table's run
    out = {}
    for f in filters:
        trace = streamed_run(scn, seed, f, filter_options(args), args.t_start,
                          {**kw, "trace": True}, args.cache).trace
        out[f] = (trace.errors, trace.events)
    return out
