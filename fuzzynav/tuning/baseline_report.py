"""``fuzzynav study run | report`` for a baseline study (:mod:`fuzzynav.tuning.baselines`).

``run`` tunes every listed filter (one Optuna study each, the config's budget) and writes the
tuned-parameter file; ``report`` writes ``report.md`` and ``runs.csv``: the tuned parameters
and the train / held-out table of the tuned filters beside the config's ``compare`` filters
(ratios to the baseline filter, 95 % CI over runs).
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import pandas as pd

from fuzzynav.fileio import staged, write_atomic
from fuzzynav.tuning.baselines import load_baseline_config, run_baselines
from fuzzynav.tuning.evaluate import format_summary, run_table
from fuzzynav.tuning.objective import Evaluator


def tuned_specs(bcfg) -> dict:
    """``NAME@FILE`` of every tuned filter -> its plain name (for tables)."""
    return {f"{n}@{bcfg.out}": n for n in bcfg.tune}


def evaluate_baselines(bcfg, cache_dir=None) -> tuple:
    """Train and test tables of the tuned filters and the ``compare`` filters."""
    cfg = bcfg.study
    ev = Evaluator(cfg, cache_dir)
    specs = tuned_specs(bcfg)
    names = tuple(dict.fromkeys([*specs, *cfg.compare]))
    train = run_table(ev, {}, cfg.train, names).replace({"filter": specs})
    test = run_table(ev, {}, cfg.test, names).replace({"filter": specs})
    return train, test


def cmd_run(args) -> int:
    """``study run`` of a baseline study."""
    bcfg = load_baseline_config(args.config)

    def progress(name, done, total):
        print(f"\r{name}: {done}/{total} trials", end="", file=sys.stderr, flush=True)

    path = run_baselines(bcfg, args.trials, args.storage, args.cache, progress)
    print(file=sys.stderr)
    print(f"wrote {path}")
    if not args.no_summary:
        train, test = evaluate_baselines(bcfg, args.cache)
        print(f"mean ratio of RMS error to {bcfg.study.baseline} (95 % CI over runs):")
        print(format_summary(train, test))
    return 0


def cmd_report(args) -> int:
    """``study report`` of a baseline study."""
    bcfg = load_baseline_config(args.config)
    out = Path(args.out or (Path(args.config).parent / f"{bcfg.study.name}_report"))
    doc = json.loads(bcfg.out.read_text()) if bcfg.out.is_file() else None
    lines = [f"# Baseline study `{bcfg.study.name}`", "", bcfg.study.description, "",
             f"Sampler `{bcfg.study.sampler}`, {bcfg.study.trials} trials per filter, "
             f"pruner `{bcfg.study.pruner}`; parameters in `{bcfg.out}`.", ""]
    if doc is None:
        lines += ["No tuned parameters yet: run the study first.", ""]
    else:
        lines += ["| filter | train score | parameters |", "|---|---|---|"]
        for name, params in doc["filters"].items():
            p = ", ".join(f"{k} = {v:.4g}" for k, v in params.items())
            lines.append(f"| {name} | {doc['train_score'].get(name, float('nan')):.3f} | {p} |")
    with staged(out, last=("report.md",)) as tmp:
        if doc is not None and not args.no_eval:
            train, test = evaluate_baselines(bcfg, args.cache)
            runs = pd.concat([train.assign(set="train"), test.assign(set="test")])
            write_atomic(tmp / "runs.csv", lambda t: runs.to_csv(t, index=False))
            lines += ["", f"## Train and held-out test (ratio of RMS error to "
                          f"{bcfg.study.baseline}; < 1 is better)", "", "```",
                      format_summary(train, test), "```"]
        text = "\n".join(lines) + "\n"
        write_atomic(tmp / "report.md", lambda t: Path(t).write_text(text))
    print(f"wrote {out / 'report.md'}")
    return 0
