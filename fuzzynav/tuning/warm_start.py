"""Warm start of a fuzzy-supervisor study: the search begins where the tuned parent ends.

A ``[[controllers]]`` table with ``parent = "sage-husa-tuned@paper000_baselines.json"``
(``NAME@FILE``, the file relative to the study file or found like any tuned-parameter file;
without ``@FILE`` the default one) does two things:

* every candidate of the study carries the parent's tuned constants in its
  ``binding.parent`` (``b``, ``floor``, ``cap`` of Sage-Husa; ``rho``, ``iterations`` of VB;
  ``gamma`` of Huber), so every trial supervises the tuned parent, not the parent's
  defaults, and the exported rule file runs as it was scored;
* a new study's first trial is enqueued at the point of the search space where the
  controller outputs the parent's constant at every epoch (:func:`first_trial`): a
  zero-order Sugeno system, every consequent the output term whose constant is the
  parent's value (the output's low end ``out_lo`` or high end ``out_hi`` set to it).  That
  trial scores what the tuned parent scores (to rounding: a weighted average of equal
  constants), so the study's best can only match or improve it on the training runs.

The space must contain that point, and the study file is refused otherwise, naming the key:
``types`` must include ``"sugeno"`` (a Mamdani output's centroid is not its term's peak),
``tune`` must search the rules (not ``"breakpoints"``), the template has one output, and the
parent's value lies in ``output_low`` or ``output_range`` (or is the template's end).
:func:`check_first_trial` builds that trial's system and checks its output is the constant
on a grid of every input's range.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from fuzzynav.errors import FuzzynavError, InputFileError

__all__ = ["parse_parent", "with_parent_file", "first_trial", "check_first_trial",
           "PartialTrial"]


def _constants(t, name: str, file: str, here: Path) -> tuple:
    from fuzzynav.filters.baselines import read_params

    path = here / file if (here / file).is_file() else file
    try:
        doc = read_params(path)
    except FuzzynavError as exc:  # missing, unreadable or invalid: one error at the key
        raise t.error("parent", str(exc)) from None
    if name not in doc["filters"]:
        raise t.error("parent", f"{doc['path']} tunes no {name!r} (it tunes "
                                f"{', '.join(doc['filters']) or 'nothing'})")
    return tuple(doc["filters"][name].items()), str(doc["path"])


def parse_parent(t, here: Path, adapter_class) -> tuple:
    """``parent``: ``(name, params file, ((constant, value), ...))`` or None.

    ``adapter_class`` is the template's adaptation policy: its ``parent`` must be the named
    filter (the supervisor of Sage-Husa warm-starts from ``sage-husa-tuned``)."""
    from fuzzynav.filters.baselines import DEFAULT_PARAMS

    if not t.has("parent"):
        t._used.add("parent")
        return None
    spec = t.string("parent")
    name, _, file = spec.partition("@")
    want = getattr(adapter_class, "parent", None)
    if want is None:
        raise t.error("parent", f"the template's adapter {adapter_class.name!r} is no fuzzy "
                                "supervisor: a warm start needs a classical parent")
    if name != want:
        raise t.error("parent", f"the template supervises {want!r}, not {name!r}")
    constants, path = _constants(t, name, file or DEFAULT_PARAMS, here)
    return (name, path, constants)


def with_parent_file(cfg, path):
    """The study ``cfg`` with every warm-started controller's parent constants read from
    the tuned-parameter file ``path`` (e.g. one tuning seed's baselines)."""
    from fuzzynav.sim.tomltable import Table

    ctrls = []
    for cc in cfg.controllers:
        if cc.parent is not None:
            t = Table({}, f"controllers.{cc.name}")
            constants, p = _constants(t, cc.parent[0], str(path), Path.cwd())
            cc = replace(cc, parent=(cc.parent[0], p, constants))
        ctrls.append(cc)
    return replace(cfg, controllers=tuple(ctrls))


class PartialTrial:
    """A trial answering from ``params`` and, for anything else, the low end of the range
    (the first choice): builds the system of an enqueued, partly fixed trial."""

    def __init__(self, params: dict):
        self.params = dict(params)

    def suggest_categorical(self, name, choices):
        return self.params.get(name, choices[0])

    def suggest_float(self, name, low, high, **_):
        return self.params.get(name, low)

    def suggest_int(self, name, low, high, **_):
        return self.params.get(name, low)


def _counts(space) -> dict:
    """Each variable's partition count in the warm trial: the configured first (smallest)."""
    t, cc = space.template, space.config
    return {v.name: cc.partitions.get(v.name, (len(v.terms),))[0] for v in t.inputs + t.outputs}


def first_trial(space) -> dict:
    """The parameters that make controller ``space`` output its parent's constant at every
    epoch (see the module docstring); :class:`~fuzzynav.errors.InputFileError` (no file,
    the key) when the search space does not contain that point."""
    import itertools

    cc, tmpl = space.config, space.template
    role = space.binding.outputs[0].target
    value = dict(cc.parent[2])[role]
    if "sugeno" not in cc.types:
        raise InputFileError(None, "types", "a warm start needs 'sugeno' among the types (a "
                             "Mamdani output's centroid is not the parent's constant)")
    if cc.tune == "breakpoints":
        raise InputFileError(None, "tune", "a warm start searches the rules: 'both' or "
                                           "'rules', not 'breakpoints'")
    if len(tmpl.outputs) != 1:
        raise InputFileError(None, "parent", "a warm start needs a template with one output")
    lo, hi = tmpl.outputs[0].range
    p = {f"{cc.name}.type": "sugeno"}
    if cc.output_low is not None and cc.output_low[0] <= value <= cc.output_low[1]:
        p[f"{cc.name}.out_lo"], k = value, 0
    elif cc.output_range is not None and cc.output_range[0] <= value <= cc.output_range[1]:
        p[f"{cc.name}.out_hi"], k = value, -1
    elif cc.output_low is None and value == lo:
        k = 0
    elif cc.output_range is None and value == hi:
        k = -1
    else:
        raise InputFileError(None, "output_low", f"the parent's {role} = {value:g} lies outside "
                             f"output_low {list(cc.output_low or ())} and output_range "
                             f"{list(cc.output_range or ())}: widen one to contain it")
    counts = _counts(space)
    for v in tmpl.inputs + tmpl.outputs:
        if len(cc.partitions.get(v.name, ())) > 1:
            p[f"{cc.name}.n.{v.name}"] = counts[v.name]
    n_out = counts[tmpl.outputs[0].name]
    cells = "x".join(str(counts[v.name]) for v in tmpl.inputs)
    for cell in itertools.product(*[range(counts[v.name]) for v in tmpl.inputs]):
        key = ".".join(map(str, cell))
        p[f"{cc.name}.rule.{cells}>{n_out}.{key}"] = k % n_out
    return p


def check_first_trial(space, params: dict, n_grid: int = 7) -> float:
    """Build the warm trial's system and check it outputs the parent's constant on a grid
    of every input's range; returns the largest deviation.  Raises
    :class:`~fuzzynav.errors.FuzzynavError` if it does not (a search-space change broke it)."""
    fis = space.build(PartialTrial(params))
    role = space.binding.outputs[0].target
    value = dict(space.config.parent[2])[role]
    axes = [np.linspace(*v.range, n_grid) for v in fis.inputs]
    grid = np.meshgrid(*axes, indexing="ij")
    y = fis.evaluate({v.name: g.ravel() for v, g in zip(fis.inputs, grid)})
    y = np.asarray(y[fis.outputs[0].name] if isinstance(y, dict) else y, dtype=float)
    dev = float(np.max(np.abs(y - value)))
    if not dev <= 1e-12 * max(1.0, abs(value)):
        raise FuzzynavError(f"controller {space.config.name!r}: the warm start's first trial "
                            f"outputs up to {dev:g} away from the parent's {role} = {value:g}")
    return dev
