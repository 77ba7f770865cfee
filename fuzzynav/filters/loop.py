"""The closed-loop error-state filter as one compiled loop over plain arrays.

Per IMU sample: bias-corrected increments -> strapdown step -> accumulate the mean attitude and
specific force.  The covariance is propagated over the accumulated interval (with the mean
``F``) whenever a measurement is due or ``max_prop_dt`` has passed — the error model varies
slowly, so propagating every sample would cost ~100x more for no accuracy (see
docs/benchmarks.md).  Measurement epochs go through the sensor's measurement model, its
adaptation policy, optional chi-square gating, the Joseph update and closed-loop feedback.

Memory is independent of the run length apart from the requested outputs (every
``out_stride`` samples) and the per-epoch event log.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from fuzzynav.filters import kalman
from fuzzynav.filters.error_model import block_end, discretize, fill_F
from fuzzynav.filters.error_st import EM_ST, discretize_dense, st_measurement, \
    st_process_noise, st_reset, st_system, st_to_phi, st_velocity_variance
from fuzzynav.filters.layout import COUPLE_ACCEL, COUPLE_GYRO, N_CORE, X_ATT, X_POS, X_VEL
from fuzzynav.nav.earth import radii_nb
from fuzzynav.nav.layout import NAV_H, NAV_LAT, NAV_LON, NAV_Q, NAV_SIZE, NAV_VEL, PREV_LLA, \
    PREV_SIZE, PREV_VEL
from fuzzynav.nav.strapdown import init_prev, mech_step, quat_mul, quat_to_dcm_into, rv2q, set_quat



class Imu(NamedTuple):
    """IMU increments: ``dth``, ``dv`` (N, 3) [rad, m/s] and ``time_s`` (N+1,)."""

    dth: np.ndarray
    dv: np.ndarray
    time_s: np.ndarray


class Start(NamedTuple):
    """Initial state: ``nav0`` (nav layout), sensor states ``xs0``, covariance ``P0``."""

    nav0: np.ndarray
    xs0: np.ndarray
    P0: np.ndarray


class Model(NamedTuple):
    """Error model: ``q_diag`` per state, the sensor blocks' start, coupling and 1/tau, and
    the error-model code (:data:`fuzzynav.filters.error_st.ERROR_MODELS`)."""

    q_diag: np.ndarray
    blk_start: np.ndarray
    blk_kind: np.ndarray
    blk_inv_tau: np.ndarray
    error_model: int


class Events(NamedTuple):
    """Measurement epochs in time order: time, sensor index, data row."""

    t: np.ndarray
    s: np.ndarray
    data: np.ndarray


class Sensors(NamedTuple):
    """Per sensor: measurement-kernel id and constants, adapter id and its flat arrays
    (``afp[afp_off[s]:afp_off[s + 1]]`` ...), chi-square gate per row count."""

    meas: np.ndarray
    mpar: np.ndarray
    adapt: np.ndarray
    afp: np.ndarray
    afp_off: np.ndarray
    aip: np.ndarray
    aip_off: np.ndarray
    ast: np.ndarray
    ast_off: np.ndarray
    gate: np.ndarray


class Settings(NamedTuple):
    """Longest propagation interval [s] and the output stride [samples]."""

    max_prop_dt: float
    out_stride: int


class Outputs(NamedTuple):
    """Recorded solution (every ``out_stride`` samples): time, nav, sensor states, sigma."""

    t: np.ndarray
    nav: np.ndarray
    xs: np.ndarray
    sig: np.ndarray


class EventOutputs(NamedTuple):
    """Per event: residual, S diagonal, NIS, flag, adaptation diagnostics."""

    r: np.ndarray
    S: np.ndarray
    nis: np.ndarray
    flag: np.ndarray
    diag: np.ndarray


# event flags
EV_PENDING, EV_ACCEPTED, EV_GATED, EV_EMPTY, EV_BAD_S, EV_BEFORE_START = 0, 1, 2, 3, 4, 5
# loop status
ST_OK, ST_COVARIANCE = 0, 1


@nb.njit(cache=True)
def _feedback(nav, prev, xs, x):
    """Apply the error-state estimate to the navigation and sensor estimates (then x = 0)."""
    a0, a1, a2, a3 = rv2q(x[X_ATT], x[X_ATT + 1], x[X_ATT + 2])
    q0, q1, q2, q3 = quat_mul(a0, a1, a2, a3, nav[NAV_Q], nav[NAV_Q + 1], nav[NAV_Q + 2],
                              nav[NAV_Q + 3])
    qn = 1.0 / math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    set_quat(nav, q0 * qn, q1 * qn, q2 * qn, q3 * qn)
    rm, rn = radii_nb(nav[NAV_LAT])
    de, dn, du = x[X_POS], x[X_POS + 1], x[X_POS + 2]  # ENU metres
    dlat = dn / (rm + nav[NAV_H])
    dlon = de / ((rn + nav[NAV_H]) * math.cos(nav[NAV_LAT]))
    for i in range(3):
        nav[NAV_VEL + i] -= x[X_VEL + i]
        prev[PREV_VEL + i] -= x[X_VEL + i]  # keep the midpoint extrapolation free of the jump
    nav[NAV_LAT] -= dlat
    nav[NAV_LON] -= dlon
    nav[NAV_H] -= du
    prev[PREV_LLA] -= dlat
    prev[PREV_LLA + 1] -= dlon
    prev[PREV_LLA + 2] -= du
    for j in range(xs.size):
        xs[j] += x[N_CORE + j]


@nb.njit(cache=True)
def _bias_totals(xs, blk_start, blk_kind, bg, ba):
    """Sum the sensor-error blocks into total gyro and accelerometer bias estimates."""
    for i in range(3):
        bg[i] = 0.0
        ba[i] = 0.0
    for b in range(blk_start.size):
        s0 = blk_start[b] - N_CORE
        for i in range(3):
            if blk_kind[b] == COUPLE_GYRO:
                bg[i] += xs[s0 + i]
            elif blk_kind[b] == COUPLE_ACCEL:
                ba[i] += xs[s0 + i]


@nb.njit(cache=True)
def _record(j, t, nav, xs, P, out_t, out_nav, out_xs, out_sig, em):
    out_t[j] = t
    for i in range(NAV_SIZE):
        out_nav[j, i] = nav[i]
    for i in range(xs.size):
        out_xs[j, i] = xs[i]
    for i in range(P.shape[0]):
        out_sig[j, i] = math.sqrt(max(P[i, i], 0.0))
    if em == EM_ST:  # report the sigma of the velocity error itself, as the phi model does
        for i in range(3):
            out_sig[j, X_VEL + i] = math.sqrt(max(st_velocity_variance(P, nav, i), 0.0))


@nb.njit(cache=True)
def run_loop(imu, start, model, events, sensors, meas_fns, adapt_fns, settings, out, evout):
    """Run the filter over all IMU samples; returns ``(status, samples_done)``.

    Arguments are the named tuples above (:class:`Imu`, :class:`Start`, :class:`Model`,
    :class:`Events`, :class:`Sensors`, :class:`Settings`, :class:`Outputs`,
    :class:`EventOutputs`) and the kernel tuples of the measurement models and adaptation
    policies.  ``imu.time_s`` has N+1 entries (increment k spans ``time_s[k]..time_s[k+1]``).
    Outputs are written into the preallocated ``out`` arrays (every ``out_stride`` samples,
    starting with the initial state) and ``evout`` (one row per event); ``sensors.ast``
    (adapter states) is updated in place.
    """
    # plain local names: the loop body reads as the algorithm, and numba sees bare arrays
    dth, dv, time_s = imu
    nav0, xs0, P0 = start
    q_diag, blk_start, blk_kind, blk_inv_tau, em = model
    ev_t, ev_s, ev_data = events
    s_meas, s_mpar, s_adapt, afp, afp_off, aip, aip_off, ast, ast_off, s_gate = sensors
    max_prop_dt, out_stride = settings
    out_t, out_nav, out_xs, out_sig = out
    ev_r, ev_S, ev_nis, ev_flag, ev_diag = evout
    n = P0.shape[0]
    M = ev_r.shape[1]
    N = dth.shape[0]
    E = ev_t.size
    nav = nav0.copy()
    prev = np.zeros(PREV_SIZE)
    init_prev(nav, prev)
    P = P0.copy()
    xs = xs0.copy()
    C = np.zeros((3, 3))
    quat_to_dcm_into(nav, C)
    sumC = np.zeros((3, 3))
    sumf = np.zeros(3)
    f_n = np.zeros(3)
    Cm = np.zeros((3, 3))
    fm = np.zeros(3)
    F = np.zeros((n, n))
    Phi = np.zeros((n, n))
    Qd = np.zeros((n, n))
    Qacc = np.zeros((n, n))
    Qc = np.zeros((n, n))
    work = np.zeros((n, n))
    AP = np.zeros((n, n))
    H = np.zeros((M, n))
    z = np.zeros(M)
    R = np.zeros(M)
    chan = np.zeros(M, dtype=np.int64)
    PHt = np.zeros((n, M))
    APHt = np.zeros((n, M))
    K = np.zeros((n, M))
    HPH = np.zeros((M, M))
    S = np.zeros((M, M))
    L = np.zeros((M, M))
    x = np.zeros(n)
    wv = np.zeros(max(n, M))
    out_a = np.zeros(2 + M)
    diag = np.zeros(ev_diag.shape[1])
    aux = np.zeros(6 + xs.size)  # IMU rates/force, then the sensor states (models read them)
    qd = q_diag.copy()
    bg = np.zeros(3)
    ba = np.zeros(3)
    dth_c = np.zeros(3)
    dv_c = np.zeros(3)
    tau = 0.0
    e = 0
    while e < E and ev_t[e] < time_s[0] - 1e-9:
        ev_flag[e] = EV_BEFORE_START
        e += 1
    _record(0, time_s[0], nav, xs, P, out_t, out_nav, out_xs, out_sig, em)
    for k in range(N):
        dt = time_s[k + 1] - time_s[k]
        _bias_totals(xs, blk_start, blk_kind, bg, ba)
        for i in range(3):
            dth_c[i] = dth[k, i] - bg[i] * dt
            dv_c[i] = dv[k, i] - ba[i] * dt
            aux[i] = dth_c[i] / dt
            aux[3 + i] = dv_c[i] / dt
        mech_step(nav, prev, dth_c, dv_c, dt, f_n)
        quat_to_dcm_into(nav, C)
        for i in range(3):
            sumf[i] += f_n[i] * dt
            for j in range(3):
                sumC[i, j] += C[i, j] * dt
        tau += dt
        t = time_s[k + 1]
        while e < E and ev_t[e] <= t + 1e-9:
            if tau > 0.0:
                _propagate(P, Qacc, xs, nav, sumC, sumf, tau, Cm, fm, F, Phi, Qd, work, qd,
                           blk_start, blk_kind, blk_inv_tau, em, Qc)
                tau = 0.0
            s = ev_s[e]
            a = s_adapt[s]
            H[:, :] = 0.0
            for i in range(xs.size):
                aux[6 + i] = xs[i]
            m = meas_fns[s_meas[s]](nav, C, aux, ev_data[e], s_mpar[s], t - ev_t[e], z, H, R,
                                    chan)
            if m == 0:
                ev_flag[e] = EV_EMPTY
                e += 1
                continue
            if em == EM_ST:  # the models write phi-model rows: H_ST = H A^-1
                st_measurement(H, m, nav)
            kalman.innovation_cov(P, H, m, PHt, HPH)
            adapt_fns[a](afp[afp_off[s]:afp_off[s + 1]], aip[aip_off[s]:aip_off[s + 1]],
                         ast[ast_off[s]:ast_off[s + 1]], z[:m], HPH, R, chan, m, out_a, diag)
            for i in range(qd.size):
                qd[i] *= out_a[1]
            for i in range(m):
                R[i] *= out_a[2 + i]
            for i in range(diag.size):
                ev_diag[e, i] = diag[i]
            ok = _innovation(HPH, R, m, S, L, z, wv, ev_r, ev_S, ev_nis, e)
            if not ok:
                ev_flag[e] = EV_BAD_S
                e += 1
                continue
            thr = s_gate[s, m]
            if thr > 0.0 and ev_nis[e] > thr:
                ev_flag[e] = EV_GATED
                e += 1
                continue
            if out_a[0] != 1.0:
                kalman.scale_predicted(P, Qacc, out_a[0], H, m, x)
                kalman.innovation_cov(P, H, m, PHt, HPH)
                _form_S(HPH, R, m, S)
                if not kalman.cholesky(S, m, L):  # the weighted S broke: skip the update
                    ev_flag[e] = EV_BAD_S
                    e += 1
                    continue
            kalman.gain(L, m, PHt, K, wv)
            kalman.joseph_update(P, H, R, m, z, PHt, K, x, AP, APHt)
            Qacc[:, :] = 0.0
            if em == EM_ST:
                st_to_phi(x, nav)
                st_reset(P, x)
            _feedback(nav, prev, xs, x)
            quat_to_dcm_into(nav, C)
            ev_flag[e] = EV_ACCEPTED
            e += 1
            if not kalman.covariance_ok(P):
                return ST_COVARIANCE, k + 1
        if tau >= max_prop_dt - 1e-12:
            _propagate(P, Qacc, xs, nav, sumC, sumf, tau, Cm, fm, F, Phi, Qd, work, qd,
                       blk_start, blk_kind, blk_inv_tau, em, Qc)
            tau = 0.0
        if (k + 1) % out_stride == 0:
            _record((k + 1) // out_stride, t, nav, xs, P, out_t, out_nav, out_xs, out_sig, em)
    return ST_OK, N


@nb.njit(cache=True)
def _form_S(HPH, R, m, S):
    """``S[:m, :m] = HPH + diag(R)``."""
    for i in range(m):
        for j in range(m):
            S[i, j] = HPH[i, j]
        S[i, i] += R[i]


@nb.njit(cache=True)
def _innovation(HPH, R, m, S, L, z, wv, ev_r, ev_S, ev_nis, e):
    """Form S = HPH + R, factor it and log the residual, S diagonal and NIS."""
    _form_S(HPH, R, m, S)
    for i in range(m):
        ev_r[e, i] = z[i]
        ev_S[e, i] = S[i, i]
    if not kalman.cholesky(S, m, L):
        return False
    ev_nis[e] = kalman.nis(L, m, z, wv)
    return True


@nb.njit(cache=True)
def _propagate(P, Qacc, xs, nav, sumC, sumf, tau, Cm, fm, F, Phi, Qd, work, qd,
               blk_start, blk_kind, blk_inv_tau, em, Qc):
    """Propagate P over the accumulated interval and decay Gauss-Markov estimates.

    ``em`` selects the error model; the ST model maps the phi model's F and noise."""
    for i in range(3):
        fm[i] = sumf[i] / tau
        sumf[i] = 0.0
        for j in range(3):
            Cm[i, j] = sumC[i, j] / tau
            sumC[i, j] = 0.0
    fill_F(F, nav, Cm, fm, blk_start, blk_kind, blk_inv_tau)
    if em == EM_ST:
        st_system(F, nav)
        st_process_noise(Qc, qd, nav)
        discretize_dense(F, Qc, tau, Phi, Qd, work)
    else:
        discretize(F, qd, tau, Phi, Qd, work)
    kalman.propagate(P, Phi, Qd, work)
    n = P.shape[0]
    for i in range(n):
        for j in range(n):
            Qacc[i, j] += Qd[i, j]
    for b in range(blk_start.size):
        if blk_inv_tau[b] > 0.0:
            d = math.exp(-tau * blk_inv_tau[b])
            for i in range(blk_start[b], block_end(blk_start, b, n)):
                xs[i - N_CORE] *= d
