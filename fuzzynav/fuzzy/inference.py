"""Batch evaluation of a FuzzySystem: exact (compiled or Python) and MATLAB-sampled modes.

Behaviour shared by every mode and engine (users rely on it):

* inputs outside their range are clamped to it and counted (``EvalInfo.n_clamped``);
  nothing is printed;
* an output whose aggregated set is empty (no rule fired, or zero area) takes its
  ``default`` (else its range midpoint) and is counted (``EvalInfo.n_no_rule``);
* a NaN input makes every output of that sample NaN (``EvalInfo.n_nan``), other samples
  are unaffected.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.fuzzy.defuzz import Implied, pwl_defuzz, singleton_defuzz
from fuzzynav.fuzzy.compiled_layout import CLAMPED, NAN_INPUT, NO_RULE
from fuzzynav.fuzzy.membership import evaluate_mf
from fuzzynav.fuzzy.quadrature import curved_defuzz

__all__ = ["EvalInfo", "clamp", "firing_strengths", "consequents", "sugeno_output", "term_levels",
           "output_values", "finish_outputs", "python_exact"]

@dataclass(frozen=True)
class EvalInfo:
    """What happened during one ``evaluate`` call.

    Attributes
    ----------
    n_samples : int
    n_clamped : int
        Samples with at least one input clamped to its range.
    n_no_rule : int
        Samples with at least one output holding its default (empty output set).
    n_nan : int
        Samples with a NaN input (their outputs are NaN).
    status : numpy.ndarray
        int64 bitmask per sample (broadcast shape): 1 clamped, 2 no rule, 4 NaN input.
    """

    n_samples: int
    n_clamped: int
    n_no_rule: int
    n_nan: int
    status: np.ndarray


def clamp(fis, X: np.ndarray):
    """Clamp rows of X to the input ranges; return (clamped X, status bits)."""
    lo = np.array([v.range[0] for v in fis.inputs])
    hi = np.array([v.range[1] for v in fis.inputs])
    nan = np.isnan(X).any(axis=1)
    Xc = np.clip(X, lo, hi)
    status = np.where(((X < lo) | (X > hi)).any(axis=1), CLAMPED, 0)
    status = np.where(nan, NAN_INPUT, status).astype(np.int64)
    Xc[nan] = np.where(np.isnan(Xc[nan]), lo, Xc[nan])
    return Xc, status


def firing_strengths(fis, Xc: np.ndarray) -> np.ndarray:
    """Firing strength (weight included) of every rule for every row: shape (n, rules)."""
    mu = {}
    for i, v in enumerate(fis.inputs):
        for t in v.terms:
            mu[(v.name, t.name)] = evaluate_mf(t.mf, t.params, Xc[:, i])
    ops = fis.operators
    W = np.empty((Xc.shape[0], len(fis.rules)))
    for r, rule in enumerate(fis.rules):
        vals = [1.0 - mu[(a.variable, a.term)] if a.negated else mu[(a.variable, a.term)]
                for a in rule.antecedents]
        acc = vals[0]
        for v in vals[1:]:
            if rule.connective == "and":
                acc = np.minimum(acc, v) if ops.and_ == "min" else acc * v
            else:
                acc = np.maximum(acc, v) if ops.or_ == "max" else acc + v - acc * v
        W[:, r] = acc * rule.weight
    return W


def consequents(fis, o: int):
    """(rule index, term index) pairs of the rules that drive output ``o``."""
    v = fis.outputs[o]
    return [(r, v.term_index(term)) for r, rule in enumerate(fis.rules)
            for out, term in rule.consequents if out == v.name]


def sugeno_output(fis, o: int, W: np.ndarray, Xc: np.ndarray) -> np.ndarray:
    """Sugeno output ``o`` for every row (nan where no rule fired)."""
    v = fis.outputs[o]
    num = np.zeros(len(W))
    den = np.zeros(len(W))
    for r, k in consequents(fis, o):
        p = v.terms[k].params
        z = p[0] if v.terms[k].mf == "constant" else Xc @ np.asarray(p[:-1]) + p[-1]
        num += W[:, r] * z
        den += W[:, r]
    with np.errstate(invalid="ignore", divide="ignore"):
        out = num if fis.operators.defuzzifier == "wtsum" else num / den
    return np.where(den > 0.0, out, np.nan)


def term_levels(fis, o: int, W: np.ndarray) -> np.ndarray:
    """Firing strengths aggregated per output term (for singleton outputs): (n, terms)."""
    agg = fis.operators.aggregation
    lev = np.zeros((len(W), len(fis.outputs[o].terms)))
    for r, k in consequents(fis, o):
        w = W[:, r]
        a = lev[:, k]
        lev[:, k] = np.maximum(a, w) if agg == "max" else a + w if agg == "sum" else \
            a + w - a * w
    return lev


def _singleton_output(fis, o, W):
    v = fis.outputs[o]
    pos = [t.params[0] for t in v.terms]
    lev = term_levels(fis, o, W)
    return np.array([singleton_defuzz(pos, row, fis.operators.defuzzifier) for row in lev])


def _exact_mamdani_output(fis, o, W):
    v = fis.outputs[o]
    ops = fis.operators
    cons = consequents(fis, o)
    curved = any(t.kind == "curved" for t in v.terms)
    fn = curved_defuzz if curved else pwl_defuzz
    out = np.empty(len(W))
    for s in range(len(W)):
        sets = [Implied(v.terms[k].mf, v.terms[k].params, W[s, r], ops.implication)
                for r, k in cons]
        out[s] = fn(sets, v.range[0], v.range[1], ops.aggregation, ops.defuzzifier)
    return out


def output_values(fis, W, Xc, per_output):
    """Evaluate every output with ``per_output(fis, o, W)`` for Mamdani set outputs."""
    Y = np.empty((len(W), len(fis.outputs)))
    for o, v in enumerate(fis.outputs):
        if fis.type == "sugeno":
            Y[:, o] = sugeno_output(fis, o, W, Xc)
        elif v.terms[0].mf == "singleton":
            Y[:, o] = _singleton_output(fis, o, W)
        else:
            Y[:, o] = per_output(fis, o, W)
    return Y


def finish_outputs(fis, Y, status):
    """Empty output sets take their defaults, NaN inputs give NaN outputs: (Y, status)."""
    empty = np.isnan(Y) & ~(status[:, None] & NAN_INPUT).astype(bool)
    defaults = np.array([v.default_value for v in fis.outputs])
    Y = np.where(empty, defaults, Y)
    status = status | np.where(empty.any(axis=1), NO_RULE, 0)
    Y[(status & NAN_INPUT).astype(bool)] = np.nan
    return Y, status


def python_exact(fis, X: np.ndarray):
    """Exact evaluation through the pure-Python reference path: (Y, status)."""
    Xc, status = clamp(fis, X)
    W = firing_strengths(fis, Xc)
    return finish_outputs(fis, output_values(fis, W, Xc, _exact_mamdani_output), status)
