"""Checks of command-line values and output places: one line naming the option, before any
work starts."""
from __future__ import annotations

import math

from fuzzynav.errors import FuzzynavError

__all__ = ["MAX_MC", "MAX_SEED", "check_count", "check_common", "check_t_start"]


def check_count(option: str, value, lo: int = 1, hi: int | None = None) -> None:
    """Refuse an integer option outside ``lo..hi`` (``None``: not given, accepted)."""
    if value is None:
        return
    if value < lo:
        raise FuzzynavError(f"{option} must be >= {lo}, got {value}")
    if hi is not None and value > hi:
        raise FuzzynavError(f"{option} must be <= {hi}, got {value}")


def check_t_start(value: float, duration_s: float, option: str = "--t-start") -> None:
    """Refuse a metrics start time that is not finite, negative, or not inside the run."""
    if not math.isfinite(value) or value < 0.0:
        raise FuzzynavError(f"{option} must be a finite number of seconds >= 0, got {value}")
    if value >= duration_s:
        raise FuzzynavError(f"{option} {value:g} s is at or after the end of the run "
                            f"({duration_s:g} s): no epoch would be scored")


#: most Monte-Carlo runs of one command: each keeps its metrics (and its seed list is built
#: up front), so a typo such as ``--mc 2000000000`` would end in an out-of-memory crash
MAX_MC = 100_000

#: largest seed: seeds go into int64 columns of the results table (numpy takes any >= 0)
MAX_SEED = 2**63 - 1


def check_common(args) -> None:
    """Refuse meaningless values of the options every run shares, and output directories
    that cannot be written, before any work."""
    from fuzzynav.fileio import check_output_dir

    for flag, what in (("plot", "figure directory (--plot)"),
                       ("output_dir", "chunk directory (--output-dir)")):
        if getattr(args, flag, None) is not None:
            check_output_dir(getattr(args, flag), what)
    check_count("--mc", args.mc)
    if args.mc > MAX_MC:
        raise FuzzynavError(f"--mc must be <= {MAX_MC} (each run is simulated and kept in "
                            f"memory; split a larger experiment), got {args.mc}")
    check_count("--seed", args.seed, lo=0)
    if args.seed + args.mc - 1 > MAX_SEED:
        raise FuzzynavError(f"--seed {args.seed} with --mc {args.mc}: the last seed must be "
                            f"<= {MAX_SEED} (a 64-bit integer)")
