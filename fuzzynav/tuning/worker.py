"""One study worker process: ``python -m fuzzynav.tuning.worker CONFIG --total N ...``.

Started by :func:`fuzzynav.tuning.study_run.run_study` (one per ``--workers``) where workers are
not forked; it opens the study file's plan (:mod:`fuzzynav.tuning.kinds`: any kind of
study), loads study ``--part`` from the shared storage and runs trials until it holds
``--total`` finished ones.  Killing it (even with SIGKILL) loses no completed trial: its
running trial is failed and retried by the next worker that starts a trial (see
:func:`study.reap_stale`).
"""
from __future__ import annotations

import argparse
import sys

from fuzzynav.errors import FuzzynavError

__all__ = ["main"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m fuzzynav.tuning.worker")
    ap.add_argument("config")
    ap.add_argument("--total", type=int, required=True)
    ap.add_argument("--storage")
    ap.add_argument("--index", type=int, default=0)
    ap.add_argument("--cache")
    ap.add_argument("--part", default="", help="which of the file's studies (default: its one)")
    ap.add_argument("--study-seed", type=int, help="the tuning seed of a --study-seeds run")
    args = ap.parse_args(argv)
    from fuzzynav.tuning.kinds import load_plan
    from fuzzynav.tuning.optuna_study import run_worker

    try:
        plan = load_plan(args.config, args.cache)
        if args.study_seed is not None:
            from fuzzynav.tuning.tuning_seeds import seeded_plan

            plan = seeded_plan(plan, args.study_seed)
        run_worker(plan.config(args.part), args.total, args.storage, args.index, args.cache,
                   make_objective=lambda worker: plan.objective(args.part, worker))
    except FuzzynavError as exc:
        print(f"fuzzynav worker {args.index}: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
