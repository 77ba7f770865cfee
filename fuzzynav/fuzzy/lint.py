"""Advisory checks of a valid FuzzySystem (``fuzzynav fis check`` prints them).

These are not errors -- a tuned system may legitimately have unused terms -- but they
usually point at a typo or a gap: a term no rule uses, an output no rule drives, part of
an input range where no term is active (no rule can fire there), an output term outside
its range, two rules with the same conditions and different conclusions.
"""
from __future__ import annotations

import numpy as np

from fuzzynav.fuzzy.membership import evaluate_mf

__all__ = ["advisories"]

_GRID = 2001


def _unused_terms(fis) -> list[str]:
    used = {(a.variable, a.term) for r in fis.rules for a in r.antecedents}
    used |= {c for r in fis.rules for c in r.consequents}
    return [f"term {v.name}.{t.name} is used by no rule"
            for v in fis.inputs + fis.outputs for t in v.terms if (v.name, t.name) not in used]


def _undriven_outputs(fis) -> list[str]:
    driven = {o for r in fis.rules for o, _ in r.consequents}
    return [f"output {v.name} is driven by no rule (always {v.default_value!r})"
            for v in fis.outputs if v.name not in driven]


def _gaps(fis) -> list[str]:
    out = []
    for v in fis.inputs:
        x = np.linspace(v.range[0], v.range[1], _GRID)
        mu = np.max([evaluate_mf(t.mf, t.params, x) for t in v.terms], axis=0)
        dead = mu <= 0.0
        if dead.any():
            idx = np.flatnonzero(dead)
            out.append(f"input {v.name}: no term is active on part of its range "
                       f"(e.g. near {x[idx[0]]:.6g}); rules that need it cannot fire there")
    return out


def _outside(fis) -> list[str]:
    out = []
    if fis.type != "mamdani":
        return out
    for v in fis.outputs:
        x = np.linspace(v.range[0], v.range[1], _GRID)
        for t in v.terms:
            if t.kind == "pwl" and np.max(evaluate_mf(t.mf, t.params, x)) <= 0.0:
                out.append(f"output term {v.name}.{t.name} lies outside the range "
                           f"{list(v.range)}")
    return out


def _conflicts(fis) -> list[str]:
    seen, out = {}, []
    for i, r in enumerate(fis.rules):
        key = (r.connective, tuple(sorted((a.variable, a.term, a.negated)
                                          for a in r.antecedents)))
        if key in seen and dict(fis.rules[seen[key]].consequents) != dict(r.consequents):
            out.append(f"rules {seen[key]} and {i} have the same conditions but different "
                       f"conclusions")
        seen.setdefault(key, i)
    return out


def advisories(fis) -> list[str]:
    """Human-readable advisory messages for ``fis`` (empty when nothing looks odd)."""
    return (_unused_terms(fis) + _undriven_outputs(fis) + _gaps(fis) + _outside(fis)
            + _conflicts(fis))
