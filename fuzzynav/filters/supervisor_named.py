"""Named filters of the fuzzy supervisors (:mod:`.adaptation.supervisors`).

``fuzzy-sage-husa``, ``fuzzy-vb`` and ``fuzzy-huber`` run the classical parent on every
sensor, with its constant set per epoch by a rule file on the sensors the rule file binds
(default: the template ``rules/supervisor_<parent>.json``; ``--rules FILE`` or
``NAME@FILE`` another; a study hands its candidates as the option ``systems``).  The
parent's other constants (``floor``, ``cap`` of Sage-Husa, ``iterations`` of VB) and the
constant used on the sensors no rule file binds (``b``, ``rho``, ``gamma``) come from the
rule file's ``binding.parent`` (a warm-started study writes its tuned parent's there), else
the parent's defaults; options of the same names override both.  The ``-tuned`` variants read
the rule file a supervisor study writes (``rules/supervisor_<parent>_tuned.json``).
"""
from __future__ import annotations

import math
from pathlib import Path

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters.adaptation.classical import Huber, SageHusa, VariationalBayes
from fuzzynav.filters.adaptation.supervisors import FuzzyHuber, FuzzySageHusa, FuzzyVB
from fuzzynav.filters.catalog import bind_rule_files, bind_systems
from fuzzynav.filters.named import FilterSetup, base_config, register_filter

__all__ = ["SUPERVISED", "supervised_setup"]


def _sage_husa(o):
    floor, cap = float(o.get("floor", 0.1)), float(o.get("cap", math.inf))
    b = float(o.get("b", 0.98))
    return (lambda: SageHusa(b, floor, cap)), dict(floor=floor, cap=cap, b_fallback=b)


def _vb(o):
    rho, it = float(o.get("rho", 0.98)), int(o.get("iterations", 3))
    return (lambda: VariationalBayes(rho, it)), dict(iterations=it, rho_fallback=rho)


def _huber(o):
    gamma = float(o.get("gamma", 1.345))
    return (lambda: Huber(gamma)), dict(gamma_fallback=gamma)


#: filter name -> (supervisor class, parent and supervisor constants from options, template)
SUPERVISED = {
    "fuzzy-sage-husa": (FuzzySageHusa, _sage_husa, "supervisor_sage_husa.json"),
    "fuzzy-vb": (FuzzyVB, _vb, "supervisor_vb.json"),
    "fuzzy-huber": (FuzzyHuber, _huber, "supervisor_huber.json"),
}


def supervised_setup(ctx, name: str, default_rules: str) -> FilterSetup:
    """The parent on every sensor, supervised on those the rule files bind; the parent's
    constants from the rule files' ``binding.parent`` (the tuned parent they were tuned
    around), options overriding them."""
    cls, constants, _ = SUPERVISED[name]
    if ctx.options.get("systems"):  # a study's candidates: (fuzzy system, source) pairs
        bound = bind_systems(ctx.options["systems"], ctx.sensors, required=True)
    else:
        given = ctx.options.get("rules") or [default_rules]
        given = [given] if isinstance(given, (str, Path)) else list(given)
        bound = bind_rule_files(given, ctx.sensors, required=True)
    for p in bound.values():
        if not isinstance(p, cls):
            raise FuzzynavError(f"{p.source}: {name} needs rule files bound to adapter "
                                f"{cls.name!r}; this one is bound to {p.name!r}")
    parent, kwargs = constants({**_parent_of(bound), **ctx.options})
    adapters = {nm: parent() for nm in ctx.sensors}
    for nm, p in bound.items():
        adapters[nm] = cls(p.fis, p.source, p.binding, **kwargs)
    return FilterSetup(base_config(ctx), adapters)


def _parent_of(bound: dict) -> dict:
    """The parent constants the bound rule files carry (one set: they must agree)."""
    sets = {p.binding.parent: p.source for p in bound.values() if p.binding.parent}
    if len(sets) > 1:
        raise FuzzynavError("rule files tuned around different parent constants run one "
                            "filter: " + "; ".join(f"{src}: {dict(c)}" for c, src in sets.items()))
    return dict(next(iter(sets), ()))


def _register(name: str, template: str) -> None:
    parent = name.removeprefix("fuzzy-")
    tuned = template.replace(".json", "_tuned.json")
    register_filter(name, f"{parent} whose constant a fuzzy supervisor sets per epoch "
                          f"(default rules {template})", takes_rules=True)(
        lambda ctx: supervised_setup(ctx, name, template))
    register_filter(f"{name}-tuned", f"{name} with the rules its study tuned ({tuned})",
                    takes_rules=True)(lambda ctx: supervised_setup(ctx, name, tuned))


for _name, (_cls, _constants, _template) in SUPERVISED.items():
    _register(_name, _template)
