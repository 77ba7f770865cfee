"""Export a FuzzySystem to a scikit-fuzzy ``ControlSystem`` (the cross-check library).

scikit-fuzzy samples every variable on a universe (``n_points`` points over the range),
clips (min) implied sets and aggregates them with max; rule weights become weighted
consequents (``term % weight``).  Systems it cannot represent are refused with a clear
error: Sugeno systems, prod implication, sum/probor aggregation, singleton terms.
Its edge behaviour differs from fuzzynav's: when no rule fires it raises or leaves the
output out instead of returning the default.
"""
from __future__ import annotations

import numpy as np

from fuzzynav.fuzzy._where import FisError
from fuzzynav.fuzzy.membership import evaluate_mf

__all__ = ["to_skfuzzy"]


def _refuse(where: str, what: str):
    raise FisError(None, where, f"scikit-fuzzy export: {what}")


def _check(fis) -> None:
    ops = fis.operators
    if fis.type != "mamdani":
        _refuse("type", "scikit-fuzzy's ControlSystem is Mamdani only")
    if ops.implication != "min":
        _refuse("operators.implication", "scikit-fuzzy clips (min implication) only")
    if ops.aggregation != "max":
        _refuse("operators.aggregation", "scikit-fuzzy aggregates with max only")
    for v in fis.inputs + fis.outputs:
        for t in v.terms:
            if t.mf == "singleton":
                _refuse(f"{v.name}.{t.name}", "singleton terms cannot be sampled")


def _probor(a, b):
    return a + b - a * b


def to_skfuzzy(fis, n_points: int = 1001):
    """Build a ``skfuzzy.control.ControlSystem`` equivalent to ``fis``.

    Parameters
    ----------
    fis : FuzzySystem
        Mamdani system with min implication and max aggregation.
    n_points : int
        Points of each variable's universe (``linspace(lo, hi, n_points)``).

    Returns
    -------
    skfuzzy.control.ControlSystem
        Its antecedents and consequents carry the fuzzynav variable names as labels.
    """
    from skfuzzy import control as ctrl

    _check(fis)
    ops = fis.operators
    variables = {}
    for v in fis.inputs + fis.outputs:
        universe = np.linspace(v.range[0], v.range[1], n_points)
        if v in fis.outputs:
            var = ctrl.Consequent(universe, v.name, defuzzify_method=ops.defuzzifier)
        else:
            var = ctrl.Antecedent(universe, v.name)
        for t in v.terms:
            var[t.name] = evaluate_mf(t.mf, t.params, universe)
        variables[v.name] = var
    rules = []
    for r in fis.rules:
        expr = None
        for a in r.antecedents:
            term = variables[a.variable][a.term]
            term = ~term if a.negated else term
            if expr is None:
                expr = term
            else:
                expr = (expr & term) if r.connective == "and" else (expr | term)
        cons = [variables[o][t] % r.weight for o, t in r.consequents]
        rules.append(ctrl.Rule(expr, cons, and_func=np.fmin if ops.and_ == "min" else
                               np.multiply, or_func=np.fmax if ops.or_ == "max" else _probor))
    return ctrl.ControlSystem(rules)
