"""Fuzzy R-scaling (paper 002): ``R(k) = t(k) R(k-1)`` with ``t(k) = FIS(ROR(k))``.

``ROR(k) = tr(C_r) / tr(D_r)``, the windowed actual innovation covariance over the
theoretical one ``D_r = H P- H^T + R(k-1)`` (``R(k-1)`` the already adapted variance).  The
running factor ``s = R(k) / R_nominal`` starts at 1 and is kept within
``[1e-3, 1e3]`` so a long run of bad epochs cannot drive it to zero or infinity.  Logged per
epoch: the running factor ``r_scale``, the step ``t`` and the fuzzy inputs.
"""
from __future__ import annotations

import numba as nb

from fuzzynav.filters.adaptation import ADAPT_SIG, register
from fuzzynav.filters.adaptation.fuzzy_common import IP_OUT, evaluate, log_inputs, scalars
from fuzzynav.filters.adaptation.fuzzy_policy import FuzzyPolicy
from fuzzynav.filters.numba_lazy import njit_signature

S_MIN, S_MAX = 1e-3, 1e3


@nb.njit(cache=True, error_model="numpy")
def r_step(fp, ip, st, r, HPH, R, chan, m, ctx):
    """Evaluate the system on statistics that see ``R(k-1)`` and step the running factor.

    Returns ``(status, x, y, s, t)``: the fuzzy inputs and outputs, the new factor ``s``
    (stored in the first policy scalar) and the step ``t``.
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
    if not t > 0.0:
        t = 1.0
    s = min(max(s * t, S_MIN), S_MAX)
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
    """Paper 002's fuzzy adaptive measurement-noise scaling."""

    name = "r-scaling"
    kernel = rscale_kernel
    role = "r_scale"
    domains = (("r_scale", S_MIN, S_MAX),)  # the step t; the running factor has these bounds
    diag_prefix = ("r_scale", "t")
