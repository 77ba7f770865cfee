"""``fuzzynav study report`` of a baseline study (:mod:`fuzzynav.tuning.kinds.baseline_studies`).

The report writes ``report.md`` and ``runs.csv``: the tuned parameters
and the train / held-out table of the tuned filters beside the config's ``compare`` filters
(ratios to the baseline filter, 95 % CI over runs).
"""
from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from fuzzynav.fileio import staged, write_atomic
from fuzzynav.tuning.evaluate import format_summary, run_table, scenario_section
from fuzzynav.tuning.objective import Evaluator

__all__ = ["tuned_specs", "evaluate_baselines", "write_baseline_report"]


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


def write_baseline_report(bcfg, out, cache_dir=None, evaluate: bool = True) -> Path:
    """Write ``report.md`` (and ``runs.csv`` with ``evaluate``) of a baseline study into
    directory ``out`` (staged: all or nothing); returns the report's path."""
    out = Path(out)
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
    with staged(out, "study report", last=("report.md",)) as tmp:
        if doc is not None and evaluate:
            train, test = evaluate_baselines(bcfg, cache_dir)
            runs = pd.concat([train.assign(set="train"), test.assign(set="test")])
            write_atomic(tmp / "runs.csv", lambda t: runs.to_csv(t, index=False))
            lines += ["", f"## Train and held-out test (ratio of RMS error to "
                          f"{bcfg.study.baseline}; < 1 is better)", "", "```",
                      format_summary(train, test), "```", ""]
            lines += scenario_section(train, test, list(bcfg.tune), bcfg.study.baseline)
        text = "\n".join(lines) + "\n"
        write_atomic(tmp / "report.md", lambda t: Path(t).write_text(text))
    return out / "report.md"
