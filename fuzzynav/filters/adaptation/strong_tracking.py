"""Zhou's strong tracking filter: a suboptimal fading factor with a softening factor.

Zhou & Frank (1996), "Fault diagnostics and fault tolerant control" / Zhou, Xi & Chen
(1991): the predicted covariance becomes ``P- = lambda Phi P Phi^T + Q`` with

    V0(1) = r r^T,   V0(k) = (rho V0(k-1) + r r^T) / (1 + rho)
    N(k)  = V0(k) - beta R(k) - H Q H^T
    M(k)  = H Phi P Phi^T H^T            ( = H P- H^T - H Q H^T )
    c(k)  = tr N(k) / tr M(k),          lambda = max(1, c)

``rho`` is the forgetting factor of the innovation average (about 0.95) and ``beta >= 1``
the softening factor that makes the estimate smoother.  Unlike
:class:`~fuzzynav.filters.adaptation.classical.FadingMemory` (``fading-memory``), which
divides by the whole ``H P- H^T`` and waits for its average to settle, this is Zhou's form:
the process noise the measurement sees is removed from both traces and the factor acts from
the first epoch.  The adaptation slot does not see ``H Q H^T``; the adapter is given it per
measurement channel (``hqh``, the variance the white IMU noise adds between two epochs,
computed by the named filter from the configuration).  ``lam_max`` (default: none) is an
optional cap.  The loop applies ``lambda`` as ``factor (P - Q_acc) + Q_acc`` on the states
the measurement sees (:func:`fuzzynav.filters.kalman.scale_predicted`), which is Zhou's
``lambda Phi P Phi^T + Q``.
"""
from __future__ import annotations

import math

import numpy as np

from fuzzynav.filters.adaptation import ADAPT_SIG, Adapter, register
from fuzzynav.filters.numba_lazy import njit_signature

__all__ = ["strong_tracking_kernel", "StrongTracking"]

_MAXROWS = 16
#: fp layout: rho, beta, lam_max, then H Q H^T per measurement channel
_FP_HQH = 3


@njit_signature(ADAPT_SIG)
def strong_tracking_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    rho, beta, lam_max = fp[0], fp[1], fp[2]
    first = st[0] == 0.0
    st[0] = 1.0
    trn, trm = 0.0, 0.0
    for i in range(m):
        v = r[i] * r[i] if first else (rho * st[1 + i] + r[i] * r[i]) / (1.0 + rho)
        st[1 + i] = v
        hqh = fp[_FP_HQH + chan[i]]
        trn += v - beta * R[i] - hqh
        trm += HPH[i, i] - hqh
    lam = 1.0
    if trm > 0.0:
        lam = min(max(1.0, trn / trm), lam_max)
    out[0] = lam
    out[1] = 1.0
    for i in range(m):
        out[2 + i] = 1.0
    diag[0] = lam
    return 0


@register
class StrongTracking(Adapter):
    """Zhou's strong tracking fading factor (forgetting ``rho``, softening ``beta``).

    Parameters
    ----------
    rho : float
        Forgetting factor of the innovation covariance average, in (0, 1].
    beta : float
        Softening factor (>= 1): innovations must exceed ``beta R`` to inflate P.
    lam_max : float
        Cap on the factor (``inf``: none, as in Zhou's filter).
    hqh : dict, optional
        Measurement channel -> ``(H Q H^T)_ii`` per row [channel unit^2] over one epoch
        interval (missing channels: 0).
    """

    name = "strong-tracking"
    kernel = strong_tracking_kernel
    diag_names = ("lambda",)

    def __init__(self, rho: float = 0.95, beta: float = 1.0, lam_max: float = math.inf,
                 hqh=None):
        self.rho, self.beta, self.lam_max = float(rho), float(beta), float(lam_max)
        self.hqh = dict(hqh or {})

    def arrays(self, model):
        hqh = [float(self.hqh.get(c, 0.0)) for c in model.channels]
        fp = np.array([self.rho, self.beta, self.lam_max, *hqh])
        return fp, np.zeros(1, np.int64), np.zeros(1 + _MAXROWS)
