"""The closed-loop error-state filter as one compiled loop over plain arrays.

Per IMU sample: bias-corrected increments -> strapdown step -> accumulate the mean attitude and
specific force.  The covariance is propagated over the accumulated interval (with the mean
``F``) when a measurement is due or ``max_prop_dt`` has passed: the error model varies slowly,
so propagating every sample would cost ~100x more for no accuracy (docs/benchmarks.md).
Measurement epochs go through the sensor's measurement model, its adaptation policy, optional
chi-square gating, the Joseph update and closed-loop feedback.  The filter is a bank of local
filters over the one mechanization (:mod:`fuzzynav.filters.bank`): each measurement updates
the local that owns its sensor, the master fuses the locals and feeds the fused estimate back
(:func:`~fuzzynav.filters.bank_fusion.fuse_and_feed_back`); the single filter is the bank of
one, which skips the fusion.  What depends on the error model is behind its hook
(:mod:`fuzzynav.filters.error_hook`).  Memory is independent of the run length apart from
the outputs (every ``out_stride`` samples) and the per-epoch event log.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from fuzzynav.filters import error_hook, kalman, precompile
from fuzzynav.filters.adaptation import context
from fuzzynav.filters.bank_beta import push_innovation
from fuzzynav.filters.bank_fusion import SHARED, STALE, after_propagation, fuse_and_feed_back, \
    local_residual, master_covariance, propagate_locals
from fuzzynav.filters.error_st import EM_ST
from fuzzynav.filters.feedback import bias_totals, feedback
from fuzzynav.filters.layout import AUX_FORCE, AUX_RATE, AUX_XS
# the argument bundles, named here too: callers build them as loop.Imu(...), ...
from fuzzynav.filters.loop_args import (  # noqa: F401
    Bank, BankState, Carry, EventOutputs, Events, Imu, Model, Outputs, Sensors, Settings, Start,
    new_carry)
from fuzzynav.filters.numba_patch_dispatch import memoise_table_types
from fuzzynav.filters.record import record_output
from fuzzynav.nav.strapdown import init_prev, mech_step, quat_to_dcm_into

__all__ = ["NO_ADAPTER", "PLAIN_LOOP", "run_loop", "loop_for"]

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
    typing, so their kernels are not compiled for it (without ``ST`` the error-model
    argument is ``None``, which compiles every hook point to the phi model's code).  Every
    copy runs the same operations in the same order for the runs it takes
    (:func:`loop_for`), so results are the same whichever runs them; each copy has its own
    entry in numba's cache.
    """

    @nb.njit(cache=True, error_model="numpy")
    def run_loop(imu, start, model, events, sensors, bank, state, meas_fns, adapt_fns, settings,
                 out, evout, chunk):
        """Run the filter bank over one chunk of IMU samples; returns ``(status,
        samples_done)``, counted from the run's first sample.

        Arguments are the named tuples of :mod:`fuzzynav.filters.loop_args` (:class:`Imu`,
        :class:`Start`, :class:`Model`, :class:`Events`, :class:`Sensors`, :class:`Bank`,
        :class:`BankState`, :class:`Settings`, :class:`Outputs`, :class:`EventOutputs`,
        :class:`Carry`) and the kernel tuples of the measurement models and adaptation
        policies.  ``imu.time_s`` has N+1 entries (increment k spans
        ``time_s[k]..time_s[k+1]``); the next chunk starts at this one's last time.  Outputs
        are written into the preallocated ``out`` arrays (every ``out_stride`` samples of the
        run, starting with the initial state; row 0 of ``out`` is the run's row
        ``chunk.count[CN_ROW0]``) and ``evout`` (one row per event of the run);
        ``sensors.ast`` (adapter states), ``state`` and ``chunk`` (everything else the loop
        keeps between samples) are updated in place, so calling the loop again with the next
        chunk continues the run exactly: a run in one chunk is the special case.

        The body reads as the filter's steps -- strapdown, propagate if due, measure,
        adapt, gate and update, fuse and feed back -- each a commented block over the
        arrays unpacked here once per chunk.  The steps that run per sample or per epoch are
        not functions of their own: every way numba has of making them one (an inlined
        function, an inlined closure, a plain call) pays per array it touches on every call
        (the inlined ones a reference count taken and dropped, a plain call the array's
        fields passed), and that made the paper000 EKF run
        4-35 % slower (docs/benchmarks.md, "The loop as steps").  The rare ones are:
        :func:`~fuzzynav.filters.bank_fusion.propagate_locals`,
        :func:`~fuzzynav.filters.bank_fusion.fuse_and_feed_back` (a bank's fusion; the
        single filter feeds its own estimate back), :func:`_begin`, :func:`_park`, and
        what depends on the error model is one hook (:mod:`fuzzynav.filters.error_hook`).
        """
        dth, dv, time_s = imu
        em = model.error_model if ST else None  # None: the phi model, known when compiled
        blk_start, blk_kind = model.blk_start, model.blk_kind
        ev_t, ev_s, ev_data = events
        s_meas, s_mpar, s_adapt, afp, afp_off, aip, aip_off, ast, ast_off, s_gate = sensors
        s_local, beta, reset, period = bank.local, bank.beta, bank.reset, bank.period
        P3, X, QD = state.P, state.x, state.qd
        ev_r, ev_S, ev_nis, ev_flag, ev_diag = evout
        nv, acc, up, ad, fu, clock, count = chunk
        nav, prev, xs, C, bg, ba, dth_c, dv_c = nv
        sumC, sumf, dv_sf, Qacc3 = acc.sumC, acc.sumf, acc.dv_sf, acc.Qacc
        H, z, R, chan, PHt, HPH, S, L, K, AP, APHt, dx, wv = up
        out_a, diag, ctx, aux = ad
        max_prop_dt, out_stride = settings
        NL, N, E, M = X.shape[0], dth.shape[0], ev_t.size, ev_r.shape[1]
        # a local's estimate survives between updates only in a bank of several locals that
        # does not reset to the fused solution after every update
        carry = BANK and NL > 1 and (reset == 0 or period > 0.0)
        # only a policy may scale the predicted covariance by the noise since the last update
        keep_q = np.any(s_adapt != NO_ADAPTER)

        k0, row0 = count[CN_K0], count[CN_ROW0]
        if count[CN_STARTED] == 0:  # the run's first chunk: its start
            _begin(start, model, ev_t, ev_flag, nv, ctx, M, clock, count, time_s)
            record_output(0 - row0, time_s[0], nav, xs, state,
                          master_covariance(P3, X, beta, state.Pg, SHARED, fu.Pf, fu.xf,
                                            fu.work) if BANK and NL > 1 else P3[0],
                          beta, out, em)
        # the scalars live in locals while the chunk runs, in ``chunk`` between chunks
        fstate, e, since_out = count[CN_FSTATE], count[CN_EVENT], count[CN_SINCE_OUT]
        t_fused, tau = clock[CL_T_FUSED], clock[CL_TAU]
        for k in range(N):
            # strapdown: bias-corrected increments, the mechanization (C follows the new
            # attitude), the interval's sums of attitude and specific force
            dt = time_s[k + 1] - time_s[k]
            for i in range(3):
                dth_c[i] = dth[k, i] - bg[i] * dt
                dv_c[i] = dv[k, i] - ba[i] * dt
            mech_step(nav, prev, dth_c, dv_c, dt, dv_sf, C)
            for i in range(3):
                sumf[i] += dv_sf[i]  # the interval's mean force is sumf / tau
                for j in range(3):
                    sumC[i, j] += C[i, j] * dt
            tau += dt
            t = time_s[k + 1]
            while e < E and ev_t[e] <= t + 1e-9:
                if tau > 0.0:  # propagate if due: every local up to the epoch
                    propagate_locals(state, model, em, acc, nav, xs, tau, keep_q, carry)
                    tau = 0.0
                    fstate = after_propagation(fstate, reset)
                    bias_totals(xs, blk_start, blk_kind, bg, ba)
                # measure: the sensor's (z, H, R), in the error model's rows
                s = ev_s[e]
                li = s_local[s]
                P, x, qd, Qacc = P3[li], X[li], QD[li], Qacc3[li]
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
                error_hook.rows(em, H, m, nav)  # the models write phi-model rows
                if carry:  # a local's estimate not fed back yet: its own innovation
                    local_residual(z, H, m, x)
                kalman.innovation_cov(P, H, m, PHt, HPH)
                # adapt: the policy's weights (P, Q, then R per row; Q and R now, P once the
                # gate has passed), then S, its factor and the NIS
                out_a[0] = 1.0
                a = s_adapt[s]
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
                if not _innovation(HPH, R, m, S, L, z, wv, ev_r, ev_S, ev_nis, e):
                    ev_flag[e] = EV_BAD_S
                    e += 1
                    continue
                if BANK and bank.ctl.on:  # the share controller reads every innovation
                    push_innovation(bank.ctl.stat[li], ev_nis[e], m, z, S)
                # gate, then update the sensor's local
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
                if keep_q:  # the noise since this local's last update starts again
                    Qacc[:, :] = 0.0
                for i in range(x.size):
                    x[i] += dx[i]
                ev_flag[e] = EV_ACCEPTED
                t_meas = ev_t[e]  # the fusion clock runs on measurement times, not IMU times
                e += 1
                # fuse and feed back (the single filter: its own estimate)
                fstate = STALE
                if BANK and NL > 1:
                    ok, fstate, t_fused = fuse_and_feed_back(em, bank, state, fu, Qacc3, nav,
                                                             prev, xs, li, t_meas, t_fused)
                else:
                    error_hook.single_feedback(em, P, x, nav)
                    feedback(nav, prev, xs, x)
                    x[:] = 0.0
                    ok = kalman.covariance_ok(P)
                quat_to_dcm_into(nav, C)
                bias_totals(xs, blk_start, blk_kind, bg, ba)
                if not ok:
                    _park(chunk, fstate, t_fused, tau, e, since_out, k0 + k + 1)
                    return ST_COVARIANCE, k0 + k + 1
            if tau >= max_prop_dt - 1e-12:  # propagate if due: the longest interval passed
                propagate_locals(state, model, em, acc, nav, xs, tau, keep_q, carry)
                tau = 0.0
                fstate = after_propagation(fstate, reset)
                bias_totals(xs, blk_start, blk_kind, bg, ba)  # Gauss-Markov decay of xs
            since_out += 1
            if since_out == out_stride:
                since_out = 0
                record_output((k0 + k + 1) // out_stride - row0, t, nav, xs, state,
                              master_covariance(P3, X, beta, state.Pg, fstate, fu.Pf, fu.xf,
                                                fu.work) if BANK and NL > 1 else P3[0],
                              beta, out, em)
        _park(chunk, fstate, t_fused, tau, e, since_out, k0 + N)
        return ST_OK, k0 + N

    return memoise_table_types(run_loop)  # the kernel tables: typed once per tuple


@nb.njit(cache=True, error_model="numpy")
def _begin(start, model, ev_t, ev_flag, nv, ctx, M, clock, count, time_s):
    """The run's start (its first chunk): the initial state, the clocks and counters, and
    the events before the first IMU sample marked."""
    count[CN_STARTED] = 1
    nav = nv.nav
    nav[:] = start.nav0
    init_prev(nav, nv.prev)
    nv.xs[:] = start.xs0
    quat_to_dcm_into(nav, nv.C)
    ctx[context.CTX_M] = M
    count[CN_FSTATE] = SHARED  # every local starts from P0 / beta_i
    clock[CL_T_FUSED] = -math.inf
    clock[CL_TAU] = 0.0
    # bias totals change only with xs (feedback, Gauss-Markov decay): formed then, not per
    # sample
    bias_totals(nv.xs, model.blk_start, model.blk_kind, nv.bg, nv.ba)
    count[CN_SINCE_OUT] = 0  # samples since the last recorded output
    e = 0
    while e < ev_t.size and ev_t[e] < time_s[0] - 1e-9:
        ev_flag[e] = EV_BEFORE_START
        e += 1
    count[CN_EVENT] = e


@nb.njit(cache=True, error_model="numpy")
def _park(chunk, fstate, t_fused, tau, e, since_out, done):
    """Store the loop's scalars in ``chunk`` for the next chunk (``done`` samples so far)."""
    chunk.clock[CL_TAU] = tau
    chunk.clock[CL_T_FUSED] = t_fused
    chunk.count[CN_EVENT] = e
    chunk.count[CN_SINCE_OUT] = since_out
    chunk.count[CN_FSTATE] = fstate
    chunk.count[CN_K0] = done


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
