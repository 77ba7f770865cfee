"""Adaptation policies: the slot between innovation and update.

At each measurement epoch of a sensor, after its residual ``r`` (length ``m``), ``H P- H^T``
and the nominal variances ``R`` are formed and before the update, the sensor's policy runs::

    status = kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx)

* ``fp`` / ``ip`` — the policy's float / int constants (e.g. a compiled fuzzy system);
* ``st`` — its mutable state (innovation windows, running estimates), kept across epochs;
* ``chan`` — channel id per row (see the measurement model's ``channels``);
* outputs: ``out[0]`` multiplies the propagated part of ``P-`` on the states this
  measurement sees directly (alpha^2 of exponential weighting, lambda of fading memory;
  1 = none; see :func:`fuzzynav.filters.kalman.scale_predicted`), ``out[1]`` multiplies the process noise from
  now on (1 = unchanged), ``out[2 + i]`` multiplies ``R[i]`` for this update; ``diag[:4]``
  diagnostic values logged per epoch (alpha, DoM, ...);
* ``ctx`` — the epoch's motion state, nominal variances and data row
  (:mod:`~fuzzynav.filters.adaptation.context`), read by context statistics;
* ``status`` — bit flags: 1 an input of a fuzzy system was clamped, 2 no rule fired.

A policy is one module here defining an :class:`Adapter` subclass and registering it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import types

from fuzzynav.filters.numba_lazy import njit_signature, table_of
from fuzzynav.registry import Registry

ADAPT_SIG = types.int64(types.float64[:], types.int64[:], types.float64[:], types.float64[:],
                        types.float64[:, :], types.float64[:], types.int64[:], types.int64,
                        types.float64[:], types.float64[:], types.float64[:])
#: number of diagnostic values a policy may log per epoch
N_DIAG = 4


@dataclass(frozen=True)
class Bound:
    """An adapter's arrays for one sensor stream, ready for the loop."""

    kernel_id: int
    fp: np.ndarray
    ip: np.ndarray
    state: np.ndarray
    diag_names: tuple


class Adapter:
    """Base class of adaptation policies (immutable configuration).

    Subclasses set ``name``, ``kernel`` (compiled with :data:`ADAPT_SIG`) and
    ``diag_names``, and implement :meth:`arrays`.
    """

    name = "none"
    kernel = None
    diag_names: tuple = ()

    def check_rows(self, model, rows) -> None:
        """Refuse data ``rows`` (of measurement ``model``) the policy cannot run on."""

    def arrays(self, model):
        """``(fp, ip, state)`` for a sensor served by measurement ``model``."""
        return np.zeros(1), np.zeros(1, dtype=np.int64), np.zeros(1)

    def bind(self, model, rows=None) -> Bound:
        """Arrays and kernel id for the loop (``rows``: the sensor's data rows, checked by
        :meth:`check_rows` when given)."""
        if rows is not None:
            self.check_rows(model, rows)
        fp, ip, st = self.arrays(model)
        _, index = kernel_table()
        return Bound(index[self.name], np.ascontiguousarray(fp, dtype=float),
                     np.ascontiguousarray(ip, dtype=np.int64),
                     np.ascontiguousarray(st, dtype=float), tuple(self.diag_names))


@njit_signature(ADAPT_SIG)
def none_kernel(fp, ip, st, r, HPH, R, chan, m, out, diag, ctx):
    out[0] = 1.0
    out[1] = 1.0
    for i in range(m):
        out[2 + i] = 1.0
    return 0


class NoAdaptation(Adapter):
    """The plain EKF: nominal noise, no adaptation."""

    name = "none"
    kernel = none_kernel


ADAPTERS = Registry("adaptation policy", __name__,
                    ("exponential_weighting", "r_scaling", "classical", "strong_tracking",
                     "rq_scaling", "supervisors"))


def register(cls):
    """Class decorator registering an :class:`Adapter` subclass under ``cls.name``."""
    return ADAPTERS.add(cls.name, cls)


register(NoAdaptation)


def get(name: str) -> type:
    """The adapter class registered as ``name``."""
    return ADAPTERS.lookup(name)


def kernel_table(used=None):
    """``(tuple of kernels, {name: index})`` for the filter loop.

    ``used``: the kernel ids the run calls; the other entries are the plain EKF's
    :func:`none_kernel`, so that only the used policies get compiled (the table's numba
    type, and so the loop's cache entry, is the same either way).  None: every policy.
    """
    index = ADAPTERS.index()
    return table_of([ADAPTERS[k].kernel for k in index], used, none_kernel), index
