"""The closed-loop error-state filter as one compiled loop over plain arrays.

Per IMU sample: bias-corrected increments -> strapdown step -> accumulate the mean attitude and
specific force.  The covariance is propagated over the accumulated interval (with the mean
``F``) when a measurement is due or ``max_prop_dt`` has passed: the error model varies slowly,
so propagating every sample would cost ~100x more for no accuracy (docs/benchmarks.md).
Measurement epochs go through the sensor's measurement model, its adaptation policy, optional
chi-square gating, the Joseph update and closed-loop feedback.  The filter is a bank of local
filters over the one mechanization (:mod:`fuzzynav.filters.bank`): each measurement updates
the local that owns its sensor, the master fuses the locals and feeds the fused estimate back;
the single filter is the bank of one, which skips the fusion.  Memory is independent of the
run length apart from the outputs (every ``out_stride`` samples) and the per-epoch event log.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.filters import kalman, precompile
from fuzzynav.filters.adaptation import context
from fuzzynav.filters.bank_beta import push_innovation, update_shares
from fuzzynav.filters.bank_fusion import FUSED_NOW, SHARED, STALE, after_propagation, fuse, \
    fusion_work, local_residual, master_covariance, propagate_locals, share
from fuzzynav.filters.numba_patch_dispatch import memoise_table_types
from fuzzynav.filters.error_st import EM_PHI, EM_ST, st_fused, st_measurement, st_regauge, \
    st_reset, st_to_phi
from fuzzynav.filters.feedback import bias_totals, feedback
from fuzzynav.filters.layout import AUX_FORCE, AUX_RATE, AUX_XS
# the argument bundles, named here too: callers build them as loop.Imu(...), ...
from fuzzynav.filters.loop_args import (  # noqa: F401
    Bank, BankState, Carry, EventOutputs, Events, Imu, Model, Outputs, Sensors, Settings, Start,
    new_carry)
from fuzzynav.filters.record import record_output
from fuzzynav.nav.state_layout import PREV_SIZE
from fuzzynav.nav.strapdown import init_prev, mech_step, quat_to_dcm_into


#: adapter id of a sensor without adaptation (the loop skips the policy's call)
NO_ADAPTER = -1
# event flags
EV_PENDING, EV_ACCEPTED, EV_GATED, EV_EMPTY, EV_BAD_S, EV_BEFORE_START = 0, 1, 2, 3, 4, 5
# loop status
ST_OK, ST_COVARIANCE = 0, 1
# the scalars a run carries from chunk to chunk (:class:`Carry`): ``clock`` (float) holds
# the covariance propagation interval accumulated so far and the time of the last fusion;
# ``count`` (int) the next event, samples since the last output, the fusion state, the
# samples done before this chunk, the first output row of this chunk's ``out``, started
CL_TAU, CL_T_FUSED = 0, 1
CN_EVENT, CN_SINCE_OUT, CN_FSTATE, CN_K0, CN_ROW0, CN_STARTED = 0, 1, 2, 3, 4, 5


def _make_loop(BANK: bool, ST: bool):
    """The compiled loop; ``BANK`` / ``ST`` False: a copy without the code of a bank of
    several locals (and of the share controller) / of the ST error model.

    The flags are constants of the copy: numba drops the branches they turn off before
    typing, so their kernels are not compiled for it.  Every copy runs the same operations
    in the same order for the runs it takes (:func:`loop_for`), so results are the same
    whichever runs them; each copy has its own entry in numba's cache.
    """

    @nb.njit(cache=True, error_model="numpy")
    def run_loop(imu, start, model, events, sensors, bank, state, meas_fns, adapt_fns, settings,
                 out, evout, chunk):
        """Run the filter bank over one chunk of IMU samples; returns ``(status,
        samples_done)``, counted from the run's first sample.

        Arguments are the named tuples above (:class:`Imu`, :class:`Start`, :class:`Model`,
        :class:`Events`, :class:`Sensors`, :class:`Bank`, :class:`BankState`,
        :class:`Settings`, :class:`Outputs`, :class:`EventOutputs`, :class:`Carry`) and the
        kernel tuples of the measurement models and adaptation policies.  ``imu.time_s`` has
        N+1 entries (increment k spans ``time_s[k]..time_s[k+1]``); the next chunk starts at
        this one's last time.  Outputs are written into the preallocated ``out`` arrays
        (every ``out_stride`` samples of the run, starting with the initial state; row 0 of
        ``out`` is the run's row ``chunk.count[CN_ROW0]``) and ``evout`` (one row per event
        of the run); ``sensors.ast`` (adapter states), ``state`` and ``chunk`` (everything
        else the loop keeps between samples) are updated in place, so calling the loop again
        with the next chunk continues the run exactly: a run in one chunk is the special case.
        """
        # plain local names: the loop body reads as the algorithm, and numba sees bare arrays
        dth, dv, time_s = imu
        nav0, xs0 = start
        blk_start, blk_kind, blk_inv_tau, em = model
        if not ST:  # a constant: the callees compile without their ST branches
            em = EM_PHI
        ev_t, ev_s, ev_data = events
        s_meas, s_mpar, s_adapt, afp, afp_off, aip, aip_off, ast, ast_off, s_gate = sensors
        s_local, beta, reset, period, ctl = bank
        P3, X, QD, Pg, xg = state
        max_prop_dt, out_stride = settings
        ev_r, ev_S, ev_nis, ev_flag, ev_diag = evout
        NL, n = X.shape
        M = ev_r.shape[1]
        N = dth.shape[0]
        E = ev_t.size
        # a local's estimate survives between updates only in a bank of several locals that
        # does not reset to the fused solution after every update
        carry = BANK and NL > 1 and (reset == 0 or period > 0.0)
        # only a policy may scale the predicted covariance by the noise since the last update
        keep_q = np.any(s_adapt != NO_ADAPTER)
        # everything the loop keeps between samples lives in ``chunk`` (:class:`Carry`), so a
        # run over consecutive chunks of the IMU is the same arithmetic as one over the whole
        (nav, prev, xs, C, sumC, sumf, dv_sf, Cm, fm, F, Phi, Qd, Qacc3, Qc, work, AP, H, z, R,
         chan, PHt, APHt, K, HPH, S, L, dx, wv, out_a, diag, ctx, aux, bg, ba, dth_c, dv_c,
         fwork, Pf, xf, xphi, clock, count) = chunk
        k0, row0 = count[CN_K0], count[CN_ROW0]
        if count[CN_STARTED] == 0:  # the run's first chunk: its start
            count[CN_STARTED] = 1
            nav[:] = nav0
            init_prev(nav, prev)
            xs[:] = xs0
            quat_to_dcm_into(nav, C)
            ctx[context.CTX_M] = M
            count[CN_FSTATE] = SHARED  # every local starts from P0 / beta_i
            clock[CL_T_FUSED] = -math.inf
            clock[CL_TAU] = 0.0
            # bias totals change only with xs (feedback, Gauss-Markov decay): formed then,
            # not per sample
            bias_totals(xs, blk_start, blk_kind, bg, ba)
            count[CN_SINCE_OUT] = 0  # samples since the last recorded output
            e = 0
            while e < E and ev_t[e] < time_s[0] - 1e-9:
                ev_flag[e] = EV_BEFORE_START
                e += 1
            count[CN_EVENT] = e
            record_output(0 - row0, time_s[0], nav, xs, state,
                          master_covariance(P3, X, beta, Pg, SHARED, Pf, xf, fwork)
                          if BANK and NL > 1 else P3[0],
                          beta, out, em)
        fstate = count[CN_FSTATE]
        t_fused = clock[CL_T_FUSED]
        tau = clock[CL_TAU]
        e = count[CN_EVENT]
        since_out = count[CN_SINCE_OUT]
        for k in range(N):
            dt = time_s[k + 1] - time_s[k]
            for i in range(3):
                dth_c[i] = dth[k, i] - bg[i] * dt
                dv_c[i] = dv[k, i] - ba[i] * dt
            mech_step(nav, prev, dth_c, dv_c, dt, dv_sf, C)  # C follows the new attitude
            for i in range(3):
                sumf[i] += dv_sf[i]  # the interval's mean force is sumf / tau
                for j in range(3):
                    sumC[i, j] += C[i, j] * dt
            tau += dt
            t = time_s[k + 1]
            while e < E and ev_t[e] <= t + 1e-9:
                if tau > 0.0:
                    propagate_locals(state, Qacc3, keep_q, carry, xs, nav, sumC, sumf, tau, Cm,
                                     fm, F, Phi, Qd, work, dx, blk_start, blk_kind, blk_inv_tau,
                                     em, Qc)
                    tau = 0.0
                    fstate = after_propagation(fstate, reset)
                    bias_totals(xs, blk_start, blk_kind, bg, ba)
                s = ev_s[e]
                a = s_adapt[s]
                P, x, qd, Qacc = P3[s_local[s]], X[s_local[s]], QD[s_local[s]], Qacc3[s_local[s]]
                H[:, :] = 0.0
                for i in range(3):  # the latest interval's rate and force, for the models only
                    aux[AUX_RATE + i] = dth_c[i] / dt
                    aux[AUX_FORCE + i] = dv_c[i] / dt
                for i in range(xs.size):
                    aux[AUX_XS + i] = xs[i]
                m = meas_fns[s_meas[s]](nav, C, aux, ev_data[e], s_mpar[s], t - ev_t[e], z, H, R,
                                        chan)
                if m == 0:
                    ev_flag[e] = EV_EMPTY
                    e += 1
                    continue
                if ST and em == EM_ST:  # the models write phi-model rows: H_ST = H A^-1
                    st_measurement(H, m, nav)
                if carry:
                    local_residual(z, H, m, x)
                kalman.innovation_cov(P, H, m, PHt, HPH)
                out_a[0] = 1.0
                if a != NO_ADAPTER:  # what the plain EKF's policy would return: ones, no diag
                    context.fill(ctx, nav, aux, R, m, ev_data[e])
                    adapt_fns[a](afp[afp_off[s]:afp_off[s + 1]], aip[aip_off[s]:aip_off[s + 1]],
                                 ast[ast_off[s]:ast_off[s + 1]], z[:m], HPH, R, chan, m, out_a,
                                 diag, ctx)
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
                if BANK and ctl.on:  # the share controller reads every formed innovation
                    push_innovation(ctl.stat[s_local[s]], ev_nis[e], m, z, S)
                thr = s_gate[s, m]
                if thr > 0.0 and ev_nis[e] > thr:
                    ev_flag[e] = EV_GATED
                    e += 1
                    continue
                if out_a[0] != 1.0:
                    kalman.scale_predicted(P, Qacc, out_a[0], H, m, dx)
                    kalman.innovation_cov(P, H, m, PHt, HPH)
                    _form_S(HPH, R, m, S)
                    if not kalman.cholesky(S, m, L):  # the weighted S broke: skip the update
                        ev_flag[e] = EV_BAD_S
                        e += 1
                        continue
                kalman.correct(L, P, H, R, m, z, PHt, K, dx, AP, APHt, wv)
                if keep_q:
                    Qacc[:, :] = 0.0
                for i in range(n):
                    x[i] += dx[i]
                ev_flag[e] = EV_ACCEPTED
                t_meas = ev_t[e]  # the fusion clock runs on measurement times, not IMU times
                e += 1
                fstate = STALE
                if not (BANK and NL > 1):
                    if ST and em == EM_ST:
                        st_to_phi(x, nav)
                        st_reset(P, x)
                    feedback(nav, prev, xs, x)
                    x[:] = 0.0
                    ok = kalman.covariance_ok(P)
                elif period <= 0.0 or t_meas - t_fused >= period - 1e-9:
                    if ctl.on:  # new shares first: a reset shares P_g by them
                        update_shares(ctl, beta, QD)
                    ok = fuse(P3, X, Pg, xg, fwork)
                    if ok:
                        fb = xg  # the ST model fuses ST states, feeds back their phi form
                        if ST and em == EM_ST:
                            fb = st_fused(xg, Pg, nav, xphi)
                        share(P3, X, Qacc3, Pg, xg, beta, reset)
                        if ST and em == EM_ST and not reset:
                            st_regauge(P3, X, fb)
                        feedback(nav, prev, xs, fb)
                        t_fused = t_meas
                        fstate = FUSED_NOW
                        ok = kalman.covariance_ok(Pg)
                else:
                    ok = kalman.covariance_ok(P)
                quat_to_dcm_into(nav, C)
                bias_totals(xs, blk_start, blk_kind, bg, ba)
                if not ok:
                    _park(chunk, fstate, t_fused, tau, e, since_out, k0 + k + 1)
                    return ST_COVARIANCE, k0 + k + 1
            if tau >= max_prop_dt - 1e-12:
                propagate_locals(state, Qacc3, keep_q, carry, xs, nav, sumC, sumf, tau, Cm, fm, F,
                                 Phi, Qd, work, dx, blk_start, blk_kind, blk_inv_tau, em, Qc)
                tau = 0.0
                fstate = after_propagation(fstate, reset)
                bias_totals(xs, blk_start, blk_kind, bg, ba)  # Gauss-Markov decay of xs
            since_out += 1
            if since_out == out_stride:
                since_out = 0
                record_output((k0 + k + 1) // out_stride - row0, t, nav, xs, state,
                              master_covariance(P3, X, beta, Pg, fstate, Pf, xf, fwork)
                              if BANK and NL > 1 else P3[0], beta, out, em)
        _park(chunk, fstate, t_fused, tau, e, since_out, k0 + N)
        return ST_OK, k0 + N

    return memoise_table_types(run_loop)  # the kernel tables: typed once per tuple


@nb.njit(cache=True, error_model="numpy")
def _park(chunk, fstate, t_fused, tau, e, since_out, done):
    """Store the loop's scalars in ``chunk`` for the next chunk (``done`` samples so far)."""
    chunk.clock[CL_TAU] = tau
    chunk.clock[CL_T_FUSED] = t_fused
    chunk.count[CN_EVENT] = e
    chunk.count[CN_SINCE_OUT] = since_out
    chunk.count[CN_FSTATE] = fstate
    chunk.count[CN_K0] = done


#: the plain loop (a single filter, phi model: the EKF and the policies) and the full one;
#: two copies, not one per combination, so that a test run or a comparison across filter
#: kinds compiles the loop at most twice
PLAIN_LOOP = _make_loop(False, False)
run_loop = _make_loop(True, True)


def loop_for(n_local: int, error_model: int, controller_on: int):
    """The compiled loop for a filter of ``n_local`` locals, error model code
    ``error_model``, share controller on or off: :data:`PLAIN_LOOP` for a single phi-model
    filter, else :func:`run_loop` (each compiled on first use).  On a cold kernel cache the
    covariance kernels are compiled meanwhile in a second process
    (:func:`fuzzynav.filters.precompile.start`)."""
    precompile.start()
    if n_local == 1 and not controller_on and error_model != EM_ST:
        return PLAIN_LOOP
    return run_loop


@nb.njit(cache=True, error_model="numpy")
def _form_S(HPH, R, m, S):
    """``S[:m, :m] = HPH + diag(R)``."""
    for i in range(m):
        for j in range(m):
            S[i, j] = HPH[i, j]
        S[i, i] += R[i]


@nb.njit(cache=True, error_model="numpy")
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
