"""Batch evaluation front end: input checking and the choice of mode and engine.

The behaviour shared by every mode is described in :mod:`fuzzynav.fuzzy.inference`; the
modes themselves live in :mod:`.inference` (exact, Python), :mod:`.compiled` (exact, numba)
and :mod:`.sampled` (MATLAB emulation).  This module sits above all of them, so none of
them needs to import another to dispatch.
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from fuzzynav.fuzzy._where import FisEvaluationError
from fuzzynav.fuzzy.inference import EvalInfo, python_exact
from fuzzynav.fuzzy.compiled_layout import CLAMPED, NAN_INPUT, NO_RULE
from fuzzynav.fuzzy.sampled import sampled_evaluate

__all__ = ["evaluate"]

#: batches at least this long use the parallel compiled kernel
_PARALLEL_MIN = 20000


def _prepare(fis, inputs):
    if not isinstance(inputs, Mapping):
        raise FisEvaluationError(f"inputs must be a mapping name -> value, got "
                                 f"{type(inputs).__name__}")
    names = fis.input_names
    missing = [n for n in names if n not in inputs]
    unknown = [n for n in inputs if n not in names]
    if missing or unknown:
        raise FisEvaluationError(f"system {fis.name!r} takes inputs {', '.join(names)}; "
                                 f"missing: {missing}, unknown: {unknown}")
    try:
        arrays = [np.asarray(inputs[n], dtype=float) for n in names]
    except (TypeError, ValueError) as exc:
        raise FisEvaluationError(f"inputs must be numbers or arrays of numbers: {exc}") \
            from None
    try:
        arrays = np.broadcast_arrays(*arrays)
    except ValueError as exc:
        raise FisEvaluationError(f"inputs do not broadcast together: {exc}") from None
    shape = arrays[0].shape
    X = np.stack([a.ravel() for a in arrays], axis=1) if arrays[0].size else \
        np.empty((0, len(names)))
    return np.ascontiguousarray(X), shape


def evaluate(fis, inputs, *, mode="exact", n_points=101, return_info=False, engine="auto"):
    """Implementation of :meth:`FuzzySystem.evaluate` (see there)."""
    X, shape = _prepare(fis, inputs)
    if mode == "exact":
        if engine not in ("auto", "compiled", "python"):
            raise FisEvaluationError(f"engine must be 'auto', 'compiled' or 'python', got "
                                     f"{engine!r}")
        compiled = engine == "compiled" or (engine == "auto" and fis.is_compilable)
        if compiled:
            Y, status = fis.compile().evaluate(X, parallel=len(X) >= _PARALLEL_MIN)
        else:
            Y, status = python_exact(fis, X)
    elif mode == "sampled":
        if isinstance(n_points, bool) or not isinstance(n_points, int) or n_points < 2:
            raise FisEvaluationError(f"n_points must be an integer >= 2, got {n_points!r}")
        Y, status = sampled_evaluate(fis, X, n_points)
    else:
        raise FisEvaluationError(f"mode must be 'exact' or 'sampled', got {mode!r}")
    out = {}
    for o, name in enumerate(fis.output_names):
        col = Y[:, o].reshape(shape)
        out[name] = float(col) if shape == () else col
    if not return_info:
        return out
    info = EvalInfo(n_samples=len(X), n_clamped=int(np.count_nonzero(status & CLAMPED)),
                    n_no_rule=int(np.count_nonzero(status & NO_RULE)),
                    n_nan=int(np.count_nonzero(status & NAN_INPUT)),
                    status=status.reshape(shape))
    return out, info
