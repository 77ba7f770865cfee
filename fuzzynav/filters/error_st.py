"""The state-transformation ("ST", "modified") error model: kernels that map the phi model.

The ST-EKF (Wang, Wu et al., GPS Solutions 2018; Scherzinger & Reid's "modified" model)
keeps the attitude error phi of :mod:`fuzzynav.filters.error_model` but carries the velocity
error as ``u = dv - [v x] phi`` (``v`` the computed ENU velocity), i.e. ``x_ST = A x`` with
``A = I`` except ``A[vel, att] = -[v x]`` and ``A^-1[vel, att] = +[v x]``.  Every piece is the
phi-model piece mapped through ``A`` (derivation in docs/navigation.md):

* system matrix ``F_ST = A F A^-1 + dA/dt A^-1``; the measured specific force cancels and the
  velocity-attitude block is ``-[g x] - [v x][omega_ie x]`` (:func:`st_system`);
* process noise ``Q_ST = A Q A^T`` — no longer diagonal, so it is discretised densely
  (:func:`st_process_noise`, :func:`discretize_dense`);
* measurement rows ``H_ST = H A^-1``: attitude columns gain ``H_vel [v x]``
  (:func:`st_measurement`), so the measurement models keep writing phi-model rows;
* feedback ``dv = u + [v x] phi`` before the velocity is corrected (:func:`st_to_phi`),
  and ``P`` re-expressed about the corrected velocity (:func:`st_reset`);
* covariances ``P_ST = A P A^T`` (:func:`st_covariance`, for P0).

The loop selects a model by the integer codes of :data:`ERROR_MODELS`, so one compiled loop
serves both (:func:`fuzzynav.filters.loop.run_loop`; its plain copy, for single phi-model
filters, leaves the ST branches out).
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.filters.error_model import transition
from fuzzynav.filters.kalman import sparse_left_mul
from fuzzynav.filters.layout import X_ATT, X_VEL
from fuzzynav.nav.earth import OMEGA_IE, gravity_nb
from fuzzynav.nav.state_layout import NAV_H, NAV_LAT, NAV_VEL

__all__ = ["ERROR_MODELS", "error_model_code", "st_system", "st_process_noise", "discretize_dense",
           "st_measurement", "st_to_phi", "st_reset", "st_velocity_variance", "st_covariance",
           "st_fused", "st_regauge"]

EM_PHI, EM_ST = 0, 1
#: error-model name -> code passed into the compiled loop
ERROR_MODELS = {"phi": EM_PHI, "st": EM_ST}


def error_model_code(name: str) -> int:
    """The loop's code of error model ``name`` (``"phi"`` or ``"st"``)."""
    try:
        return ERROR_MODELS[name]
    except (KeyError, TypeError):
        raise InputFileError(None, "error_model",
                             f"must be one of {', '.join(ERROR_MODELS)}, got {name!r}") from None


@nb.njit(cache=True, error_model="numpy")
def _vel_skew(nav, S):
    """``S = [v x]`` of the computed velocity."""
    ve, vn, vu = nav[NAV_VEL], nav[NAV_VEL + 1], nav[NAV_VEL + 2]
    S[0, 0], S[0, 1], S[0, 2] = 0.0, -vu, vn
    S[1, 0], S[1, 1], S[1, 2] = vu, 0.0, -ve
    S[2, 0], S[2, 1], S[2, 2] = -vn, ve, 0.0


@nb.njit(cache=True, error_model="numpy")
def st_system(F, nav):
    """Map the phi-model ``F`` (from ``fill_F``) to the ST model in place.

    ``A F A^-1`` moves every coupling (position, sensor blocks); the velocity-attitude block
    is then replaced by its closed form ``-[g x] - [v x][omega_ie x]``, in which the
    specific-force term of ``F`` and the ``-[dv/dt x]`` of ``dA/dt`` have cancelled.
    """
    n = F.shape[0]
    S = np.empty((3, 3))
    _vel_skew(nav, S)
    for j in range(n):  # rows: (A F)[vel] = F[vel] - S F[att]
        a0, a1, a2 = F[X_ATT, j], F[X_ATT + 1, j], F[X_ATT + 2, j]
        for i in range(3):
            F[X_VEL + i, j] -= S[i, 0] * a0 + S[i, 1] * a1 + S[i, 2] * a2
    for i in range(n):  # columns: (A F A^-1)[:, att] = (A F)[:, att] + (A F)[:, vel] S
        b0, b1, b2 = F[i, X_VEL], F[i, X_VEL + 1], F[i, X_VEL + 2]
        for j in range(3):
            F[i, X_ATT + j] += b0 * S[0, j] + b1 * S[1, j] + b2 * S[2, j]
    lat = nav[NAV_LAT]
    g = gravity_nb(lat, nav[NAV_H])
    wn, wu = OMEGA_IE * math.cos(lat), OMEGA_IE * math.sin(lat)
    # [omega_ie x] with omega_ie = (0, wn, wu); g_n = (0, 0, -g) so -[g_n x] = [[0,-g,0],[g,0,0],0]
    W = np.array([[0.0, -wu, wn], [wu, 0.0, 0.0], [-wn, 0.0, 0.0]])
    for i in range(3):
        for j in range(3):
            F[X_VEL + i, X_ATT + j] = -(S[i, 0] * W[0, j] + S[i, 1] * W[1, j]
                                        + S[i, 2] * W[2, j])
    F[X_VEL, X_ATT + 1] -= g
    F[X_VEL + 1, X_ATT] += g


@nb.njit(cache=True, error_model="numpy")
def st_process_noise(Qc, q_diag, nav):
    """``Qc = A diag(q) A^T``: the attitude noise also drives ``u`` through ``-[v x]``."""
    n = Qc.shape[0]
    S = np.empty((3, 3))
    _vel_skew(nav, S)
    Qc[:, :] = 0.0
    for i in range(n):
        Qc[i, i] = q_diag[i]
    for i in range(3):
        for j in range(3):
            c = -S[i, j] * q_diag[X_ATT + j]
            Qc[X_VEL + i, X_ATT + j] = c
            Qc[X_ATT + j, X_VEL + i] = c
            acc = 0.0
            for k in range(3):
                acc += S[i, k] * q_diag[X_ATT + k] * S[j, k]
            Qc[X_VEL + i, X_VEL + j] += acc


@nb.njit(cache=True, error_model="numpy")
def discretize_dense(F, Qc, dt, Phi, Qd, work):
    """As :func:`~fuzzynav.filters.error_model.discretize`, for a full noise density ``Qc``.

    ``Qd = Qc dt + (F Qc + Qc F^T) dt^2 / 2 + F Qc F^T dt^3 / 3``.
    """
    n = F.shape[0]
    transition(F, dt, Phi, work)
    sparse_left_mul(F, Qc, work)  # work = F Qc
    h2, h3 = 0.5 * dt * dt, dt * dt * dt / 3.0
    for i in range(n):
        for j in range(i, n):
            acc = 0.0
            for k in range(n):
                f = F[j, k]
                if f != 0.0:
                    acc += work[i, k] * f
            s = Qc[i, j] * dt + (work[i, j] + work[j, i]) * h2 + acc * h3
            Qd[i, j] = s
            Qd[j, i] = s


@nb.njit(cache=True, error_model="numpy")
def st_measurement(H, m, nav):
    """``H <- H A^-1`` for the first ``m`` rows: attitude columns gain ``H[:, vel] [v x]``."""
    S = np.empty((3, 3))
    _vel_skew(nav, S)
    for r in range(m):
        b0, b1, b2 = H[r, X_VEL], H[r, X_VEL + 1], H[r, X_VEL + 2]
        if b0 != 0.0 or b1 != 0.0 or b2 != 0.0:
            for j in range(3):
                H[r, X_ATT + j] += b0 * S[0, j] + b1 * S[1, j] + b2 * S[2, j]


@nb.njit(cache=True, error_model="numpy")
def st_to_phi(x, nav):
    """Turn an ST estimate into the phi model's in place: ``dv = u + [v x] phi``."""
    S = np.empty((3, 3))
    _vel_skew(nav, S)
    p0, p1, p2 = x[X_ATT], x[X_ATT + 1], x[X_ATT + 2]
    for i in range(3):
        x[X_VEL + i] += S[i, 0] * p0 + S[i, 1] * p1 + S[i, 2] * p2


@nb.njit(cache=True, error_model="numpy")
def st_reset(P, x):
    """Re-express ``P_ST`` about the corrected velocity (``x``: the phi-model correction).

    ``u`` is defined with the computed velocity, which the feedback moves by ``-dv``:
    ``u_new = u_old + [dv x] phi`` to first order, so ``P <- G P G^T`` with
    ``G = I + [dv x]`` in the velocity-attitude block.  Without it, a velocity correction
    under a large attitude uncertainty reads as heading information the data do not hold.
    """
    n = P.shape[0]
    d0, d1, d2 = x[X_VEL], x[X_VEL + 1], x[X_VEL + 2]
    D = np.array([[0.0, -d2, d1], [d2, 0.0, -d0], [-d1, d0, 0.0]])
    for j in range(n):  # rows
        a0, a1, a2 = P[X_ATT, j], P[X_ATT + 1, j], P[X_ATT + 2, j]
        for i in range(3):
            P[X_VEL + i, j] += D[i, 0] * a0 + D[i, 1] * a1 + D[i, 2] * a2
    for i in range(n):  # columns
        a0, a1, a2 = P[i, X_ATT], P[i, X_ATT + 1], P[i, X_ATT + 2]
        for j in range(3):
            P[i, X_VEL + j] += D[j, 0] * a0 + D[j, 1] * a1 + D[j, 2] * a2


@nb.njit(cache=True, error_model="numpy")
def st_velocity_variance(P, nav, i):
    """Variance of the phi-model velocity error ``dv_i = u_i + ([v x] phi)_i`` from ``P_ST``."""
    S = np.empty((3, 3))
    _vel_skew(nav, S)
    v = P[X_VEL + i, X_VEL + i]
    for k in range(3):
        v += 2.0 * S[i, k] * P[X_ATT + k, X_VEL + i]
        for m in range(3):
            v += S[i, k] * S[i, m] * P[X_ATT + k, X_ATT + m]
    return v


def st_covariance(P, vel_n) -> np.ndarray:
    """``A P A^T``: a phi-model covariance in ST coordinates at velocity ``vel_n`` (ENU)."""
    P = np.asarray(P, float)
    ve, vn, vu = np.asarray(vel_n, float)
    A = np.eye(P.shape[0])
    A[X_VEL:X_VEL + 3, X_ATT:X_ATT + 3] = -np.array([[0.0, -vu, vn], [vu, 0.0, -ve],
                                                      [-vn, ve, 0.0]])
    return A @ P @ A.T


@nb.njit(cache=True, error_model="numpy")
def st_fused(xg, Pg, nav, xphi):
    """The master's fused ST estimate as the phi-model correction ``xphi`` it feeds back, and
    ``Pg`` re-expressed about the corrected velocity (:func:`st_reset`); returns ``xphi``.

    Fusion is linear in the ST states (every local's ``x_i = A x_i,phi`` with the one ``A`` of
    the shared ``nav``, so ``sum P_i^-1 x_i`` is ``A^-T`` times the phi-model sum): the bank
    fuses ST states as they are and converts only what it feeds back, as the single filter
    does with its own estimate.
    """
    for i in range(xg.size):
        xphi[i] = xg[i]
    st_to_phi(xphi, nav)
    st_reset(Pg, xphi)
    return xphi


@nb.njit(cache=True, error_model="numpy")
def st_regauge(P3, X, xphi):
    """Re-express every local of a no-reset bank about the corrected velocity.

    After the feedback of ``xphi`` (the fused correction) and the shift ``x_i -= x_g``, a
    local's velocity state ``u_i = dv_i - [v x] phi_i`` is still defined with the old
    velocity; with the new one (``v - dv_g``) it is ``u_i + [dv_g x] (phi_i - phi_g)``, i.e.
    ``x_i <- G x_i`` and ``P_i <- G P_i G^T`` with ``G = I + [dv_g x]`` in the
    velocity-attitude block, as :func:`st_reset` does for the single filter's ``P``.
    """
    d0, d1, d2 = xphi[X_VEL], xphi[X_VEL + 1], xphi[X_VEL + 2]
    for k in range(X.shape[0]):
        x = X[k]
        p0, p1, p2 = x[X_ATT], x[X_ATT + 1], x[X_ATT + 2]
        x[X_VEL] += -d2 * p1 + d1 * p2
        x[X_VEL + 1] += d2 * p0 - d0 * p2
        x[X_VEL + 2] += -d1 * p0 + d0 * p1
        st_reset(P3[k], xphi)
