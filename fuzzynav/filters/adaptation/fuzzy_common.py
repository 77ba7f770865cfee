"""Binding a rule file to a sensor stream: shared by the fuzzy adaptation policies.

Array layout of a fuzzy policy (all numba-friendly flat arrays):

* ``ip`` — header (:data:`IP_HEADER` ints), then ``(statistic code, channel id)`` per fuzzy
  input (for ``fix_type`` / ``n_sat`` the data-row column instead of a channel), then the compiled system's ``iparams`` (starting at ``ip[IP_FIS]``);
* ``fp`` — ``fp[0] = k`` the number of policy floats, ``fp[1:1+k]`` those floats, then the
  compiled system's ``fparams``;
* ``st`` — the innovation window, then ``x`` (inputs), ``y`` (outputs), the system's work
  buffer and :data:`N_SCALARS` policy scalars at the end.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from fuzzynav.filters.adaptation import context, window
from fuzzynav.fuzzy.kernels import eval_compiled

__all__ = ["IP_HEADER", "N_WINDOW_STATS", "N_SCALARS", "pack", "evaluate", "scalars", "log_inputs"]

IP_NIN, IP_NOUT, IP_NCHAN, IP_WIN, IP_OUT, IP_FIS = 0, 1, 2, 3, 4, 5
IP_HEADER = 8
#: statistic codes below this come from the innovation window, the others from ``ctx``
N_WINDOW_STATS = len(window.STATISTICS)
N_SCALARS = 4


def pack(fis, source, binding, model, role: str, floats=()):
    """``(fp, ip, st)`` of a fuzzy policy for a sensor served by ``model``.

    ``binding`` is the system's parsed :class:`~fuzzynav.filters.adaptation.binding.Binding`;
    its channels are checked against ``model`` (an error names ``source``).
    """
    binding.check_channels(model, source)
    cf = fis.compile()
    table = [(code, binding.column(b, model, source) if b.statistic in context.QUALITY
              else model.channel_index(b.channel))
             for code, b in zip(binding.statistic_codes(), binding.inputs)]
    n_win, n_ch = binding.window, len(model.channels)
    head = np.zeros(IP_HEADER, dtype=np.int64)
    head[[IP_NIN, IP_NOUT, IP_NCHAN, IP_WIN]] = cf.n_inputs, cf.n_outputs, n_ch, n_win
    head[IP_OUT] = binding.output_index(fis, role)
    head[IP_FIS] = IP_HEADER + 2 * len(table)
    ip = np.concatenate([head, np.array(table, dtype=np.int64).ravel(), cf.iparams])
    fp = np.concatenate([[float(len(floats))], np.asarray(floats, float), cf.fparams])
    st = np.zeros(window.window_size(n_win, n_ch) + cf.n_inputs + cf.n_outputs + cf.work_size
                  + N_SCALARS)
    return fp, ip, st


# inlined into each policy kernel: the call and its nine array arguments cost ~0.2 us per
# epoch, a fifth of the adapter (benchmarks: alternating A/B of the adapter call)
@nb.njit(cache=True, inline="always", error_model="numpy")
def evaluate(fp, ip, st, r, HPH, R, chan, m, ctx):
    """Push the window, form the bound statistics (innovation ones from the window, the
    others from the epoch context ``ctx``), evaluate the system.

    Returns ``(status, x, y)`` with ``x``/``y`` views into ``st``.
    """
    n_in, n_out, n_ch, n_win = ip[IP_NIN], ip[IP_NOUT], ip[IP_NCHAN], ip[IP_WIN]
    w = 2 + n_win * (n_ch + 1)
    window.push(st, 0, n_win, n_ch, r, chan, m)
    x = st[w:w + n_in]
    y = st[w + n_in:w + n_in + n_out]
    work = st[w + n_in + n_out:st.size - N_SCALARS]
    for j in range(n_in):
        kind, c = ip[IP_HEADER + 2 * j], ip[IP_HEADER + 2 * j + 1]
        if kind >= N_WINDOW_STATS:
            x[j] = context.statistic(kind, ctx, chan, m, c)
        else:
            x[j] = window.statistic_of(kind, st, 0, n_win, n_ch, HPH, R, chan, m, c, r)
    status = eval_compiled(fp[1 + int(fp[0]):], ip[ip[IP_FIS]:], x, y, work)
    return status, x, y


@nb.njit(cache=True, error_model="numpy")
def scalars(st):
    """The policy's persistent scalars (a view of the last entries of ``st``)."""
    return st[st.size - N_SCALARS:]


@nb.njit(cache=True, error_model="numpy")
def log_inputs(diag, first, x):
    """Write the fuzzy inputs into ``diag`` from index ``first`` (as many as fit)."""
    for j in range(min(x.size, diag.size - first)):
        diag[first + j] = x[j]
