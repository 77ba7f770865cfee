"""Search ranges of a baseline study: the defaults, and a study file's own.

A baseline study searches each tuned filter's parameters over the ranges of
:data:`fuzzynav.tuning.baseline_config.SPACES` (``ekf-tuned``: ``Q_BOUNDS`` and ``R_BOUNDS``).
A study file may set other ranges, keeping each parameter's scale (log, linear, integer)::

    [baselines.ranges]
    apso = { q_att = [1e-4, 100], r_all = [1e-3, 100] }

Both ends are checked as the tuned-parameter reader checks a value
(:mod:`fuzzynav.filters.params_file`), so a study never writes a file the filters refuse;
a log-scaled range must be positive, an integer one whole.  The ranges searched are written
into the parameter file (``space``), so that a value at the end of its range is judged
against what was searched (:func:`fuzzynav.tuning.baseline_config.bound_hits`).
"""
from __future__ import annotations

import math

from fuzzynav.errors import InputFileError, brief
from fuzzynav.filters.params_file import known_keys

__all__ = ["parse_ranges", "with_ranges", "recorded"]


def _pair(value, t, key: str) -> tuple:
    ok = isinstance(value, list) and len(value) == 2 and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
        for v in value)
    if not ok:
        raise t.error(key, f"must be [low, high], two finite numbers, got {brief(value)}")
    lo, hi = float(value[0]), float(value[1])
    if not lo < hi:
        raise t.error(key, f"low must be below high, got [{lo:g}, {hi:g}]")
    return lo, hi


def _checked(name: str, key: str, pair: tuple, default: tuple, t) -> tuple:
    """``pair`` as ``(lo, hi, scale)`` with ``default``'s scale, every end checked."""
    scale = default[2]
    param = known_keys(name)[key]
    for end, v in zip(("low", "high"), pair):
        try:
            param.check(v, None, "")
        except InputFileError:
            raise t.error(key, f"{end} end must be {param.describe()} (what the filter "
                               f"reads), got {v:g}") from None
    if scale is True and pair[0] <= 0.0:  # every log-scaled parameter reads > 0 today
        raise t.error(key, f"is searched on a log scale: low must be > 0, got {pair[0]:g}")
    if scale == "int":  # whole numbers: the reader's check said so
        return int(pair[0]), int(pair[1]), scale
    return pair[0], pair[1], scale


def parse_ranges(table, defaults) -> dict:
    """``filter -> {key: (lo, hi)}`` of a ``[baselines.ranges]`` table (``None``: none).

    ``defaults(name)``: the filter's default space, key -> ``(lo, hi, scale)``, every key
    it may search (for ``ekf-tuned`` an ``r_<channel>`` of every known channel).
    """
    if table is None:
        return {}
    out = {}
    for name in list(table.data):
        sub = table.table(name)
        space = defaults(name)
        if space is None:
            raise table.error(name, "not a searched filter of this study's [baselines] tune")
        for key in list(sub.data):
            if key not in space:
                raise sub.error(key, f"not a searched parameter of {name} (searched: "
                                     f"{', '.join(space)})")
            sub._used.add(key)
            out.setdefault(name, {})[key] = _checked(name, key, _pair(sub.data[key], sub, key),
                                                     space[key], sub)[:2]
        sub.finish()
    return out


def with_ranges(space: dict, ranges: dict, where: str) -> dict:
    """``space`` (key -> ``(lo, hi, scale)``) with the study file's ``ranges`` (key ->
    ``(lo, hi)``) put in, keeping each scale; a range for a key the space lacks (a channel
    the training runs do not have) is refused, naming ``where``."""
    out = dict(space)
    for key, (lo, hi) in ranges.items():
        if key not in out:
            raise InputFileError(None, f"{where}.{key}",
                                 f"the training runs have no such parameter (searched: "
                                 f"{', '.join(space)})")
        out[key] = (lo, hi, out[key][2])
    return out


def recorded(doc: dict, name: str, default: dict) -> dict:
    """The space a parameter file says filter ``name`` was searched over (its ``space``),
    the scales taken from ``default``; ``default`` for a file that does not say."""
    given = (doc.get("space") or {}).get(name)
    if not isinstance(given, dict):
        return default
    return {**default, **{k: (float(v[0]), float(v[1]), default[k][2]) for k, v in given.items()
                          if k in default and isinstance(v, list) and len(v) == 2}}
