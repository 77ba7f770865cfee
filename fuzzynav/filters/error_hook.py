"""The error-model hook of the compiled loop: every place where its arithmetic depends on
the definition of the error state.

The loop, the bank's propagation and the output recorder call these functions with the
run's error-model argument ``em``, and nothing else of theirs knows which model runs:

* :func:`system` — the system matrix over an interval (after ``fill_F`` wrote the phi model's);
* :func:`discretize` — ``Phi`` and ``Qd`` of one local;
* :func:`rows` — a measurement model's rows (written for the phi model);
* :func:`single_feedback` — the single filter's estimate before it is fed back;
* :func:`fused_feedback`, :func:`regauge` — the bank's fused estimate and its locals after
  the fused feedback;
* :func:`sigma_velocity` — the velocity sigma of a recorded output.

``em`` is an error-model code (:data:`~fuzzynav.filters.error_st.ERROR_MODELS`) or ``None``.
``None`` is the phi model known when the loop is compiled: the loop's plain copy
(:func:`fuzzynav.filters.loop.loop_for`) passes it, and each hook point then compiles to the
phi model's code alone — numba picks the implementation by the type of ``em``
(:func:`numba.extending.overload`), so the ST kernels are not even typed for that copy.  An
integer code selects at run time; the phi branch runs the same operations as the ``None``
implementation, so both copies give the same bits.  A new error model adds its branch to each
point here (``docs/architecture.md``, "Adding an error-model variant").
"""
from __future__ import annotations

import functools
import math

from numba.core import types
from numba.extending import overload

from fuzzynav.filters.error_model import discretize_tail
from fuzzynav.filters.error_st import EM_ST, discretize_dense, st_fused, st_measurement, \
    st_process_noise, st_regauge, st_reset, st_system, st_to_phi, st_velocity_variance
from fuzzynav.filters.layout import X_VEL

__all__ = ["system", "discretize", "rows", "single_feedback", "fused_feedback", "regauge",
           "sigma_velocity"]


def _hook_point(phi_impl):
    """Make ``phi_impl`` (the phi model's code, and the hook point's signature) a hook point
    whose code for an integer ``em`` is the decorated function.

    Both implementations are inlined into the caller (``inline='always'``: a hook point adds
    no call), compiled with the numpy error model like every kernel of the loop.
    """
    def register(coded_impl):
        @functools.wraps(phi_impl)  # numba checks the implementations against this signature
        def typer(em, *args):
            return phi_impl if isinstance(em, types.NoneType) else coded_impl

        overload(phi_impl, inline="always", jit_options={"error_model": "numpy"})(typer)
        return phi_impl
    return register


def system(em, F, nav):
    """Map the phi model's system matrix ``F`` to the error model's, in place (the phi
    model: nothing to do)."""


@_hook_point(system)
def _system(em, F, nav):
    if em == EM_ST:
        st_system(F, nav)


def discretize(em, F, q_diag, dt, Phi, Qd, work, tail, Qc, nav):
    """``Phi``, ``Qd`` of one local over ``dt`` from its noise densities ``q_diag``; ``tail``
    is the first row from which ``F`` is diagonal, ``Qc`` a scratch for a full density."""
    discretize_tail(F, q_diag, dt, Phi, Qd, work, tail)


@_hook_point(discretize)
def _discretize(em, F, q_diag, dt, Phi, Qd, work, tail, Qc, nav):
    if em == EM_ST:  # A Q A^T is no longer diagonal
        st_process_noise(Qc, q_diag, nav)
        discretize_dense(F, Qc, dt, Phi, Qd, work)
    else:
        discretize_tail(F, q_diag, dt, Phi, Qd, work, tail)


def rows(em, H, m, nav):
    """Turn the first ``m`` measurement rows ``H`` (written for the phi model by every
    measurement model) into the error model's rows."""


@_hook_point(rows)
def _rows(em, H, m, nav):
    if em == EM_ST:
        st_measurement(H, m, nav)


def single_feedback(em, P, x, nav):
    """Turn the single filter's estimate ``x`` into the phi-model correction that is fed
    back, and re-express ``P`` about the corrected state."""


@_hook_point(single_feedback)
def _single_feedback(em, P, x, nav):
    if em == EM_ST:
        st_to_phi(x, nav)
        st_reset(P, x)


def fused_feedback(em, xg, Pg, nav, xphi):
    """The phi-model correction the bank feeds back for its fused estimate ``xg`` (``xg``
    itself, or ``xphi`` filled from it, with ``Pg`` re-expressed)."""
    return xg


@_hook_point(fused_feedback)
def _fused_feedback(em, xg, Pg, nav, xphi):
    if em == EM_ST:  # the bank fuses ST states and feeds back their phi form
        return st_fused(xg, Pg, nav, xphi)
    return xg


def regauge(em, P, X, fb, reset):
    """Re-express the locals ``P`` (L, n, n), ``X`` (L, n) of a bank about the state
    corrected by ``fb`` (in reset mode they restarted from the fused solution: nothing to
    do)."""


@_hook_point(regauge)
def _regauge(em, P, X, fb, reset):
    if em == EM_ST and not reset:
        st_regauge(P, X, fb)


def sigma_velocity(em, row, P, nav):
    """Overwrite ``row``'s velocity entries with the sigma of the velocity error itself,
    where the error model's velocity state is something else."""


@_hook_point(sigma_velocity)
def _sigma_velocity(em, row, P, nav):
    if em == EM_ST:
        for i in range(3):
            row[X_VEL + i] = math.sqrt(max(st_velocity_variance(P, nav, i), 0.0))
