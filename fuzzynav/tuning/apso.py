"""``python -m fuzzynav.tuning.apso CONFIG [--out FILE]``: paper 004's APSO, an alias.

Paper 004's adaptive PSO of the Q and R multipliers is a baseline study on the PSO sampler
(``studies/paper004_apso.toml``: ``[baselines] tune = ["apso"]``, ``sampler = "pso"``,
``[study.pso] inertia = [0.9, 0.4]``; :mod:`fuzzynav.tuning.baselines`,
:mod:`fuzzynav.tuning.pso`), run by ``fuzzynav study run``.  This module only runs such a
study, optionally writing its parameter file elsewhere (``--out``); the ``apso`` filter
reads that file (``--filter apso@studies/paper004_apso.json``).
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

from fuzzynav.errors import FuzzynavError


def main(argv=None) -> int:
    """Run the baseline study ``CONFIG``; exit code 2 with one line on a user error."""
    from fuzzynav.tuning.baselines import load_baseline_config, run_baselines

    ap = argparse.ArgumentParser(prog="python -m fuzzynav.tuning.apso", description=__doc__)
    ap.add_argument("config")
    ap.add_argument("--out", help="the parameter file (default: the config's [baselines] out)")
    args = ap.parse_args(argv)
    try:
        bcfg = load_baseline_config(args.config)
        if "apso" not in bcfg.tune:
            raise FuzzynavError(f"{args.config}: [baselines] tune has no \"apso\"")
        if args.out:
            bcfg = replace(bcfg, out=Path(args.out))
        path = run_baselines(bcfg)
    except FuzzynavError as exc:
        print(f"apso: error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
