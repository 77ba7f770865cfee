"""The ``[[controllers]]`` tables of a study file: which rule file is tuned, and how.

Keys (``docs/studies.md``): ``name``, ``template`` (a rule file), ``tune``, ``partitions``,
``free_triangles``, ``rule_weights``, ``window``, ``output_range``, ``output_low``,
``types``, ``parent`` (warm start, :mod:`fuzzynav.tuning.warm_start`).  Every problem is one :class:`fuzzynav.errors.InputFileError` naming the file
and key (:mod:`fuzzynav.tuning.study_config` reads the rest of the study file).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from fuzzynav.errors import InputFileError, brief
from fuzzynav.filters.adaptation.binding import WINDOW_RANGE
from fuzzynav.sim.tomltable import Table

__all__ = ["TUNE_MODES", "FIS_TYPES", "MAX_OUTPUT_FACTOR", "ControllerConfig", "user_file",
           "parse_controller"]

TUNE_MODES = ("both", "rules", "breakpoints")
FIS_TYPES = ("mamdani", "sugeno")
#: a tuned output scales a covariance or R: a positive factor, at most this
MAX_OUTPUT_FACTOR = 1e3
#: files a study may name are the user's own: never system places
_SYSTEM_DIRS = (Path("/etc"), Path("/proc"), Path("/sys"), Path("/dev"), Path("/boot"))


@dataclass(frozen=True)
class ControllerConfig:
    """How one rule file (controller) is tuned."""

    name: str
    template: Path
    tune: str = "both"
    partitions: dict = field(default_factory=dict)
    free_triangles: bool = False
    rule_weights: bool = False
    window: tuple | None = None
    output_range: tuple | None = None
    output_low: tuple | None = None
    types: tuple = ("mamdani",)
    #: warm start (:mod:`fuzzynav.tuning.warm_start`): ``(filter, params file,
    #: ((constant, value), ...))`` of the tuned parent, or None
    parent: tuple | None = None


def user_file(t: Table, key: str, path: Path, suffixes: tuple, what: str) -> Path:
    """Refuse a path that is not a ``suffixes`` file or that lies in a system directory."""
    real = path.resolve()
    if path.suffix.lower() not in suffixes:
        raise t.error(key, f"must be a {what} ({' or '.join(suffixes)}), got {brief(str(path))}")
    if any(real.is_relative_to(d) for d in _SYSTEM_DIRS):
        raise t.error(key, f"{brief(str(path))} is a system file, not a {what}")
    return path


def _pair(t: Table, key):
    if not t.has(key):
        t._used.add(key)
        return None
    lo, hi = t.vector(key, 2, broadcast=False)
    if not lo < hi:
        raise t.error(key, f"needs lo < hi, got [{lo}, {hi}]")
    return (lo, hi)


def _factor_pair(t: Table, key):
    """Bounds of a tuned output end: positive factors up to :data:`MAX_OUTPUT_FACTOR`."""
    pair = _pair(t, key)
    if pair is not None and not (pair[0] > 0.0 and pair[1] <= MAX_OUTPUT_FACTOR):
        raise t.error(key, f"must lie in (0, {MAX_OUTPUT_FACTOR:g}] (the output is a factor "
                           f"on a covariance), got {list(pair)}")
    return pair


def _window(t: Table):
    pair = _pair(t, "window")
    if pair is None:
        return None
    lo, hi = WINDOW_RANGE
    if not all(float(v).is_integer() and lo <= v <= hi for v in pair):
        raise t.error("window", f"must be two integer epoch counts in {lo}..{hi}, "
                                f"got {list(pair)}")
    return (int(pair[0]), int(pair[1]))


def _types(t: Table) -> tuple:
    """``types``: the fuzzy-system types a trial may choose (``.type`` when several)."""
    raw, _ = t._get("types", ["mamdani"])
    if isinstance(raw, str):
        raw = [raw]
    if not isinstance(raw, list) or not raw or not all(v in FIS_TYPES for v in raw):
        raise t.error("types", f"must be an array of {', '.join(FIS_TYPES)}, got {brief(raw)}")
    return tuple(dict.fromkeys(raw))


def _parent(t: Table, tmpl: Path, here: Path):
    """``parent``: the tuned classical filter a supervisor's study warm-starts from."""
    from fuzzynav.filters import adaptation
    from fuzzynav.fuzzy import load_fis
    from fuzzynav.tuning.warm_start import parse_parent

    if not t.has("parent"):
        return parse_parent(t, here, None)
    binding = load_fis(tmpl).binding or {}
    cls = adaptation.ADAPTERS.load().get(binding.get("adapter"))
    if cls is None:
        raise t.error("parent", f"the template {tmpl} names no adaptation policy to warm-start")
    return parse_parent(t, here, cls)


def parse_controller(t: Table, here: Path) -> ControllerConfig:
    name = t.string("name")
    tmpl = Path(t.string("template"))
    if not tmpl.is_absolute():
        tmpl = here / tmpl
    user_file(t, "template", tmpl, (".json", ".fis"), "rule file")
    if tmpl.is_dir():
        raise t.error("template", f"{tmpl} is a directory, not a rule file")
    if not tmpl.is_file():
        raise t.error("template", f"rule file not found: {tmpl}")
    parts = {}
    pt = t.table("partitions", required=False)
    if pt is not None:
        for var, counts in pt.data.items():
            pt._used.add(var)
            if isinstance(counts, int) and not isinstance(counts, bool):
                counts = [counts]
            if not isinstance(counts, list) or not counts or not all(
                    isinstance(c, int) and not isinstance(c, bool) and 1 <= c <= 9 for c in counts):
                raise pt.error(var, "must be a term count in 2..9 (or 1 on an input, "
                                    "which switches it off) or an array of them")
            parts[var] = tuple(sorted(set(counts)))
    c = ControllerConfig(name=name, template=tmpl,
                         tune=t.string("tune", "both", choices=TUNE_MODES),
                         partitions=parts,
                         free_triangles=t.boolean("free_triangles", False),
                         rule_weights=t.boolean("rule_weights", False),
                         window=_window(t),
                         output_range=_factor_pair(t, "output_range"),
                         output_low=_factor_pair(t, "output_low"),
                         types=_types(t),
                         parent=_parent(t, tmpl, here))
    t.finish()
    if c.output_low and c.output_range and not c.output_low[1] < c.output_range[0]:
        raise t.error("output_low", "must lie below output_range (the output's low end "
                                    "must stay under its high end)")
    from fuzzynav.tuning.space import check_against_template

    try:
        check_against_template(c)
        if c.parent is not None:  # the space must hold the parent (checked on its system)
            from fuzzynav.tuning.space import ControllerSpace
            from fuzzynav.tuning.warm_start import check_first_trial, first_trial

            space = ControllerSpace.from_config(c)
            check_first_trial(space, first_trial(space))
    except InputFileError as exc:
        if exc.path is not None:  # the template itself is broken: its own error says where
            raise
        raise t.error(exc.where, exc.what) from None
    return c
