"""Fuzzy supervisors of the classical adaptive filters: a rule file sets the parent's
constant per epoch.

* ``fuzzy-sage-husa`` -- the forgetting factor ``b_k`` of Sage-Husa (role ``b``);
* ``fuzzy-vb`` -- the forgetting ``rho_k`` of variational Bayes (role ``rho``);
* ``fuzzy-huber`` -- the threshold ``gamma_k`` of the Huber update (role ``gamma``).

The fuzzy inputs are any statistic a binding offers (innovation DoM/ROR/NIS, speed,
angular rate, specific-force deviation, fix type, satellite count).  The parent's maths is
the classical kernel's own per-epoch step (:func:`~.classical.sage_husa_step`,
:func:`~.classical.vb_step`, :func:`~.classical.huber_step`), so a rule file whose output is
the parent's constant gives the parent's run bit for bit.

State: the fuzzy policy's arrays (:func:`~.fuzzy_common.pack`) come first, then the parent's
state (its own layout), then the supervisor's scalars; the fuzzy evaluation sees only its
own part of ``st``.

Sage-Husa with a varying ``b_k``: the classical weight ``d_k = (1-b)/(1-b^(k+1))`` is the
reciprocal of ``W_k = 1 + b + ... + b^k``, i.e. the recursion ``W_k = 1 + b_k W_(k-1)``,
``d_k = d_(k-1) / (d_(k-1) + b_k)`` (``d_0 = 1``).  The supervisor uses the closed form
while ``b_k`` has kept its first value (exactly the parent's arithmetic) and the recursion
from the first epoch it differs.  Outputs beyond the parameter's domain are clamped (the
binding refuses rule files whose output range leaves :attr:`domains`).
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.filters.adaptation import ADAPT_SIG, register
from fuzzynav.filters.adaptation.classical import (MAX_ROWS, huber_step, sage_husa_step,
                                                   vb_step)
from fuzzynav.filters.adaptation.fuzzy_common import IP_OUT, evaluate, log_inputs
from fuzzynav.filters.adaptation.fuzzy_policy import FuzzyPolicy
from fuzzynav.filters.numba_lazy import njit_signature

__all__ = ["SH_STATE", "SH_EXTRA", "VB_EXTRA", "B_MAX", "fuzzy_sage_husa_kernel",
           "fuzzy_vb_kernel", "fuzzy_huber_kernel", "FuzzySageHusa", "FuzzyVB", "FuzzyHuber"]

#: Sage-Husa parent state (k, estimates) then the supervisor's b_0, d_(k-1), varied flag
SH_STATE = 1 + MAX_ROWS
SH_EXTRA = SH_STATE + 3
VB_EXTRA = 1 + 2 * MAX_ROWS
B_MAX = 1.0 - 1e-12
GAMMA_MIN, GAMMA_MAX = 1e-3, 100.0


@nb.njit(cache=True, inline="always", error_model="numpy")
def _supervise(fp, ip, st, r, HPH, R, chan, m, ctx, n_extra, lo, hi, fallback):
    """Evaluate the fuzzy system on its part of ``st``; the parameter clamped to
    ``[lo, hi]`` (``fallback`` when not a number).  Returns ``(status, x, value, extra)``,
    ``extra`` the parent's part of ``st``."""
    n = st.size - n_extra
    status, x, y = evaluate(fp, ip, st[:n], r, HPH, R, chan, m, ctx)
    v = y[ip[IP_OUT]]
    v = fallback if not v == v else min(max(v, lo), hi)
    return status, x, v, st[n:]


@njit_signature(ADAPT_SIG)
def fuzzy_sage_husa_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    status, x, b, ps = _supervise(fp, ip, st, r, HPH, R, chan, m, ctx, SH_EXTRA, 0.0, B_MAX,
                                  fp[3])
    k = ps[0]
    if k == 0.0:
        ps[SH_STATE] = b
    if ps[SH_STATE + 2] == 0.0 and b == ps[SH_STATE]:
        d = (1.0 - b) / (1.0 - b ** (k + 1.0))  # constant so far: the parent's closed form
    else:
        ps[SH_STATE + 2] = 1.0
        d = ps[SH_STATE + 1] / (ps[SH_STATE + 1] + b)
    ps[SH_STATE + 1] = d
    ps[0] = k + 1.0
    sage_husa_step(d, fp[1], fp[2], ps, r, HPH, R, m, out)
    diag[0] = out[2] if m > 0 else 1.0
    diag[1] = b
    log_inputs(diag, 2, x)
    return status


@njit_signature(ADAPT_SIG)
def fuzzy_vb_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    status, x, rho, ps = _supervise(fp, ip, st, r, HPH, R, chan, m, ctx, VB_EXTRA, 0.0, 1.0,
                                    fp[3])
    vb_step(rho, int(fp[1]), ps, r, HPH, R, m, out)
    diag[0] = out[2] if m > 0 else 1.0
    diag[1] = rho
    log_inputs(diag, 2, x)
    return status


@njit_signature(ADAPT_SIG)
def fuzzy_huber_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    status, x, gamma, _ = _supervise(fp, ip, st, r, HPH, R, chan, m, ctx, 0, GAMMA_MIN,
                                     GAMMA_MAX, fp[1])
    diag[0] = huber_step(gamma, r, HPH, R, m, out)
    diag[1] = gamma
    log_inputs(diag, 2, x)
    return status


class _Supervisor(FuzzyPolicy):
    """A fuzzy policy setting a classical parent's constant (``n_extra`` floats of parent
    state appended to ``st``).  ``parent`` names the tuned parent's entry of a
    tuned-parameter file: the constants a rule file's ``binding.parent`` may give."""

    n_extra = 0

    def arrays(self, model):
        fp, ip, st = super().arrays(model)
        return fp, ip, np.concatenate([st, np.zeros(self.n_extra)])


@register
class FuzzySageHusa(_Supervisor):
    """Sage-Husa whose forgetting factor ``b_k`` a fuzzy system sets per epoch.

    Parameters
    ----------
    fis, source, binding
        As :class:`~.fuzzy_policy.FuzzyPolicy`.
    floor, cap : float
        The parent's R bounds (times the nominal variance).
    b_fallback : float
        ``b`` used at an epoch whose output is not a number.
    """

    name = "fuzzy-sage-husa"
    parent = "sage-husa-tuned"
    kernel = fuzzy_sage_husa_kernel
    role = "b"
    domains = (("b", 0.0, 1.0),)
    diag_prefix = ("r_scale_row0", "b")
    n_extra = SH_EXTRA

    def __init__(self, fis, source=None, binding=None, floor: float = 0.1,
                 cap: float = math.inf, b_fallback: float = 0.98):
        super().__init__(fis, source, binding)
        self.floats = (float(floor), float(cap), float(b_fallback))


@register
class FuzzyVB(_Supervisor):
    """Variational Bayes whose forgetting ``rho_k`` a fuzzy system sets per epoch
    (``iterations`` fixed-point iterations, ``rho_fallback`` for a non-number output)."""

    name = "fuzzy-vb"
    parent = "vb-tuned"
    kernel = fuzzy_vb_kernel
    role = "rho"
    domains = (("rho", 0.0, 1.0),)
    diag_prefix = ("r_scale_row0", "rho")
    n_extra = VB_EXTRA

    def __init__(self, fis, source=None, binding=None, iterations: int = 3,
                 rho_fallback: float = 0.98):
        super().__init__(fis, source, binding)
        self.floats = (float(int(iterations)), 0.0, float(rho_fallback))


@register
class FuzzyHuber(_Supervisor):
    """The Huber update whose threshold ``gamma_k`` a fuzzy system sets per epoch."""

    name = "fuzzy-huber"
    parent = "huber-tuned"
    kernel = fuzzy_huber_kernel
    role = "gamma"
    domains = (("gamma", GAMMA_MIN, GAMMA_MAX),)
    diag_prefix = ("min_weight", "gamma")

    def __init__(self, fis, source=None, binding=None, gamma_fallback: float = 1.345):
        super().__init__(fis, source, binding)
        self.floats = (float(gamma_fallback),)
