"""Information shares set at run time: a fuzzy controller of the bank's ``beta_i`` (numba).

A filter bank (:mod:`fuzzynav.filters.bank`) gives local ``i`` the information share
``beta_i``: it propagates with ``Q / beta_i`` and, in reset mode, restarts from
``P_g / beta_i``.  The controller here (the rule file's ``binding.adapter`` is
``beta-sharing``, :mod:`fuzzynav.filters.beta_controller`) sets the shares from each local's
innovation statistics, inside the compiled loop.

How beta enters, and why this way (Carlson 1990)
-------------------------------------------------
Carlson divides the common information -- the prior ``P^-1`` and the process-noise
information -- among the locals, ``P_i^-1 = beta_i P^-1``, ``Q_i = Q / beta_i`` with
``sum beta_i = 1``, so that fusing ``sum P_i^-1`` counts it once; each local's measurement
information is its own and is never divided.  A share is therefore a statement about the
*common* part only, and a new share is applied to that part only:

* ``Q_i <- Q_i beta_i,old / beta_i,new`` at the change (the noise densities ``qd_i`` are
  rescaled, so a factor an adaptation policy applied to them is kept), from then on for
  every propagation until the next change.  A local with a smaller share adds more process
  noise, so its covariance grows, its information shrinks and the master weights it less
  (``P_g^-1 = sum P_i^-1``); it also leans more on its own sensors, which is what a local
  whose sensor disagrees with the others should *not* be trusted for.
* ``P_i <- P_g / beta_i`` at a reset (reset mode): the fused covariance is the common
  information after a fusion, and it is shared by the current ``beta``.
* ``P_i`` is not rescaled at a change in no-reset mode: between resets it holds the
  local's own measurement information, which a share does not own (rescaling it would
  create or destroy information).

Hence the shares can act only where they enter: in no-reset mode (through ``Q_i``), and in
reset mode with a ``fusion_period_s`` (``Q_i`` between fusions and ``P_g / beta_i`` at each).
In reset mode fused after every update they cancel exactly (``sum P_i^-1 = P^-1`` for any
shares; ``fuzzynav.filters.bank``), so the controller changes nothing there but what an
adaptation policy or gate reads from ``H P_i H^T``.

When
----
The shares are rewritten at each fusion, before the locals are fused (so a reset already
uses the new shares), from windowed statistics of each local's last ``N`` innovations (every
epoch whose innovation covariance ``S = H P_i H^T + R`` could be formed, gated ones
included, after the local's own adaptation scaled ``R``):

* ``nis`` -- ``sum NIS / sum m`` over the window: the mean normalised innovation square per
  measurement row, 1 when the local is consistent;
* ``ror`` -- ``sum r^T r / sum tr S``: the ratio of actual to predicted innovation power.

A local with no innovation yet reads 1 (consistent: no evidence against it).  The fuzzy
system maps a local's statistics to a weight ``w_i > 0``; the shares are the normalised
weights ``w_i / sum w`` with a floor: every share is at least ``floor`` (``< 1 / L``), the
rest of the mass shared in proportion to the weights (:func:`floor_shares`).  The floor
keeps every local's ``Q_i`` at most ``1 / floor`` times the nominal one, so a local that
lost its share stays well conditioned and wins it back once its innovations are consistent
again.  An invalid weight (NaN, not positive) leaves every share unchanged at that fusion;
a relative change below :data:`MIN_CHANGE` is not applied (it would only add rounding, and
so a controller whose output is constant is bit for bit the bank with fixed shares).

State per local (``BankState.stat[i]``): ``[count, next slot, (nis, m, r^T r, tr S) x N]``.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from numba import types

from fuzzynav.filters.numba_lazy import njit_signature
from fuzzynav.fuzzy.kernels import eval_compiled

__all__ = ["STATISTICS", "DEFAULT_FLOOR", "MIN_CHANGE", "ShareControl", "WEIGH_SIG",
           "fuzzy_weight", "no_weight", "stat_size", "share_control", "push_innovation",
           "window_stat", "floor_shares", "update_shares"]

#: the statistics a share controller reads (binding ``statistic``) -> kernel code
STATISTICS = {"nis": 0, "ror": 1}
#: smallest share any local keeps unless the controller's floor says otherwise
DEFAULT_FLOOR = 0.05
#: relative share changes below this are not applied
MIN_CHANGE = 1e-12
_HEAD, _W = 2, 4  # ring header (count, next), values per epoch (nis, m, rr, trS)


class ShareControl(NamedTuple):
    """The share controller as the loop sees it (``on = 0``: fixed shares).

    ``fp``, ``ip`` the compiled fuzzy system, ``codes`` the statistic of each fuzzy input,
    ``out_index`` the output giving the weight, ``floor`` the smallest share, ``stat``
    (L, :func:`stat_size`) each local's innovation ring; then scratch: ``x``, ``y``,
    ``fwork`` (the system's inputs, outputs, work), ``w`` and ``new`` (L,); ``weigh``,
    a 1-tuple of the kernel evaluating the system (:func:`fuzzy_weight`, or the stand-in
    :func:`no_weight` when off).  The kernel is a first-class function (:data:`WEIGH_SIG`):
    the loop's code does not contain the fuzzy engine, which a bank without a controller
    (every filter but the fuzzy-beta ones) then never compiles.
    """

    on: int
    fp: np.ndarray
    ip: np.ndarray
    codes: np.ndarray
    out_index: int
    floor: float
    stat: np.ndarray
    x: np.ndarray
    y: np.ndarray
    fwork: np.ndarray
    w: np.ndarray
    new: np.ndarray
    weigh: tuple


#: ``status = weigh(fp, ip, x, y, fwork)``: the share controller's fuzzy evaluation
WEIGH_SIG = types.int64(types.float64[::1], types.int64[::1], types.float64[::1],
                        types.float64[::1], types.float64[::1])


@njit_signature(WEIGH_SIG)
def fuzzy_weight(fp, ip, x, y, fwork):
    """Evaluate the controller's compiled fuzzy system (:func:`eval_compiled`)."""
    return eval_compiled(fp, ip, x, y, fwork)


@njit_signature(WEIGH_SIG)
def no_weight(fp, ip, x, y, fwork):
    """Stand-in of :func:`fuzzy_weight` for fixed shares (never called)."""
    return 0


def stat_size(window: int) -> int:
    """Length of one local's statistics ring for a window of ``window`` epochs."""
    return _HEAD + _W * window


def share_control(n_local: int, cf=None, codes=(), out_index: int = 0,
                  floor: float = DEFAULT_FLOOR, window: int = 0) -> ShareControl:
    """The loop's :class:`ShareControl`: of compiled fuzzy system ``cf``, or off (None)."""
    on = cf is not None
    return ShareControl(int(on), np.ascontiguousarray(cf.fparams) if on else np.zeros(1),
                        np.ascontiguousarray(cf.iparams) if on else np.zeros(1, np.int64),
                        np.asarray(codes or (0,), np.int64), int(out_index), float(floor),
                        np.zeros((n_local, stat_size(window))),
                        np.zeros(max(cf.n_inputs if on else 1, 1)),
                        np.zeros(max(cf.n_outputs if on else 1, 1)),
                        np.zeros(max(cf.work_size if on else 1, 1)),
                        np.zeros(n_local), np.zeros(n_local),
                        (fuzzy_weight if on else no_weight,))


@nb.njit(cache=True, error_model="numpy")
def push_innovation(st, nis, m, z, S):
    """Add one epoch of a local (NIS, rows ``m``, residual ``z``, ``S``) to its ring ``st``."""
    n = (st.size - _HEAD) // _W
    if n <= 0:
        return
    rr, trs = 0.0, 0.0
    for i in range(m):
        rr += z[i] * z[i]
        trs += S[i, i]
    base = _HEAD + int(st[1]) * _W
    st[base] = nis
    st[base + 1] = m
    st[base + 2] = rr
    st[base + 3] = trs
    st[1] = (st[1] + 1) % n
    if st[0] < n:
        st[0] += 1


@nb.njit(cache=True, error_model="numpy")
def window_stat(st, code):
    """Statistic ``code`` (:data:`STATISTICS`) of a local's ring; 1 if it is empty."""
    num, den = 0.0, 0.0
    for j in range(int(st[0])):
        base = _HEAD + j * _W
        num += st[base + 2 * code]
        den += st[base + 2 * code + 1]
    return num / den if den > 0.0 else 1.0


@nb.njit(cache=True, error_model="numpy")
def floor_shares(w, floor, out):
    """``out = w / sum w``, each at least ``floor``, summing to 1 (``L floor < 1``).

    Water filling: a share that falls below the floor is fixed there and the remaining
    mass is shared again by the others' weights, until none falls below (at most ``L``
    passes).
    """
    L = w.size
    fixed = np.zeros(L, np.bool_)
    mass, wsum = 1.0, 0.0
    for _ in range(L):
        mass, wsum = 1.0, 0.0
        for i in range(L):
            if fixed[i]:
                mass -= floor
            else:
                wsum += w[i]
        changed = False
        for i in range(L):
            if not fixed[i] and mass * w[i] / wsum < floor:
                fixed[i] = True
                changed = True
        if not changed:
            break
    for i in range(L):
        out[i] = floor if fixed[i] else mass * w[i] / wsum


@nb.njit(cache=True, error_model="numpy")
def update_shares(ctl, beta, qd):
    """Set the shares from the locals' statistics; rescale each local's noise ``qd``.

    ``ctl`` is a :class:`ShareControl`, ``beta`` (L,) the shares (written), ``qd`` (L, n)
    the noise densities (``Q_i = Q / beta_i``: rescaled by ``beta_old / beta_new``).
    Returns False (nothing changed) if a weight was invalid.
    """
    fp, ip, codes, out_index, floor = ctl.fp, ctl.ip, ctl.codes, ctl.out_index, ctl.floor
    stat, x, y, fwork, w, new = ctl.stat, ctl.x, ctl.y, ctl.fwork, ctl.w, ctl.new
    weigh = ctl.weigh[0]
    L = beta.size
    for k in range(L):
        for j in range(codes.size):
            x[j] = window_stat(stat[k], codes[j])
        weigh(fp, ip, x, y, fwork)
        w[k] = y[out_index]
        if not (math.isfinite(w[k]) and w[k] > 0.0):
            return False
    floor_shares(w, floor, new)
    for k in range(L):
        ratio = beta[k] / new[k]
        if abs(ratio - 1.0) < MIN_CHANGE:
            continue
        for i in range(qd.shape[1]):
            qd[k, i] *= ratio
        beta[k] = new[k]
    return True

