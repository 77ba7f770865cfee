"""MATLAB ``evalfis`` emulation: Mamdani output sets sampled on ``n_points`` points.

Reproduces the Fuzzy Logic Toolbox's sampled defuzzification on
``linspace(lo, hi, n_points)`` (``NumSamplePoints``, default 101):

* centroid: ``sum(mu * x) / sum(mu)``;
* bisector: the first grid point at which the running sum of ``mu`` reaches half of
  its total (MATLAB's ``defuzz``);
* mom: mean of the grid points where ``mu`` equals its maximum; som / lom: the smallest /
  largest of them (current MATLAB documentation; very old releases chose by magnitude).

Use it to compare with published ``.fis`` results; the exact mode is the reference.
Inputs are clamped, and empty sets take the default, as in the exact mode (MATLAB would
warn and return the range midpoint).  Sugeno and singleton outputs are not sampled.
"""
from __future__ import annotations

import numpy as np

from fuzzynav.fuzzy.inference import (clamp, consequents, finish_outputs,
                                      firing_strengths, output_values)
from fuzzynav.fuzzy.membership import evaluate_mf

__all__ = ["sampled_aggregate", "sampled_defuzz", "sampled_evaluate"]

_CHUNK = 8192


def sampled_aggregate(fis, o: int, W: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Aggregated output set of output ``o`` on ``grid`` for every row of W: (n, grid)."""
    v = fis.outputs[o]
    ops = fis.operators
    mf = np.array([evaluate_mf(t.mf, t.params, grid) for t in v.terms])
    agg = np.zeros((len(W), len(grid)))
    for r, k in consequents(fis, o):
        w = W[:, r, None]
        imp = np.minimum(w, mf[k]) if ops.implication == "min" else w * mf[k]
        if ops.aggregation == "max":
            np.maximum(agg, imp, out=agg)
        elif ops.aggregation == "sum":
            agg += imp
        else:
            agg = agg + imp - agg * imp
    return agg


def sampled_defuzz(grid: np.ndarray, mu: np.ndarray, method: str) -> np.ndarray:
    """MATLAB-style defuzzification of sampled sets ``mu`` (n, grid); nan when empty."""
    total = mu.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        if method == "centroid":
            out = (mu @ grid) / total
        elif method == "bisector":
            reach = np.cumsum(mu, axis=1) >= 0.5 * total[:, None]
            out = grid[np.argmax(reach, axis=1)]
        else:
            at = mu == mu.max(axis=1, keepdims=True)
            if method == "mom":
                out = (at @ grid) / at.sum(axis=1)
            elif method == "som":
                out = grid[np.argmax(at, axis=1)]
            else:
                out = grid[len(grid) - 1 - np.argmax(at[:, ::-1], axis=1)]
    return np.where(total > 0.0, out, np.nan)


def _per_output(n_points):
    def run(fis, o, W):
        v = fis.outputs[o]
        grid = np.linspace(v.range[0], v.range[1], n_points)
        out = np.empty(len(W))
        for s in range(0, len(W), _CHUNK):
            mu = sampled_aggregate(fis, o, W[s:s + _CHUNK], grid)
            out[s:s + _CHUNK] = sampled_defuzz(grid, mu, fis.operators.defuzzifier)
        return out

    return run


def sampled_evaluate(fis, X: np.ndarray, n_points: int = 101):
    """Sampled-mode evaluation of rows of X: (Y, status)."""
    Xc, status = clamp(fis, X)
    W = firing_strengths(fis, Xc)
    return finish_outputs(fis, output_values(fis, W, Xc, _per_output(n_points)), status)
