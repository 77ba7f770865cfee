"""``fuzzynav compare <alignment scenario>``: the alignment filters' table with the claims."""
from __future__ import annotations

import json

from fuzzynav.align.scenario import load_alignment_scenario
from fuzzynav.align.alignment_run import ALIGN_ROWS, align_spec, seed_runs
from fuzzynav.align.fine import r_policy
from fuzzynav.errors import FuzzynavError, brief
from fuzzynav.experiment import monte_carlo
from fuzzynav.metrics import mean_ci
from fuzzynav.report import comparison_rows, render

__all__ = ["MAX_THRESHOLD_ARCMIN", "compare_alignment", "ALIGNED_NAV_ROWS", "parse_align_spec",
           "run_with_alignment", "describe_alignment"]


def _refuse(args, *options) -> None:
    """Options that mean nothing here: one line, not silence."""
    given = [flag for attr, flag in options if getattr(args, attr, None)]
    if given:
        raise FuzzynavError(f"{', '.join(given)}: not available with alignment "
                            "(compare on an alignment scenario, run --align)")


#: largest azimuth threshold (arcmin): half a turn; more means nothing
MAX_THRESHOLD_ARCMIN = 180.0 * 60.0


def compare_alignment(args, filters, claims=None, claim_labels=(), rows=(),
                      streaming_of=lambda rate_hz: {}) -> int:
    """Run ``filters`` on ``args.mc`` seeds of an alignment scenario and print the table;
    ``streaming_of(imu_rate_hz)``'s ``chunk_samples`` (``--chunk``), if any, simulates and
    mechanizes each seed in chunks (:func:`~.alignment_run.streamed_epochs`)."""
    _refuse(args, ("plot", "--plot"), ("t_start", "--t-start"),
            ("output_rate", "--output-rate (its outputs are its filter epochs)"),
            ("output_dir", "--output-dir"))
    scn = load_alignment_scenario(args.scenario)
    chunk = streaming_of(scn.imu.rate_hz).get("chunk_samples")
    fuzzy = [f for f in filters if align_spec(f)[0].fuzzy]
    if args.rules and len(args.rules) > 1:
        raise FuzzynavError("--rules: the alignment filters take one rule file (ROR -> t)")
    if args.rules and not fuzzy:
        raise FuzzynavError(f"--rules: no filter of {', '.join(filters)} takes a rule file "
                            "(the fuzzy ones do: align-fuzzy, align-fuzzy-fast)")
    if args.rules:
        r_policy(args.rules[0])  # a file that is not an R-scaling controller: refused now
    thr = getattr(args, "align_threshold", None)
    if thr is not None and not 0 < thr <= MAX_THRESHOLD_ARCMIN:
        raise FuzzynavError(f"--align-threshold must be in (0, {MAX_THRESHOLD_ARCMIN:g}] "
                            f"arcmin, got {thr}")
    seeds = list(range(args.seed, args.seed + args.mc))
    df = monte_carlo(scn, filters, seeds, progress=not args.json and args.mc > 1,
                     seed_runs=seed_runs(scn, (args.rules or [None])[0], thr, chunk))
    thr = scn.threshold_arcmin if thr is None else thr
    if args.json:
        out = {"scenario": scn.name, "seeds": seeds, "threshold_arcmin": thr, "filters": {}}
        for f in filters:
            sub = df[df["filter"] == f]
            out["filters"][f] = {k: {"mean": mean_ci(sub[k]).mean,
                                     "ci95": [mean_ci(sub[k]).lo, mean_ci(sub[k]).hi]}
                                 for _, k in (*(rows or ALIGN_ROWS), ("", "aligned_pct"))}
        print(json.dumps(out, indent=2))
        return 0
    header = ["alignment", *filters, *(f"{f} vs {filters[0]}" for f in filters[1:]),
              *claim_labels]
    print(f"scenario {scn.name} ({scn.duration_s:.0f} s), azimuth threshold {thr:g} arcmin, "
          f"seeds {seeds[0]}..{seeds[-1]}"
          + (" — mean ± 95 % CI over seeds" if len(seeds) > 1 else "") + "\n"
          + render(header, comparison_rows(df, filters, filters[0], rows=rows or ALIGN_ROWS,
                                           claims=claims)))
    never = df.groupby("filter", sort=False)["aligned_pct"].apply(lambda v: int((v == 0).sum()))
    print(f"runs never within {thr:g} arcmin to the end (time counted as the run length): "
          + ", ".join(f"{f} {never[f]}/{len(seeds)}" for f in filters))
    return 0


#: rows of ``run --align``: the aligned attitude, then the navigation
ALIGNED_NAV_ROWS = (("aligned heading error (deg)", "align_heading_err_deg"),
                    ("aligned level error (deg)", "align_level_err_deg"))


def parse_align_spec(text: str):
    """``"align-fuzzy@FILE"`` -> ``("align-fuzzy", "FILE")``; ``"align-kf"`` -> ``(.., None)``;
    ``"align-kf-tuned@FILE"``: FILE is its tuned-parameter file.

    The aligner's rule file is given with the aligner: ``--rules`` belongs to the
    navigation filter (``run --filter fakf --align align-fuzzy --rules F`` used to send F
    to the aligner and leave fakf on its default rules).
    """
    from fuzzynav.align.tuned import tuned_params

    try:
        spec, file = align_spec(text)
    except FuzzynavError as exc:
        if type(exc) is not FuzzynavError:
            raise
        raise FuzzynavError(f"--align {exc}") from None
    if spec.tuned:
        tuned_params(file)  # a bad parameter file: refused now, naming file and field
    elif file:
        r_policy(file)  # refused now if it is not an R-scaling controller
    return spec.name, file


def run_with_alignment(args, streaming_of=lambda rate_hz: {}, plot_traces=None) -> int:
    """``fuzzynav run SCENARIO --filter F --align A``: align on the rest, then navigate;
    ``streaming_of(imu_rate_hz)``: the run's ``chunk_samples``, ``output_rate_hz`` and
    ``output_dir`` (``--chunk``, ``--output-rate``, ``--output-dir``), with which the
    scenario is simulated and run chunk by chunk (:func:`~.chain.run_aligned_streamed`).

    Like every table of runs, a diverged run prints nothing and exits 3
    (:func:`fuzzynav.runpath.check_outcomes`).  ``--json`` prints the runs' summary
    (:func:`fuzzynav.report.summary_document`, the aligned attitude's errors with the
    navigation's); ``--plot DIR`` draws the first seed's run with ``plot_traces(traces,
    name, seed, DIR, output_rate_hz, json_on_stdout)`` (the command line's figures), from the run the
    table was made of: its errors from the navigation's start, at the output rate.
    """
    import pandas as pd

    from fuzzynav.report import NAV_ROWS, summary_document
    from fuzzynav.runpath import check_outcomes
    from fuzzynav.sim.scenario import load_scenario

    _refuse(args, ("t_start", "--t-start"))
    if args.plot and plot_traces is None:
        raise FuzzynavError("--plot: no figures here (run_with_alignment without plot_traces)")
    scn = load_scenario(args.scenario)
    streaming = streaming_of(scn.imu.rate_hz)
    seeds = list(range(args.seed, args.seed + args.mc))
    align, rules = parse_align_spec(args.align)
    outcomes, traces = [], None
    for seed in seeds:
        out, trace = _aligned_run(args, scn, seed, streaming, align, rules,
                                  figures=bool(args.plot) and seed == seeds[0])
        outcomes.append(out)
        traces = traces or trace
    check_outcomes(outcomes)   # a diverged run: no table, no figure, exit 3
    df = pd.DataFrame([{"filter": args.filter, "seed": o.seed, **o.metrics} for o in outcomes])
    label = f"{args.align} -> {args.filter}"
    if args.json:
        doc = summary_document(df, scn.name, [args.filter], seeds,
                               prefixes=("rms_", "max_", "align_"), label=lambda f: label)
        print(json.dumps(doc, indent=2, allow_nan=False))
    else:
        print(f"scenario {scn.name}: aligned with {args.align} on the opening rest (until "
              f"{df['align_end_s'].iloc[0]:.0f} s), then {args.filter}; seeds "
              f"{seeds[0]}..{seeds[-1]}\n"
              + render(["error", label],
                       comparison_rows(df, [args.filter], rows=(*ALIGNED_NAV_ROWS, *NAV_ROWS))))
    if traces is not None:
        plot_traces({label: traces}, scn.name, seeds[0], args.plot,
                    streaming.get("output_rate_hz"), args.json)
    return 0


def _aligned_run(args, scn, seed, streaming, align, rules, figures=False):
    """One seed of :func:`run_with_alignment`: its outcome and, with ``figures``, its
    (errors, event logs) from the navigation's start."""
    from fuzzynav.align.chain import run_aligned, run_aligned_streamed
    from fuzzynav.fileio import safe_stem
    from fuzzynav.metrics import errors_vs_trajectory
    from fuzzynav.sim.sensor_log import simulate

    opts = {"rules": list(args.rules)} if args.rules else {}
    if streaming:  # simulated chunk by chunk, aligned on the chunks of the rest
        kw = dict(streaming, cache_dir=args.cache, trace=figures)
        if "output_dir" in kw:
            kw["output_dir"] = f"{kw['output_dir']}/{safe_stem(args.filter)}-seed{seed}"
        out = run_aligned_streamed(scn, seed, args.filter, opts, align, rules, **kw)
        return out, (out.trace.errors, out.trace.events) if figures else None
    log = simulate(scn, seed, args.cache)
    out = run_aligned(log, args.filter, opts, align, rules)
    return out, ((errors_vs_trajectory(out.result, log.truth), out.result.events)
                 if figures else None)


def describe_alignment() -> str:
    """The alignment scenarios and filters, for ``fuzzynav scenarios``."""
    from fuzzynav.align.alignment_run import ALIGN_FILTERS
    from fuzzynav.align.scenario import list_alignment_scenarios

    lines = ["\nalignment scenarios (compare NAME --filters align-kf,align-fuzzy,...):"]
    for name in list_alignment_scenarios():
        scn = load_alignment_scenario(name)
        lines.append(f"  {name:<24} {scn.duration_s:7.0f} s  {scn.description}")
    lines.append("\nalignment filters (compare --filters, run --align):")
    lines += [f"  {f.name:<24} {f.description}" for f in ALIGN_FILTERS.values()]
    return "\n".join(lines)
