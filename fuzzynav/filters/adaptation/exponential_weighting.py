"""Fuzzy exponential weighting (paper 000): a fuzzy system maps the degree of mismatch to alpha.

At each epoch of the bound sensor, the windowed innovation statistics of the channels named
in the rule file's binding (e.g. DoM of ``pos`` and ``vel``) feed the fuzzy system; its output
``alpha`` (>= 1) weights the update as the paper writes it::

    P- = alpha^2 Phi P Phi^T + Gamma Q Gamma^T,    K = P- H^T (H P- H^T + R / alpha^2)^-1

(``alpha^2`` multiplies the part of ``P-`` propagated since the last update, on the states
the sensor measures directly; the process noise accumulated since then is not weighted).

The paper's alpha is a fading factor, ``alpha >= 1``: outputs below 1 are raised to 1 —
unless the rule file's output range itself reaches below 1, in which case alpha may go down
to that bound (``alpha < 1`` sharpens ``P-`` and inflates ``R``: trusting measurements less,
outside the paper's scheme, offered to the optimiser as an extension).  NaN (no statistic)
gives 1.  Logged per epoch: ``alpha`` and the fuzzy inputs.
"""
from __future__ import annotations

import math


from fuzzynav.filters.adaptation import ADAPT_SIG, register
from fuzzynav.filters.adaptation.fuzzy_common import IP_OUT, evaluate, log_inputs
from fuzzynav.filters.adaptation.fuzzy_policy import FuzzyPolicy
from fuzzynav.filters.numba_lazy import njit_signature

__all__ = ["ALPHA_MIN", "alpha_kernel", "FuzzyExponentialWeighting"]


#: lowest fading factor the kernel applies (an output below is raised to it)
ALPHA_MIN = 0.1


@njit_signature(ADAPT_SIG)
def alpha_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    status, x, y = evaluate(fp, ip, st, r, HPH, R, chan, m, ctx)
    alpha = y[ip[IP_OUT]]
    if not alpha >= fp[1]:  # fp[1]: the lowest alpha allowed (1, or the output range's low end)
        alpha = fp[1] if math.isfinite(alpha) else 1.0
    out[0] = alpha * alpha
    out[1] = 1.0
    for i in range(m):
        out[2 + i] = 1.0 / (alpha * alpha)
    diag[0] = alpha
    log_inputs(diag, 1, x)
    return status


@register
class FuzzyExponentialWeighting(FuzzyPolicy):
    """Paper 000's fuzzy adaptive (exponentially weighted) Kalman filter, per sensor."""

    name = "exponential-weighting"
    kernel = alpha_kernel
    role = "alpha"
    domains = (("alpha", ALPHA_MIN, math.inf),)
    diag_prefix = ("alpha",)

    def policy_floats(self):
        out = self.fis.outputs[self.binding.output_index(self.fis, self.role)]
        return (min(1.0, max(out.range[0], ALPHA_MIN)),)
