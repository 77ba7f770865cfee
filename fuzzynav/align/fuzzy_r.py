"""Paper 002's fuzzy R-scaling: ``R(k) = t(k) R(k-1)``, ``t = FIS(ROR)``.

``ROR(k) = tr(C_r) / tr(D_r)``: the measured innovation covariance over the last ``M``
epochs, ``C_r = (1/M) sum r_i r_i^T``, against the theoretical one of this epoch,
``D_r = H P- H^T + R(k-1)``.  ROR near 1: the filter is consistent, keep R; above 1: the
innovations are larger than the filter expects, raise R; below 1: lower it.  Until the
window is full, t = 1.  The paper leaves R free; here its scale relative to R0 is kept in
``[scale_min, scale_max]`` (default 1e-2 .. 1e3), so a long run of t != 1 cannot drive R to
zero or overflow.
"""
from __future__ import annotations

from collections import deque

import numpy as np

from fuzzynav.errors import InputFileError, brief
from fuzzynav.filters.catalog import find_rule_file
from fuzzynav.fuzzy import load_fis
from fuzzynav.fuzzy.kernels import eval_compiled

__all__ = ["DEFAULT_RULES", "AlignRScaling", "FuzzyRScaling", "policy_for"]

#: the rule file shipped with the paper's three hand rules
DEFAULT_RULES = "paper002_ror.json"


def _check_controller(fis, path) -> None:
    """Refuse a rule file that is not a ROR -> t controller (one input, one positive output;
    a binding, if any, of the ``r-scaling`` adapter reading ``ror``), naming the field."""
    def fail(where, what):
        raise InputFileError(path, where, f"{what}; the alignment filters take a ROR -> t "
                                          f"controller (e.g. {DEFAULT_RULES})")
    if len(fis.inputs) != 1 or len(fis.outputs) != 1:
        fail("$.inputs", f"has {len(fis.inputs)} input(s) and {len(fis.outputs)} output(s), "
                         "not 1 and 1")
    binding = fis.binding or {}
    if binding:
        if binding.get("adapter") != "r-scaling":
            fail("$.binding.adapter", f"is {brief(binding.get('adapter'))}, not 'r-scaling'")
        stat = (binding.get("inputs") or {}).get(fis.inputs[0].name, {}).get("statistic")
        if stat != "ror":
            fail(f"$.binding.inputs.{fis.inputs[0].name}.statistic",
                 f"is {brief(stat)}, not 'ror'")
    lo = fis.outputs[0].range[0]
    if not lo > 0:
        fail("$.outputs[0].range", f"starts at {lo:g}: the factor t multiplies R and must be "
                                   "> 0 over the whole range")


class AlignRScaling:
    """The ROR -> t controller as an alignment-filter policy, stepped epoch by epoch in
    numpy (the navigation loop's compiled ``r-scaling`` policy is
    :class:`fuzzynav.filters.adaptation.r_scaling.FuzzyRScaling`).

    Parameters
    ----------
    fis : FuzzySystem or path
        One input (ROR) and one output (t); a rule file's ``binding.window`` gives the
        default window.
    window : int, optional
        Epochs M of the measured innovation covariance.
    scale_min, scale_max : float
        Bounds of ``tr R / tr R0``.
    """

    def __init__(self, fis, window=None, scale_min=1e-2, scale_max=1e3):
        path = None
        if not hasattr(fis, "evaluate"):
            path = find_rule_file(fis)
            fis = load_fis(path)
        self.fis = fis
        _check_controller(fis, path)
        binding = self.fis.binding or {}
        self.window = int(window or binding.get("window", 10))
        self.scale_min, self.scale_max = scale_min, scale_max
        self._in = self.fis.inputs[0].name
        self._out = self.fis.outputs[0].name
        # the compiled kernel costs ~1 us a call against ~150 us for ``evaluate``
        self._cf = self.fis.compile() if self.fis.is_compilable else None
        if self._cf is not None:
            self._x, self._y = np.empty(1), np.empty(self._cf.n_outputs)
            self._work = np.empty(self._cf.work_size)
        self.reset(None)

    def reset(self, R0) -> None:
        """Forget the innovations; the scale of R starts at 1."""
        self._buf = deque(maxlen=self.window)
        self._scale = 1.0
        self.last_ror = np.nan

    def factor(self, r, D) -> float:
        """The factor t for this epoch from the innovation ``r`` and ``D = H P- H^T + R``."""
        r = np.asarray(r, dtype=float)
        self._buf.append(float(r @ r))       # tr(r r^T): only the trace of C_r is used
        if len(self._buf) < self.window:
            self.last_ror = np.nan
            return 1.0
        self.last_ror = float(np.mean(self._buf) / np.trace(D))
        t = self._evaluate(self.last_ror)
        t = min(max(t, self.scale_min / self._scale), self.scale_max / self._scale)
        self._scale *= t
        return t

    def _evaluate(self, ror: float) -> float:
        if self._cf is None:
            return float(self.fis.evaluate({self._in: ror})[self._out])
        self._x[0] = ror
        eval_compiled(self._cf.fparams, self._cf.iparams, self._x, self._y, self._work)
        return float(self._y[0])


#: the former name (it clashed with the navigation loop's policy); kept for the
#: alignment study driver until issue 23's branches are merged
FuzzyRScaling = AlignRScaling


def policy_for(fuzzy: bool, rules=None):
    """The R-scaling policy of an alignment filter (None if it does not adapt R).

    Parameters
    ----------
    fuzzy : bool
        Whether the filter adapts R (:attr:`fuzzynav.align.alignment_run.AlignFilter.fuzzy`).
    rules : str, path or FuzzySystem, optional
        The ROR -> t controller (default: the paper's, :data:`DEFAULT_RULES`).
    """
    return AlignRScaling(DEFAULT_RULES if rules is None else rules) if fuzzy else None
