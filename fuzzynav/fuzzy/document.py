"""The ``fuzzynav-fis`` version-1 document of a fuzzy system (system -> dict).

Kept apart from :mod:`fuzzynav.fuzzy.io` (which parses documents into systems) so that
:meth:`FuzzySystem.to_dict <fuzzynav.fuzzy.system.FuzzySystem.to_dict>` needs no import of
the loader: the writer reads only the systems' attributes.
"""
from __future__ import annotations

import json

__all__ = ["FORMAT", "VERSION", "OPTIONAL_OBJECTS", "to_dict"]

FORMAT = "fuzzynav-fis"
VERSION = 1
#: optional top-level objects, carried verbatim (the engine does not interpret them)
OPTIONAL_OBJECTS = ("binding", "provenance", "expected")


def _var_dict(v, output: bool) -> dict:
    d = {"name": v.name, "range": list(v.range)}
    if output and v.default is not None:
        d["default"] = v.default
    d["terms"] = [{"name": t.name, "mf": t.mf, "params": list(t.params)} for t in v.terms]
    return d


def _rule_dict(r) -> dict:
    cond = {a.variable: ({"not": a.term} if a.negated else a.term) for a in r.antecedents}
    d = {"if": cond, "then": dict(r.consequents), "weight": r.weight}
    if r.connective != "and":
        d["connective"] = r.connective
    return d


def to_dict(fis) -> dict:
    """The canonical ``fuzzynav-fis`` version-1 document of ``fis``."""
    d = {"format": FORMAT, "version": VERSION, "name": fis.name, "type": fis.type,
         "operators": fis.operators.as_dict(),
         "inputs": [_var_dict(v, False) for v in fis.inputs],
         "outputs": [_var_dict(v, True) for v in fis.outputs],
         "rules": [_rule_dict(r) for r in fis.rules]}
    for key in OPTIONAL_OBJECTS:
        value = getattr(fis, key)
        if value is not None:
            d[key] = json.loads(json.dumps(value))
    return d
