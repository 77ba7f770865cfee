"""``fuzzynav study run | export | report``: learn rules with Optuna (or PSO), export, inspect.

One driver for every kind of study file (:mod:`fuzzynav.tuning.kinds`): fuzzy controllers,
classical baselines (``[baselines]``, paper 004's APSO among them) and the alignment
filter's rules (``kind = "alignment"``).
"""
from __future__ import annotations

import os
from pathlib import Path

from fuzzynav.cli.values import check_count

__all__ = ["MAX_WORKERS", "register"]

#: more worker processes than this only queue on the machine's cores (and its memory)
MAX_WORKERS = 4 * (os.cpu_count() or 1)


def register(sub) -> None:
    p = sub.add_parser("study", help="tune rules or filters: run, export, report")
    ss = p.add_subparsers(dest="study_command", metavar="ACTION")
    ss.required = True
    r = ss.add_parser("run", help="run (or resume) a study until it holds --trials trials")
    _common(r)
    r.add_argument("--trials", type=int, help="total finished trials wanted (default: config)")
    r.add_argument("--workers", type=int, default=1, help="worker processes (default 1)")
    r.add_argument("--no-summary", action="store_true",
                   help="skip the final train/test evaluation of the best trial")
    r.set_defaults(func=_cmd_run)
    e = ss.add_parser("export", help="write the best (or a chosen) trial as rule files")
    _common(e)
    e.add_argument("--out", required=True, help="rule file to write (rules/NAME.json)")
    e.add_argument("--trial", type=int, help="trial number (default: the best)")
    e.add_argument("--pareto", type=int, help="Pareto member (multi-objective studies)")
    e.set_defaults(func=_cmd_export)
    rp = ss.add_parser("report", help="trials table, figures and the train/test table")
    _common(rp)
    rp.add_argument("--out", help="report directory (default: <config dir>/<name>_report)")
    rp.add_argument("--no-eval", action="store_true", help="skip the train/test evaluation")
    rp.set_defaults(func=_cmd_report)


def _common(p) -> None:
    from fuzzynav.cli.nav import default_cache_dir

    p.add_argument("config", help="study configuration (studies/*.toml)")
    p.add_argument("--storage", help="Optuna storage URL (default: journal file next to the "
                                     "config), e.g. postgresql://user@host/db")
    p.add_argument("--cache", default=str(default_cache_dir()), help="simulation cache")
    p.add_argument("--study-seeds", type=int, metavar="N",
                   help="tune N times with sampler seeds [study] seed + 0..N-1, each into "
                        "its own study <name>-seed<S> (see docs/studies.md)")


def _plan(args):
    """The plan of the study file (:mod:`fuzzynav.tuning.kinds`: fuzzy, baselines or
    alignment -- the same driver, storages, workers and outputs for each)."""
    from fuzzynav.tuning.kinds import load_plan

    return load_plan(args.config, args.cache)


def _tunings(plan, args) -> list:
    """``[(seed, plan)]``: the file's one study, or one per ``--study-seeds`` tuning."""
    from fuzzynav.tuning.tuning_seeds import tunings

    check_count("--study-seeds", args.study_seeds)
    return tunings(plan, args.study_seeds)


def _seeded_path(path, seed):
    """``rules/x.json`` -> ``rules/x-seed<S>.json`` (unchanged without a tuning seed)."""
    path = Path(path)
    return path if seed is None else path.with_name(f"{path.stem}-seed{seed}{path.suffix}")


def _open(plan, args) -> dict:
    from fuzzynav.tuning.study_run import open_plan_studies

    return open_plan_studies(plan, args.storage)  # a missing study: error, no file created


def _cmd_run(args) -> int:
    from fuzzynav.tuning.warmup import compile_by_running, compiling

    check_count("--trials", args.trials)
    check_count("--workers", args.workers, hi=MAX_WORKERS)
    check_count("--study-seeds", args.study_seeds)
    with compiling() as cold:  # a cold kernel cache: loading the config already compiles
        plan = _plan(args)
        if cold and plan.kind == "fuzzy":
            compile_by_running(plan.cfg, args.cache)
    from fuzzynav.tuning.study_run import run_plan

    for seed, one in _tunings(plan, args):
        if seed is not None:
            print(f"tuning seed {seed}: study {one.name}")
        studies, lines = run_plan(one, args.trials, args.workers, args.storage)
        for line in lines:
            print(line)
        if not args.no_summary:
            one.summary(studies)
    return 0


def _cmd_export(args) -> int:
    plan = _plan(args)
    for seed, one in _tunings(plan, args):
        out = _seeded_path(args.out, seed)
        for p in one.export(_open(one, args), out, args.trial, args.pareto):
            print(f"wrote {p}")
    return 0


def _cmd_report(args) -> int:
    from fuzzynav.tuning.tuning_seeds import tuned_names, write_spread_report

    plan = _plan(args)
    out = Path(args.out or (Path(args.config).parent / f"{plan.name}_report"))
    runs = _tunings(plan, args)
    for seed, one in runs:
        where = out if seed is None else out / f"seed{seed}"
        print(f"wrote {one.report(_open(one, args), where, evaluate=not args.no_eval)}")
    if args.study_seeds is not None and not args.no_eval:
        seeds = [seed for seed, _ in runs]
        print(f"wrote {write_spread_report(plan, seeds, out, tuned_names(plan))}")
    last = runs[-1][1]  # (a journal per tuning: the last one's)
    url = args.storage or (last.config(last.parts()[0]).storage_url if last.parts() else None)
    if url:
        print(f"interactive: optuna-dashboard {url.replace('journal:', '')}")
    return 0
