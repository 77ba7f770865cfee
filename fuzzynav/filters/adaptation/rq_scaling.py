"""Fuzzy R- and Q-scaling: paper 002's ``R(k) = t(k) R(k-1)`` plus a process-noise factor.

Like :mod:`~fuzzynav.filters.adaptation.r_scaling` (output bound to ``r_scale``: the step
``t`` of the running R factor), with an optional second output bound to ``q_scale``: the
*level* ``q`` of the process-noise multiplier from this epoch on (1 = nominal Q), kept within
``[Q_MIN, Q_MAX]`` -- more process noise during manoeuvres, less in steady cruise.  The loop
multiplies its process noise by the policy's ``out[1]`` at every epoch, so the kernel returns
the ratio of the new level to the previous one.  Several sensors with a ``q_scale`` output
would compound their factors: bind at most one.  Logged per epoch: ``r_scale``, ``t``,
``q_scale`` and the first fuzzy input.
"""
from __future__ import annotations


from fuzzynav.filters.adaptation import ADAPT_SIG, register
from fuzzynav.filters.adaptation.fuzzy_common import log_inputs, scalars
from fuzzynav.filters.adaptation.fuzzy_policy import FuzzyPolicy
from fuzzynav.filters.adaptation.r_scaling import R_STEP_FLOATS, S_MAX, S_MIN, r_step
from fuzzynav.filters.numba_lazy import njit_signature

__all__ = ["IP_QOUT", "rq_kernel", "FuzzyRQScaling"]

#: bounds of the process-noise level
Q_MIN, Q_MAX = 1e-2, 1e2
#: the free ``ip`` header slot holding the q output's index (-1: none)
IP_QOUT = 6


@njit_signature(ADAPT_SIG)
def rq_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    status, x, y, s, t = r_step(fp, ip, st, r, HPH, R, chan, m, ctx)
    sc = scalars(st)
    if sc[1] == 0.0:  # the process-noise level starts nominal
        sc[1] = 1.0
    q = sc[1]
    if ip[IP_QOUT] >= 0:
        qn = y[ip[IP_QOUT]]
        q = min(max(qn, Q_MIN), Q_MAX) if qn > 0.0 else q
    out[0] = 1.0
    out[1] = q / sc[1]
    sc[1] = q
    for i in range(m):
        out[2 + i] = s
    diag[0], diag[1], diag[2] = s, t, q
    log_inputs(diag, 3, x)
    return status


@register
class FuzzyRQScaling(FuzzyPolicy):
    """Fuzzy R-scaling with an optional fuzzy process-noise level (output ``q_scale``)."""

    name = "rq-scaling"
    kernel = rq_kernel
    role = "r_scale"
    extra_roles = ("q_scale",)
    domains = (("r_scale", S_MIN, S_MAX), ("q_scale", Q_MIN, Q_MAX))
    diag_prefix = ("r_scale", "t", "q_scale")
    floats = R_STEP_FLOATS  # r_step's bounds, no full-window hold

    def __init__(self, fis, source=None, binding=None):
        super().__init__(fis, source, binding)
        self.diag_names = self.diag_names[:4]  # r_scale, t, q_scale, first input

    def arrays(self, model):
        fp, ip, st = super().arrays(model)
        has_q = any(b.target == "q_scale" for b in self.binding.outputs)
        ip[IP_QOUT] = self.binding.output_index(self.fis, "q_scale") if has_q else -1
        return fp, ip, st
