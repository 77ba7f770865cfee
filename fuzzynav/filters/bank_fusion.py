"""The bank's numba kernels: propagation of every local, information fusion, sharing, shifts.

The algebra and why the loop applies it as it does are in :mod:`fuzzynav.filters.bank`.
Shapes: ``L`` local filters, ``n`` error states; ``P`` (L, n, n), ``x`` (L, n).  Work
arrays are passed in, so nothing allocates inside the filter loop.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.filters import error_hook, kalman
from fuzzynav.filters.bank_beta import update_shares
from fuzzynav.filters.error_model import block_end, fill_F
from fuzzynav.filters.feedback import feedback
from fuzzynav.filters.layout import N_CORE

__all__ = ["REF_LOCAL", "lower_inverse", "add_gram", "add_information_vector", "spd_inverse",
           "fuse", "after_propagation", "master_covariance", "share", "propagate_state",
           "local_residual", "fusion_work", "propagate_locals", "fuse_and_feed_back"]


#: the local filter whose standard deviations scale the states for the fusion (any would do)
REF_LOCAL = 0


@nb.njit(cache=True, error_model="numpy")
def lower_inverse(L, n, W):
    """``W = L^-1`` for a lower-triangular ``L`` (n x n), by columns; ``W``'s strict upper
    triangle is not touched (nothing here reads it)."""
    for j in range(n):
        W[j, j] = 1.0 / L[j, j]
        for i in range(j + 1, n):
            s = 0.0
            for k in range(j, i):
                s += L[i, k] * W[k, j]
            W[i, j] = -s / L[i, i]


@nb.njit(cache=True, error_model="numpy")
def add_gram(W, n, Y):
    """``Y += W^T W`` on the lower triangle, ``W`` lower triangular: with ``A = L L^T`` and
    ``W = L^-1``, ``A^-1 = W^T W`` (the triangular inverse costs a third of ``n`` solves)."""
    for i in range(n):
        for j in range(i + 1):
            s = 0.0
            for k in range(i, n):
                s += W[k, i] * W[k, j]
            Y[i, j] += s


@nb.njit(cache=True, error_model="numpy")
def add_information_vector(W, n, v, y, tmp):
    """``y += W^T W v`` (``W`` lower triangular), through ``tmp = W v``."""
    for i in range(n):
        s = 0.0
        for k in range(i + 1):
            s += W[i, k] * v[k]
        tmp[i] = s
    for i in range(n):
        s = 0.0
        for k in range(i, n):
            s += W[k, i] * tmp[k]
        y[i] += s


@nb.njit(cache=True, error_model="numpy")
def spd_inverse(A, out, L, W):
    """``out = A^-1`` for a symmetric positive-definite ``A`` (n x n, its lower triangle
    read); False if not PD.  ``L`` receives the Cholesky factor, ``W`` its inverse; ``out``
    is exactly symmetric."""
    n = A.shape[0]
    if not kalman.cholesky(A, n, L):
        return False
    lower_inverse(L, n, W)
    for i in range(n):
        for j in range(i + 1):
            out[i, j] = 0.0
    add_gram(W, n, out)
    for i in range(n):
        for j in range(i + 1, n):
            out[i, j] = out[j, i]
    return True


@nb.njit(cache=True, error_model="numpy")
def fuse(P, x, Pg, xg, work):
    """Information fusion ``Pg = (sum P_i^-1)^-1``, ``xg = Pg sum P_i^-1 x_i``; False if a
    covariance is not positive definite.

    The states are scaled by the first local's standard deviations ``d`` first
    (``P_i -> D^-1 P_i D^-1``): the bias variances are ~1e-10 of the position variances, and
    the inverses of the scaled matrices lose ~1e10 times less to rounding.  Each local's
    information ``P_i^-1 = W_i^T W_i`` comes from the inverse ``W_i`` of its Cholesky factor
    (about n^3 / 2 operations where n solves for the columns of ``P_i^-1`` cost 7 n^3 / 6);
    only lower triangles are summed.  ``work`` is a :func:`fusion_work` tuple.
    """
    d, Y, y, A, W, L, col, v = work
    nl, n = x.shape
    for i in range(n):
        d[i] = math.sqrt(P[REF_LOCAL, i, i])
        y[i] = 0.0
        for j in range(i + 1):
            Y[i, j] = 0.0
    for k in range(nl):
        for i in range(n):
            for j in range(i + 1):
                A[i, j] = P[k, i, j] / (d[i] * d[j])
        if not kalman.cholesky(A, n, L):
            return False
        lower_inverse(L, n, W)
        add_gram(W, n, Y)
        for j in range(n):
            v[j] = x[k, j] / d[j]
        add_information_vector(W, n, v, y, col)
    if not spd_inverse(Y, A, L, W):
        return False
    kalman.chol_solve_vec(L, n, y, y)  # L still holds the factor of Y
    for i in range(n):
        xg[i] = d[i] * y[i]
        for j in range(i + 1):  # mirrored: exactly symmetric
            Pg[i, j] = d[i] * A[i, j] * d[j]
            Pg[j, i] = Pg[i, j]
    return True


#: what the locals' covariances say about the master's (``master_covariance``): the last
#: fusion is current; every local holds the master's ``P / beta_i`` (at the start, and in
#: reset mode until a local updates without fusing); or only a new fusion tells
FUSED_NOW, SHARED, STALE = 0, 1, 2


@nb.njit(cache=True, error_model="numpy")
def after_propagation(fstate, reset):
    """The fusion state once every local has been propagated with ``Q / beta_i``."""
    if fstate == STALE or (fstate == FUSED_NOW and not reset):
        return STALE
    return SHARED


@nb.njit(cache=True, error_model="numpy")
def master_covariance(P, x, beta, Pg, fstate, Pf, xf, work):
    """The master's covariance now: ``Pg``, ``beta_1 P_1`` or a fusion into ``Pf`` (NaN if
    that fails)."""
    if fstate == FUSED_NOW:
        return Pg
    n = x.shape[1]
    if fstate == SHARED:
        for i in range(n):
            for j in range(n):
                Pf[i, j] = beta[REF_LOCAL] * P[REF_LOCAL, i, j]
    elif not fuse(P, x, Pf, xf, work):
        Pf[:, :] = np.nan
    return Pf


@nb.njit(cache=True, error_model="numpy")
def share(P, x, Qacc, Pg, xg, beta, reset):
    """After feeding ``xg`` back to the shared navigation state: every local's error shifts
    by ``-xg``; in reset mode the locals restart from the fused solution (``x_i = xg``, so
    0 after the shift, and ``P_i = Pg / beta_i``, an updated covariance: nothing in it is
    propagated noise any more, so the ``Qacc_i`` that adaptive weighting reads restart)."""
    nl, n = x.shape
    for k in range(nl):
        if reset:
            for i in range(n):
                x[k, i] = 0.0
                for j in range(n):
                    P[k, i, j] = Pg[i, j] / beta[k]
                    Qacc[k, i, j] = 0.0
        else:
            for i in range(n):
                x[k, i] -= xg[i]


@nb.njit(cache=True, error_model="numpy")
def propagate_state(Phi, x, tmp):
    """``x <- Phi x`` (a local's error estimate carried between fusions)."""
    n = x.size
    for i in range(n):
        s = 0.0
        for j in range(n):
            a = Phi[i, j]
            if a != 0.0:
                s += a * x[j]
        tmp[i] = s
    for i in range(n):
        x[i] = tmp[i]


@nb.njit(cache=True, error_model="numpy")
def local_residual(z, H, m, x):
    """``z <- z - H x``: the innovation of a local whose estimate ``x`` is not fed back yet."""
    for r in range(m):
        s = 0.0
        for j in range(x.size):
            h = H[r, j]
            if h != 0.0:
                s += h * x[j]
        z[r] -= s


@nb.njit(cache=True, error_model="numpy")
def fusion_work(n):
    """Scratch arrays of :func:`fuse`: ``(d, Y, y, A, W, L, col, v)``."""
    return (np.zeros(n), np.zeros((n, n)), np.zeros(n), np.zeros((n, n)), np.zeros((n, n)),
            np.zeros((n, n)), np.zeros(n), np.zeros(n))


@nb.njit(cache=True, error_model="numpy")
def propagate_locals(state, model, em, acc, nav, xs, tau, keep_q, carry):
    """Propagate every local's P (and, with ``carry``, its x) over the accumulated interval
    ``tau`` and decay the shared Gauss-Markov estimates ``xs``.

    ``state`` is the :class:`~fuzzynav.filters.loop_args.BankState`, ``model`` the
    :class:`~fuzzynav.filters.loop_args.Model`, ``em`` the error-model argument of
    :mod:`fuzzynav.filters.error_hook`, ``acc`` the
    :class:`~fuzzynav.filters.loop_args.Propagation` (its sums restart from zero).  One
    ``F`` for all locals (one mechanization); each local its own noise densities.  With
    ``keep_q`` each local's discrete noise is summed into ``acc.Qacc`` (the noise since its
    last update, which a policy that scales the predicted covariance needs)."""
    P3, X, QD = state.P, state.x, state.qd
    sumC, sumf, Cm, fm = acc.sumC, acc.sumf, acc.Cm, acc.fm
    F, Phi, Qd, work = acc.F, acc.Phi, acc.Qd, acc.work
    blk_start, blk_inv_tau = model.blk_start, model.blk_inv_tau
    for i in range(3):
        fm[i] = sumf[i] / tau
        sumf[i] = 0.0
        for j in range(3):
            Cm[i, j] = sumC[i, j] / tau
            sumC[i, j] = 0.0
    fill_F(F, nav, Cm, fm, blk_start, model.blk_kind, blk_inv_tau)
    error_hook.system(em, F, nav)
    n = F.shape[0]
    tail = kalman.diagonal_tail(F)  # the sensor blocks only decay: Phi keeps F's tail
    for b in range(X.shape[0]):
        error_hook.discretize(em, F, QD[b], tau, Phi, Qd, work, tail, acc.Qc, nav)
        kalman.propagate_tail(P3[b], Phi, Qd, work, tail)
        if keep_q:
            Qacc = acc.Qacc[b]
            for i in range(n):
                for j in range(n):
                    Qacc[i, j] += Qd[i, j]
        if carry:
            propagate_state(Phi, X[b], acc.dx)
    for b in range(blk_start.size):
        if blk_inv_tau[b] > 0.0:
            d = math.exp(-tau * blk_inv_tau[b])
            for i in range(blk_start[b], block_end(blk_start, b, n)):
                xs[i - N_CORE] *= d


@nb.njit(cache=True, error_model="numpy")
def fuse_and_feed_back(em, bank, state, fu, Qacc3, nav, prev, xs, li, t_meas, t_fused):
    """A bank after an update of local ``li`` at ``t_meas``: when the fusion is due, new
    shares (share controller), the fusion, the sharing of the fused solution and its
    feedback into ``nav``, ``prev``, ``xs``.

    ``bank``, ``state``, ``fu`` are the loop's :class:`~fuzzynav.filters.loop_args.Bank`,
    :class:`~fuzzynav.filters.loop_args.BankState` and
    :class:`~fuzzynav.filters.loop_args.FusionWork`, ``em`` the error-model argument of
    :mod:`fuzzynav.filters.error_hook`.  Returns ``(ok, fusion state, time of the last
    fusion)``, ``ok`` whether the covariance the step leaves (the fused one, else the
    updated local's) is still one.
    """
    if not (bank.period <= 0.0 or t_meas - t_fused >= bank.period - 1e-9):  # not due yet
        return kalman.covariance_ok(state.P[li]), STALE, t_fused
    if bank.ctl.on:  # new shares first: a reset shares P_g by them
        update_shares(bank.ctl, bank.beta, state.qd)
    if not fuse(state.P, state.x, state.Pg, state.xg, fu.work):
        return False, STALE, t_fused
    fb = error_hook.fused_feedback(em, state.xg, state.Pg, nav, fu.xphi)
    share(state.P, state.x, Qacc3, state.Pg, state.xg, bank.beta, bank.reset)
    error_hook.regauge(em, state.P, state.x, fb, bank.reset)
    feedback(nav, prev, xs, fb)
    return kalman.covariance_ok(state.Pg), FUSED_NOW, t_meas
