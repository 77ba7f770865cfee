"""Classical adaptive and robust baselines the fuzzy filters are judged against.

All act per sensor stream through the adaptation slot (see :mod:`..adaptation`); ``fp`` holds
their constants, ``st`` their running state.  Rows are identified by their position in the
measurement (stable for a given sensor configuration).

* :class:`ConstantScale` — a fixed R multiplier per channel: the tuned constant-noise EKF.
* :class:`SageHusa` — ``R_i <- (1-d) R_i + d (r_i^2 - (H P- H^T)_ii)`` with
  ``d_k = (1-b)/(1-b^(k+1))``, kept between a floor and a cap times the nominal variance.
* :class:`Huber` — M-estimation: ``w_i = min(1, gamma / |r_i / sqrt(S_ii)|)``, R divided by w.
* :class:`FadingMemory` — strong tracking: ``V = (rho V + r r^T) / (1 + rho)``,
  ``lambda = min(max(1, (tr V - beta tr R) / tr(H P- H^T)), lam_max)`` inflates the
  propagated P.
* :class:`VariationalBayes` — Särkkä & Nummenmaa (2009) diagonal-R inverse-Gamma posteriors
  with forgetting ``rho`` and a few fixed-point iterations, done in measurement space.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.filters.adaptation import ADAPT_SIG, Adapter, register
from fuzzynav.filters.numba_lazy import njit_signature

__all__ = ["MAX_ROWS", "constant_kernel", "ConstantScale", "sage_husa_step", "sage_husa_kernel",
           "SageHusa", "huber_step", "huber_kernel", "Huber", "fading_kernel", "FadingMemory",
           "vb_step", "vb_kernel", "VariationalBayes"]

MAX_ROWS = 16


@nb.njit(cache=True, error_model="numpy")
def _ones(out, m):
    out[0] = 1.0
    out[1] = 1.0
    for i in range(m):
        out[2 + i] = 1.0


@njit_signature(ADAPT_SIG)
def constant_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    out[0] = 1.0
    out[1] = 1.0
    for i in range(m):
        out[2 + i] = fp[chan[i]]
    diag[0] = fp[chan[0]] if m > 0 else 1.0
    return 0


@register
class ConstantScale(Adapter):
    """Fixed R multipliers per measurement channel (``{"pos": 2.0, "vel": 1.5}``)."""

    name = "constant-scale"
    kernel = constant_kernel
    diag_names = ("r_scale",)

    def __init__(self, scales=None, default: float = 1.0):
        self.scales = dict(scales or {})
        self.default = float(default)

    def arrays(self, model):
        fp = np.array([float(self.scales.get(c, self.default)) for c in model.channels])
        return fp, np.zeros(1, np.int64), np.zeros(1)


@nb.njit(cache=True, error_model="numpy")
def sage_husa_step(d, floor, cap, st, r, HPH, R, m, out):
    """One Sage-Husa epoch with weight ``d``: ``R_i <- (1-d) R_i + d (r_i^2 - HPH_ii)``,
    bounded by ``[floor, cap] R_i``; estimates in ``st[1:1+m]``, R multipliers in ``out``.
    Shared by :func:`sage_husa_kernel` and the fuzzy supervisor
    (:mod:`~fuzzynav.filters.adaptation.supervisors`)."""
    out[0] = 1.0
    out[1] = 1.0
    for i in range(m):
        rh = st[1 + i] if st[1 + i] > 0.0 else R[i]
        rh = (1.0 - d) * rh + d * (r[i] * r[i] - HPH[i, i])
        rh = min(max(rh, floor * R[i]), cap * R[i])
        st[1 + i] = rh
        out[2 + i] = rh / R[i]


@njit_signature(ADAPT_SIG)
def sage_husa_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    b, floor, cap = fp[0], fp[1], fp[2]
    k = st[0]
    d = (1.0 - b) / (1.0 - b ** (k + 1.0))
    st[0] = k + 1.0
    sage_husa_step(d, floor, cap, st, r, HPH, R, m, out)
    diag[0] = out[2] if m > 0 else 1.0
    return 0


@register
class SageHusa(Adapter):
    """Sage-Husa measurement-noise estimation (forgetting factor ``b``).

    The estimate is kept within ``[floor, cap]`` times the nominal variance (the R bounds a
    baseline study tunes; ``cap = inf``: no upper bound).
    """

    name = "sage-husa"
    kernel = sage_husa_kernel
    diag_names = ("r_scale_row0",)

    def __init__(self, b: float = 0.98, floor: float = 0.1, cap: float = math.inf):
        self.b, self.floor, self.cap = float(b), float(floor), float(cap)

    def arrays(self, model):
        return (np.array([self.b, self.floor, self.cap]), np.zeros(1, np.int64),
                np.zeros(1 + MAX_ROWS))


@nb.njit(cache=True, error_model="numpy")
def huber_step(gamma, r, HPH, R, m, out):
    """Huber weights ``w_i = min(1, gamma / |r_i / sqrt(S_ii)|)``, ``out[2+i] = 1 / w_i``;
    returns the smallest weight (shared with the fuzzy supervisor)."""
    out[0] = 1.0
    out[1] = 1.0
    wmin = 1.0
    for i in range(m):
        zeta = abs(r[i]) / math.sqrt(HPH[i, i] + R[i])
        w = 1.0 if zeta <= gamma else gamma / zeta
        out[2 + i] = 1.0 / w
        wmin = min(wmin, w)
    return wmin


@njit_signature(ADAPT_SIG)
def huber_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    diag[0] = huber_step(fp[0], r, HPH, R, m, out)
    return 0


@register
class Huber(Adapter):
    """Huber M-estimation of the update (one reweighting step), threshold ``gamma``."""

    name = "huber"
    kernel = huber_kernel
    diag_names = ("min_weight",)

    def __init__(self, gamma: float = 1.345):
        self.gamma = float(gamma)

    def arrays(self, model):
        return np.array([self.gamma]), np.zeros(1, np.int64), np.zeros(1)


@njit_signature(ADAPT_SIG)
def fading_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    rho, beta, lam_max = fp[0], fp[1], fp[2]
    trv, trr, trh = 0.0, 0.0, 0.0
    first = st[0] == 0.0
    st[0] = 1.0
    for i in range(m):
        v = r[i] * r[i] if first else (rho * st[1 + i] + r[i] * r[i]) / (1.0 + rho)
        st[1 + i] = v
        trv += v
        trr += R[i]
        trh += HPH[i, i]
    st[1 + MAX_ROWS] += 1.0
    lam = 1.0
    if trh > 0.0 and st[1 + MAX_ROWS] >= 1.0 / (1.0 - rho):  # after the average has settled
        lam = min(max(1.0, (trv - beta * trr) / trh), lam_max)
    _ones(out, m)
    out[0] = lam
    diag[0] = lam
    return 0


@register
class FadingMemory(Adapter):
    """Strong-tracking fading memory: inflate the propagated P by lambda >= 1.

    ``beta`` > 1 softens the test (innovations must exceed ``beta R``) and ``lam_max`` caps the
    factor: when ``H P- H^T`` is much smaller than ``R`` (a converged heading, say) the noise of
    the innovation average alone would otherwise give huge factors and inflate P without end.
    """

    name = "fading-memory"
    kernel = fading_kernel
    diag_names = ("lambda",)

    def __init__(self, rho: float = 0.95, beta: float = 4.0, lam_max: float = 3.0):
        self.rho, self.beta, self.lam_max = float(rho), float(beta), float(lam_max)

    def arrays(self, model):
        return (np.array([self.rho, self.beta, self.lam_max]), np.zeros(1, np.int64),
                np.zeros(2 + MAX_ROWS))


@nb.njit(cache=True, error_model="numpy")
def vb_step(rho, n_iter, st, r, HPH, R, m, out):
    """One variational-Bayes epoch with forgetting ``rho`` on the posteriors in ``st``
    (layout of :class:`VariationalBayes`); shared with the fuzzy supervisor."""
    a = st[1:1 + MAX_ROWS]
    b = st[1 + MAX_ROWS:1 + 2 * MAX_ROWS]
    if st[0] == 0.0:  # prior: mean R equal to the nominal variance, weak (alpha = 2)
        for i in range(m):
            a[i], b[i] = 2.0, 2.0 * R[i]
        st[0] = 1.0
    a0 = np.empty(m)
    b0 = np.empty(m)
    for i in range(m):
        a0[i], b0[i] = rho * a[i], rho * b[i]
        a[i], b[i] = a0[i] + 0.5, b0[i]
    Rh = np.empty(m)
    for _ in range(n_iter):
        S = HPH[:m, :m].copy()
        for i in range(m):
            Rh[i] = b[i] / a[i]
            S[i, i] += Rh[i]
        Si = np.linalg.inv(S)
        G = HPH[:m, :m] @ Si          # H K in measurement space
        res = r[:m] - G @ r[:m]       # posterior residual r - H dx
        HPpH = HPH[:m, :m] - G @ HPH[:m, :m]
        for i in range(m):
            b[i] = b0[i] + 0.5 * (res[i] * res[i] + HPpH[i, i])
    _ones(out, m)
    for i in range(m):
        out[2 + i] = (b[i] / a[i]) / R[i]


@njit_signature(ADAPT_SIG)
def vb_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    vb_step(fp[0], int(fp[1]), st, r, HPH, R, m, out)
    diag[0] = out[2] if m > 0 else 1.0
    return 0


@register
class VariationalBayes(Adapter):
    """Variational-Bayes adaptive Kalman filter (diagonal R, forgetting ``rho``)."""

    name = "variational-bayes"
    kernel = vb_kernel
    diag_names = ("r_scale_row0",)

    def __init__(self, rho: float = 0.98, iterations: int = 3):
        self.rho, self.iterations = float(rho), int(iterations)

    def arrays(self, model):
        return (np.array([self.rho, float(self.iterations)]), np.zeros(1, np.int64),
                np.zeros(1 + 2 * MAX_ROWS))
