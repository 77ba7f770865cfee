"""Windowed innovation statistics shared by adaptation policies (numba).

A window keeps, for the last ``N`` epochs, the sum of squared residuals of each channel
and of all rows together (column ``C``).  Layout inside a policy's state array ``st``
starting at ``off``::

    st[off]                      number of epochs stored (<= N)
    st[off + 1]                  index of the next slot
    st[off + 2 : off + 2 + N (C + 1)]   ring buffer, one row of C + 1 sums per epoch

Statistics of a channel ``c`` (``c = -1`` for all rows) at the current epoch:

* ``trace_actual`` — window mean of the channel's sum of squared residuals, the trace of
  the measured innovation covariance ``C_r = mean(r r^T)``;
* ``trace_theory`` — the channel's trace of ``P_z = H P- H^T + R`` now;
* ``dom`` (relative trace) — ``(tr P_z - tr C_r) / tr P_z``: 0 when the filter is
  consistent, negative when innovations are larger than the model says, at most 1;
* ``ror`` — ``tr C_r / tr P_z`` (paper 002's ratio of residuals);
* ``nis`` — this epoch's mean ``r_i^2 / (P_z)_ii`` over the channel's rows;
* ``trend`` — (newer half - older half of the window's squared-residual sums) / ``tr P_z``.
"""
from __future__ import annotations

import numba as nb

__all__ = ["window_size", "push", "trace_actual", "trace_theory", "nis_now", "trend",
           "statistic_of", "statistic", "STATISTICS", "DOM_NORMALISATIONS"]

# push, trace_* and statistic* are inline="always": called once per epoch and statistic,
# their call overhead cost more than their few additions (same bits either way).


def window_size(n: int, n_channels: int) -> int:
    """Length of the state slice a window needs."""
    return 2 + n * (n_channels + 1)


@nb.njit(cache=True, inline="always", error_model="numpy")
def push(st, off, n, n_channels, r, chan, m):
    """Add this epoch's per-channel sums of squared residuals to the window."""
    w = n_channels + 1
    base = off + 2 + int(st[off + 1]) * w
    for c in range(w):
        st[base + c] = 0.0
    for i in range(m):
        rr = r[i] * r[i]
        st[base + chan[i]] += rr
        st[base + n_channels] += rr
    st[off + 1] = (st[off + 1] + 1) % n
    if st[off] < n:
        st[off] += 1


@nb.njit(cache=True, inline="always", error_model="numpy")
def trace_actual(st, off, n, n_channels, c):
    """Window mean of the channel's squared-residual sum (``c = -1``: all rows)."""
    w = n_channels + 1
    col = n_channels if c < 0 else c
    k = int(st[off])
    if k == 0:
        return 0.0
    s = 0.0
    for j in range(k):
        s += st[off + 2 + j * w + col]
    return s / k


@nb.njit(cache=True, inline="always", error_model="numpy")
def trace_theory(HPH, R, chan, m, c):
    """The channel's trace of ``H P- H^T + R`` (``c = -1``: all rows)."""
    s = 0.0
    for i in range(m):
        if c < 0 or chan[i] == c:
            s += HPH[i, i] + R[i]
    return s


@nb.njit(cache=True, error_model="numpy")
def nis_now(r, HPH, R, chan, m, c):
    """This epoch's mean normalised innovation square ``r_i^2 / (H P- H^T + R)_ii`` over
    the channel's rows (``c = -1``: all rows); 1 on average when the filter is consistent."""
    s, k = 0.0, 0
    for i in range(m):
        if c < 0 or chan[i] == c:
            s += r[i] * r[i] / (HPH[i, i] + R[i])
            k += 1
    return s / k if k > 0 else float("nan")


@nb.njit(cache=True, error_model="numpy")
def trend(st, off, n, n_channels, c, th):
    """Innovation-magnitude trend: (mean squared-residual sum of the newer half of the
    window - that of the older half) / ``th``; > 0 when innovations grow."""
    w = n_channels + 1
    col = n_channels if c < 0 else c
    k = int(st[off])
    if k < 2:
        return 0.0
    nxt = int(st[off + 1])
    half = k // 2
    old, new = 0.0, 0.0
    for j in range(k):  # j = 0 is the oldest stored epoch
        slot = (nxt - k + j) % n
        v = st[off + 2 + slot * w + col]
        if j < half:
            old += v
        elif j >= k - half:
            new += v
    return (new - old) / half / th


@nb.njit(cache=True, inline="always", error_model="numpy")
def statistic_of(kind, st, off, n, n_channels, HPH, R, chan, m, c, r):
    """Any statistic ``kind`` (0 dom, 1 ror, 2 nis, 3 trend) of channel ``c``, given this
    epoch's residuals ``r``; NaN if the channel is absent."""
    if kind == 2:
        th = trace_theory(HPH, R, chan, m, c)
        return nis_now(r, HPH, R, chan, m, c) if th > 0.0 else float("nan")
    if kind == 3:
        th = trace_theory(HPH, R, chan, m, c)
        return trend(st, off, n, n_channels, c, th) if th > 0.0 else float("nan")
    return statistic(kind, st, off, n, n_channels, HPH, R, chan, m, c)


@nb.njit(cache=True, inline="always", error_model="numpy")
def statistic(kind, st, off, n, n_channels, HPH, R, chan, m, c):
    """Statistic ``kind`` (0 = dom, 1 = ror) of channel ``c``; NaN if the channel is absent."""
    th = trace_theory(HPH, R, chan, m, c)
    if th <= 0.0:
        return float("nan")
    act = trace_actual(st, off, n, n_channels, c)
    if kind == 0:
        return (th - act) / th
    return act / th


#: statistic names as written in rule-file bindings -> kernel code of :func:`statistic`:
#: ``nis`` is this epoch's mean NIS of the channel's rows (per channel, or ``all`` for the
#: total), ``trend`` the growth of the windowed squared innovations relative to ``tr P_z``
STATISTICS = {"dom": 0, "ror": 1, "nis": 2, "trend": 3}
#: how ``dom`` is normalised (``binding.normalisation``) -> kernel code: only the relative
#: trace per channel, ``(tr P_z - tr C_r) / tr P_z``, is implemented
DOM_NORMALISATIONS = {"relative-trace": 0}
