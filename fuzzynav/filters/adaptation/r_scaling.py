"""Fuzzy R-scaling (paper 002): ``R(k) = t(k) R(k-1)`` with ``t(k) = FIS(ROR(k))``.

``ROR(k) = tr(C_r) / tr(D_r)``, the windowed actual innovation covariance over the
theoretical one ``D_r = H P- H^T + R(k-1)`` (``R(k-1)`` the already adapted variance).  The
running factor ``s = R(k) / R_nominal`` starts at 1 and is kept within its bounds (default
``[1e-3, 1e3]``) so a long run of bad epochs cannot drive it to zero or infinity.  Logged per
epoch: the running factor ``r_scale``, the step ``t`` and the fuzzy inputs.

The one R-scaling policy of the package: the navigation loop runs it per sensor, the
alignment filters (:mod:`fuzzynav.align.fine`) step it epoch by epoch through
:class:`~fuzzynav.filters.adaptation.epoch.EpochPolicy` with their own bounds and
``full_window`` (paper 002: ``t = 1`` until the window holds ``M`` epochs).
"""
from __future__ import annotations

import numba as nb

from fuzzynav.filters.adaptation import ADAPT_SIG, register
from fuzzynav.errors import FuzzynavError
from fuzzynav.filters.adaptation.fuzzy_common import (IP_OUT, IP_WIN, evaluate, log_inputs,
                                                      scalars)
from fuzzynav.filters.adaptation.fuzzy_policy import FuzzyPolicy
from fuzzynav.filters.numba_lazy import njit_signature

__all__ = ["R_STEP_FLOATS", "r_step", "rscale_kernel", "FuzzyRScaling"]

#: default bounds of the running factor ``s``
S_MIN, S_MAX = 1e-3, 1e3
#: where :func:`r_step` reads its constants in ``fp`` (the policy floats): the bounds of
#: ``s`` and the full-window flag (nonzero: ``t = 1`` until the window is full)
FP_S_MIN, FP_S_MAX, FP_FULL_WINDOW = 1, 2, 3
#: those floats by default (every policy stepping :func:`r_step` carries them)
R_STEP_FLOATS = (S_MIN, S_MAX, 0.0)


@nb.njit(cache=True, error_model="numpy")
def r_step(fp, ip, st, r, HPH, R, chan, m, ctx):
    """Evaluate the system on statistics that see ``R(k-1)`` and step the running factor.

    Returns ``(status, x, y, s, t)``: the fuzzy inputs and outputs, the new factor ``s``
    (stored in the first policy scalar) and the step ``t`` (1 while a full-window policy's
    window fills: the window count is ``st[0]``, :mod:`.window`).
    """
    sc = scalars(st)
    if sc[0] == 0.0:
        sc[0] = 1.0
    s = sc[0]
    for i in range(m):  # the statistics see R(k-1), the running adapted variance
        R[i] *= s
    status, x, y = evaluate(fp, ip, st, r, HPH, R, chan, m, ctx)
    for i in range(m):
        R[i] /= s
    t = y[ip[IP_OUT]]
    if not t > 0.0 or (fp[FP_FULL_WINDOW] != 0.0 and st[0] < ip[IP_WIN]):
        t = 1.0
    s = min(max(s * t, fp[FP_S_MIN]), fp[FP_S_MAX])
    sc[0] = s
    return status, x, y, s, t


@njit_signature(ADAPT_SIG)
def rscale_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    status, x, y, s, t = r_step(fp, ip, st, r, HPH, R, chan, m, ctx)
    out[0] = 1.0
    out[1] = 1.0
    for i in range(m):
        out[2 + i] = s
    diag[0] = s
    diag[1] = t
    log_inputs(diag, 2, x)
    return status


@register
class FuzzyRScaling(FuzzyPolicy):
    """Paper 002's fuzzy adaptive measurement-noise scaling.

    Parameters
    ----------
    fis, source, binding
        As :class:`~fuzzynav.filters.adaptation.fuzzy_policy.FuzzyPolicy`.
    scale_bounds : (float, float)
        Bounds of the running factor ``s = R / R_nominal`` (``0 < lo <= 1 <= hi``).
    full_window : bool
        Keep ``t = 1`` until the window holds ``binding.window`` epochs (paper 002's
        ``C_r`` is a mean over ``M`` epochs); by default the statistics of a filling
        window drive ``t`` from the first epoch.
    """

    name = "r-scaling"
    kernel = rscale_kernel
    role = "r_scale"
    domains = (("r_scale", S_MIN, S_MAX),)  # the step t; the running factor has these bounds
    diag_prefix = ("r_scale", "t")

    def __init__(self, fis, source=None, binding=None, scale_bounds=(S_MIN, S_MAX),
                 full_window=False):
        super().__init__(fis, source, binding)
        lo, hi = (float(b) for b in scale_bounds)
        if not 0.0 < lo <= 1.0 <= hi < float("inf"):
            raise FuzzynavError(f"r-scaling: scale_bounds must satisfy 0 < lo <= 1 <= hi "
                                f"(finite), got {scale_bounds!r}")
        self.floats = (lo, hi, 1.0 if full_window else 0.0)
