"""Binding a rule file to a sensor stream: shared by the fuzzy adaptation policies.

Array layout of a fuzzy policy (all numba-friendly flat arrays):

* ``ip`` — header (:data:`IP_HEADER` ints), then ``(statistic code, channel id)`` per fuzzy
  input, then the compiled system's ``iparams`` (starting at ``ip[IP_FIS]``);
* ``fp`` — ``fp[0] = k`` the number of policy floats, ``fp[1:1+k]`` those floats, then the
  compiled system's ``fparams``;
* ``st`` — the innovation window, then ``x`` (inputs), ``y`` (outputs), the system's work
  buffer and :data:`N_SCALARS` policy scalars at the end.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.filters.adaptation import window
from fuzzynav.fuzzy.kernels import eval_compiled

IP_NIN, IP_NOUT, IP_NCHAN, IP_WIN, IP_OUT, IP_FIS = 0, 1, 2, 3, 4, 5
IP_HEADER = 8
N_SCALARS = 4


def _err(source, where, what):
    return InputFileError(source, f"$.binding.{where}", what)


def check_binding(fis, source, adapter_name: str) -> dict:
    """The rule file's binding, checked to be for ``adapter_name``."""
    b = dict(fis.binding or {})
    if b.get("adapter") != adapter_name:
        raise _err(source, "adapter", f"this policy needs adapter {adapter_name!r}; "
                                      f"the rule file is bound to {b.get('adapter')!r}")
    inputs = b.get("inputs")
    if not isinstance(inputs, dict):
        raise _err(source, "inputs", "must map every fuzzy input to a statistic and a channel")
    for name in fis.input_names:
        spec = inputs.get(name)
        if not isinstance(spec, dict):
            raise _err(source, f"inputs.{name}", "missing: say which statistic feeds this input")
        if spec.get("statistic") not in window.STATISTICS:
            raise _err(source, f"inputs.{name}.statistic",
                       f"unknown statistic {spec.get('statistic')!r}; "
                       f"known: {', '.join(window.STATISTICS)}")
    n = b.get("window", 10)
    if not isinstance(n, int) or isinstance(n, bool) or not 1 <= n <= 10000:
        raise _err(source, "window", f"must be an integer number of epochs in 1..10000, got {n!r}")
    return b


def channels_of(fis) -> tuple:
    """The measurement channels a rule file's binding reads (``all`` excluded)."""
    return tuple(sorted({spec.get("channel", "all") for spec in (fis.binding or {})
                         .get("inputs", {}).values()} - {"all"}))


def output_index(fis, source, binding, role: str) -> int:
    """Index of the fuzzy output that drives ``role`` (e.g. ``alpha``, ``r_scale``)."""
    for name, target in (binding.get("outputs") or {}).items():
        if target == role:
            if name not in fis.output_names:
                raise _err(source, f"outputs.{name}", "names no output of the fuzzy system")
            return fis.output_names.index(name)
    raise _err(source, "outputs", f"no output is bound to {role!r}")


def pack(fis, source, binding, model, role: str, floats=()):
    """``(fp, ip, st)`` of a fuzzy policy for a sensor served by ``model``."""
    cf = fis.compile()
    table = [(window.STATISTICS[binding["inputs"][nm]["statistic"]],
              model.channel_index(binding["inputs"][nm].get("channel", "all")))
             for nm in fis.input_names]
    n_win, n_ch = int(binding.get("window", 10)), len(model.channels)
    head = np.zeros(IP_HEADER, dtype=np.int64)
    head[[IP_NIN, IP_NOUT, IP_NCHAN, IP_WIN]] = cf.n_inputs, cf.n_outputs, n_ch, n_win
    head[IP_OUT] = output_index(fis, source, binding, role)
    head[IP_FIS] = IP_HEADER + 2 * len(table)
    ip = np.concatenate([head, np.array(table, dtype=np.int64).ravel(), cf.iparams])
    fp = np.concatenate([[float(len(floats))], np.asarray(floats, float), cf.fparams])
    st = np.zeros(window.window_size(n_win, n_ch) + cf.n_inputs + cf.n_outputs + cf.work_size
                  + N_SCALARS)
    return fp, ip, st


@nb.njit(cache=True)
def evaluate(fp, ip, st, r, HPH, R, chan, m):
    """Push the window, form the bound statistics, evaluate the system.

    Returns ``(status, x, y)`` with ``x``/``y`` views into ``st``.
    """
    n_in, n_out, n_ch, n_win = ip[IP_NIN], ip[IP_NOUT], ip[IP_NCHAN], ip[IP_WIN]
    w = 2 + n_win * (n_ch + 1)
    window.push(st, 0, n_win, n_ch, r, chan, m)
    x = st[w:w + n_in]
    y = st[w + n_in:w + n_in + n_out]
    work = st[w + n_in + n_out:st.size - N_SCALARS]
    for j in range(n_in):
        x[j] = window.statistic(ip[IP_HEADER + 2 * j], st, 0, n_win, n_ch, HPH, R, chan, m,
                                ip[IP_HEADER + 2 * j + 1])
    status = eval_compiled(fp[1 + int(fp[0]):], ip[ip[IP_FIS]:], x, y, work)
    return status, x, y


@nb.njit(cache=True)
def scalars(st):
    """The policy's persistent scalars (a view of the last entries of ``st``)."""
    return st[st.size - N_SCALARS:]


@nb.njit(cache=True)
def log_inputs(diag, first, x):
    """Write the fuzzy inputs into ``diag`` from index ``first`` (as many as fit)."""
    for j in range(min(x.size, diag.size - first)):
        diag[first + j] = x[j]
