"""The richer fuzzy controller (``studies/paper000_fair_ctl.toml``) against the tuned baselines.

Tunes the controller of ``paper000_fair_ctl.toml`` (rq-scaling: R step and Q level, inputs
selected among ROR, NIS, trend, speed, angular rate and |f| - g, Mamdani or Sugeno) with
``--trials`` trials on the training runs of ``paper000_fair.toml``, runs it and the classical
filters with the tuned parameters already in ``studies/paper000_baselines.json`` on every
held-out run, and prints per scenario the paired difference of its score against the best
classical baseline, with 95 % CIs (never pooled).  It reuses the scoring of
:mod:`fuzzynav.pages.science` and writes no page (``docs/science.md`` is that page's)::

    nice python -m fuzzynav.pages.fairctl --trials 30 --workers 2 --work /tmp/ctl
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

import pandas as pd

from fuzzynav.pages import scores as sc
from fuzzynav.pages.science import cpu_minutes
from fuzzynav.pages.common import REPO_ROOT as ROOT

__all__ = ["STUDY", "PARAMS", "tune", "held_out_table", "verdict_line", "main"]

STUDY = ROOT / "studies" / "paper000_fair_ctl.toml"
PARAMS = ROOT / "studies" / "paper000_baselines.json"


def tune(trials: int, workers: int, work: Path, cache: str):
    """Run (or resume) the study; the chosen trial's systems and the config."""
    from fuzzynav.tuning.study_config import load_study_config
    from fuzzynav.tuning.export import choose_trial, systems_of
    from fuzzynav.tuning.study_run import run_study

    cfg = load_study_config(STUDY)
    study = run_study(cfg, trials, workers, f"journal:{work / 'fair_ctl.journal'}", cache)
    trial = choose_trial(study, cfg)
    return cfg, systems_of(cfg, trial), trial


def held_out_table(cfg, systems, params, cache) -> pd.DataFrame:
    """The tuned controller (labelled :data:`~fuzzynav.pages.scores.FUZZY`) and every
    filter of the study's ``compare`` -- the tuned ones with ``params`` -- on its held-out
    runs: one row per run and filter with the RMS metrics."""
    from fuzzynav.filters.baselines import TUNED
    from fuzzynav.pages.science_eval import fuzzy_rows, named_rows

    runs = list(cfg.test)
    specs = {n: f"{n}@{params}" if n in TUNED else n for n in cfg.compare}
    return pd.concat([fuzzy_rows(cfg, systems, runs, sc.FUZZY, cache),
                      named_rows(cfg, specs, runs, cache)], ignore_index=True)


def verdict_line(tally: dict, n_scenarios: int) -> str:
    """The controller's wins, draws and losses against the best classical filter."""
    return (f"`{sc.FUZZY}` wins {tally['wins against']}, draws {tally['draws with']} and "
            f"loses {tally['loses to']} of {n_scenarios} held-out sets against the best "
            "classical filter of each (paired 95 % CIs, never pooled)")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--trials", type=int, default=30, help="trials (default 30, the "
                                                          "baselines' budget)")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--work", required=True, help="directory for the journal and the runs")
    p.add_argument("--seeds", type=int, help="held-out seeds per scenario (default: all)")
    p.add_argument("--cache", default=os.environ.get(
        "FUZZYNAV_CACHE", str(Path.home() / ".cache" / "fuzzynav")), help="simulation cache")
    args = p.parse_args(argv)
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    t0 = time.time()
    cfg, systems, trial = tune(args.trials, args.workers, work, args.cache)
    if args.seeds:
        keep = sorted({d for _, d in cfg.test})[:args.seeds]
        cfg = replace(cfg, test=tuple(r for r in cfg.test if r[1] in keep))
    df = held_out_table(cfg, systems, PARAMS, args.cache)
    df.to_csv(work / "fair_ctl_runs.csv", index=False)
    scenarios = list(dict.fromkeys(s for s, _ in cfg.test))
    scores = sc.scores_to(df, sc.REF)
    rows, text, tally = sc.comparison_lines(scores, scenarios)
    print(f"trial {trial.number}: training value {trial.value:.4f}; params {trial.params}")
    print("\n".join(sc.ratio_table(scores, list(dict.fromkeys(df["filter"])), scenarios)))
    print("\n".join(rows + [""] + text + [""]))
    print(verdict_line(tally, len(scenarios)))
    print(f"{(time.time() - t0) / 60:.1f} min wall, {cpu_minutes():.1f} min CPU")
    return 0


if __name__ == "__main__":
    sys.exit(main())
