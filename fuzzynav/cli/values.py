"""Checks of command-line values: one line naming the option, before any work starts."""
from __future__ import annotations

import math

from fuzzynav.errors import FuzzynavError

__all__ = ["check_count", "check_t_start"]


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
