"""``fuzzynav study run | export | report``: learn rules with Optuna (or PSO), export, inspect."""
from __future__ import annotations

import os
from pathlib import Path

from fuzzynav.cli.values import check_count
from fuzzynav.errors import FuzzynavError

#: more worker processes than this only queue on the machine's cores (and its memory)
MAX_WORKERS = 4 * (os.cpu_count() or 1)


def register(sub) -> None:
    p = sub.add_parser("study", help="tune fuzzy rules: run, export, report")
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


def _load(args):
    from fuzzynav.tuning.config import load_study_config

    return load_study_config(args.config)


def _open(cfg, args):
    from fuzzynav.tuning.study import open_study

    return open_study(cfg, args.storage)  # a missing study: FuzzynavError, no file created


def _baseline_study(args):
    """The ``run`` / ``report`` module of a baseline study file, or None (a fuzzy study)."""
    from fuzzynav.tuning.baselines import is_baseline_config

    if not is_baseline_config(args.config):
        return None
    from fuzzynav.tuning import baseline_report

    return baseline_report


def _cmd_run(args) -> int:
    from fuzzynav.tuning.warmup import compile_by_running, compiling

    if _baseline_study(args) is not None:
        return _baseline_study(args).cmd_run(args)
    check_count("--trials", args.trials)
    check_count("--workers", args.workers, hi=MAX_WORKERS)
    with compiling() as cold:  # a cold kernel cache: loading the config already compiles
        cfg = _load(args)
        if cold:
            compile_by_running(cfg, args.cache)
    from fuzzynav.tuning.run import run_study

    study = run_study(cfg, args.trials, args.workers, args.storage, args.cache)
    print(f"study {cfg.name}: {len(study.trials)} trials in {args.storage or cfg.storage_url}")
    if not args.no_summary:
        _print_summary(cfg, study, args.cache)
    return 0


def _print_summary(cfg, study, cache):
    from fuzzynav.tuning.evaluate import format_summary, run_table
    from fuzzynav.tuning.export import choose_trial, systems_of
    from fuzzynav.tuning.objective import Evaluator

    try:
        trial = choose_trial(study, cfg)
    except FuzzynavError as exc:  # e.g. every trial so far failed or was pruned
        print(f"no summary: {exc}")
        return
    print(f"best trial {trial.number}: score "
          f"{trial.values if cfg.multi_objective else round(trial.value, 4)} "
          f"(ratios to {cfg.baseline}: "
          + ", ".join(f"{k} {v:.3f}" for k, v in (trial.user_attrs.get('ratios') or {}).items())
          + ")")
    ev = Evaluator(cfg, cache)
    systems = systems_of(cfg, trial)
    compare = tuple(f for f in dict.fromkeys(cfg.compare) if f != cfg.baseline)
    train = run_table(ev, systems, cfg.train, compare)
    test = run_table(ev, systems, cfg.test, compare)
    print("mean ratio of RMS error to the EKF (95 % CI over runs; < 1 beats the EKF):")
    print(format_summary(train, test))


def _cmd_export(args) -> int:
    from fuzzynav.tuning.export import export_rules

    cfg = _load(args)
    paths = export_rules(cfg, _open(cfg, args), args.out, args.trial, args.pareto, args.cache)
    for p in paths:
        print(f"wrote {p}")
    return 0


def _cmd_report(args) -> int:
    from fuzzynav.tuning.report import write_report

    if _baseline_study(args) is not None:
        return _baseline_study(args).cmd_report(args)
    cfg = _load(args)
    out = args.out or (Path(args.config).parent / f"{cfg.name}_report")
    path = write_report(cfg, _open(cfg, args), out, args.cache, evaluate=not args.no_eval)
    print(f"wrote {path}")
    print(f"interactive: optuna-dashboard {(args.storage or cfg.storage_url).replace('journal:', '')}")
    return 0
