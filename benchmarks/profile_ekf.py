"""Where a paper000 EKF run spends its time: per-part costs times their counts.

numba code cannot be sampled by a Python profiler, so each part is timed on its own in a
compiled loop (the kernels the filter loop calls, on the true state at 300 s and each
sensor's data row of that time) and multiplied by how often a run calls it; the mechanization is the run without sensors
(which still propagates once per ``max_prop_dt_s``) less those propagations.  Parts:
mechanization per IMU sample, covariance propagation (``fill_F`` + ``discretize`` +
``kalman.propagate``), the measurement models, the update (innovation covariance,
Cholesky, NIS, gain, Joseph, covariance check), feedback, recording.

Imports whichever fuzzynav is first on ``sys.path``, so ``bench_ekf.py`` runs it in its
workers for the base revision and this tree, alternating.  Usage: ``python benchmarks/profile_ekf.py [--json]``.
"""
from __future__ import annotations

import json
import sys
import tempfile
import time

import numba as nb
import numpy as np

from fuzzynav.experiment import perturbed_initial_state, setup_for, simulate
from fuzzynav.filters import kalman, loop
from fuzzynav.filters.error_model import discretize, fill_F
from fuzzynav.filters.runner import run_filter

try:  # this tree packs the sensors in their own module; a base revision in the runner
    from fuzzynav.filters.sensor_tables import pack_sensors as _sensor_tables
except ImportError:
    from fuzzynav.filters.runner import _sensor_tables

try:  # this tree: feedback has its own module (filter banks)
    from fuzzynav.filters.feedback import feedback as _apply_feedback
except ImportError:  # the base revision: it lived in the loop module
    _apply_feedback = loop._feedback
from fuzzynav.nav import strapdown

try:
    from fuzzynav.nav.state_layout import PREV_SIZE
except ImportError:  # a base revision before the module got its name (bench_ekf --base)
    from fuzzynav.nav.layout import PREV_SIZE
from fuzzynav.sim.scenario import load_scenario


@nb.njit(cache=True)
def _propagation(reps, P0, nav, C, f_n, q, bs, bk, bi):
    n = P0.shape[0]
    F, Phi, Qd, w, P = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n)), P0.copy()
    for _ in range(reps):
        fill_F(F, nav, C, f_n, bs, bk, bi)
        discretize(F, q, 0.2, Phi, Qd, w)
        kalman.propagate(P, Phi, Qd, w)
        P[:, :] = P0  # cheap next to the rest; keeps P from drifting
    return P


@nb.njit(cache=True)
def _measurement(reps, fns, idx, nav, C, aux, row, par, z, H, R, chan):
    m = 0
    for _ in range(reps):
        H[:, :] = 0.0
        m = fns[idx](nav, C, aux, row, par, 0.0, z, H, R, chan)
    return m


if hasattr(kalman, "correct"):  # this tree: gain and update in one call, as the loop runs them
    _correct = kalman.correct
else:  # the base revision
    @nb.njit(cache=True)
    def _correct(L, P, H, R, m, z, PHt, K, x, AP, APHt, wv):
        kalman.gain(L, m, PHt, K, wv)
        kalman.joseph_update(P, H, R, m, z, PHt, K, x, AP, APHt)


@nb.njit(cache=True)
def _update(reps, P0, H, R, m, z):
    n, M = P0.shape[0], H.shape[0]
    P, PHt, HPH, S, L = P0.copy(), np.zeros((n, M)), np.zeros((M, M)), np.zeros((M, M)), np.zeros((M, M))
    K, x, AP, APHt, wv = np.zeros((n, M)), np.zeros(n), np.zeros((n, n)), np.zeros((n, M)), np.zeros(max(n, M))
    for _ in range(reps):
        kalman.innovation_cov(P, H, m, PHt, HPH)
        for i in range(m):
            for j in range(m):
                S[i, j] = HPH[i, j]
            S[i, i] += R[i]
        kalman.cholesky(S, m, L)
        kalman.nis(L, m, z, wv)
        _correct(L, P, H, R, m, z, PHt, K, x, AP, APHt, wv)
        kalman.covariance_ok(P)
        P[:, :] = P0
    return P


@nb.njit(cache=True)
def _feedback_record(reps, nav0, P, out_t, out_nav, out_xs, out_sig):
    nav, prev, xs, x, C = nav0.copy(), np.zeros(PREV_SIZE), np.zeros(out_xs.shape[1]), \
        np.full(P.shape[0], 1e-12), np.zeros((3, 3))
    strapdown.init_prev(nav, prev)
    for r in range(reps):
        _apply_feedback(nav, prev, xs, x)
        strapdown.quat_to_dcm_into(nav, C)
        # the recording (signature changed with the banks) is left out: ~0.1 % of a run


def per_call_us(fn, args, reps):
    """Median CPU time of one call [µs] over 5 timings of ``reps`` calls."""
    fn(2, *args)
    t = []
    for _ in range(5):
        c0 = time.process_time()
        fn(reps, *args)
        t.append(time.process_time() - c0)
    return 1e6 * float(np.median(t)) / reps


def run_ms(log, setup, sensors, repeat=5):
    init = perturbed_initial_state(log, setup)
    once = lambda: run_filter(log.imu, sensors, init, setup.config, {})  # noqa: E731
    res = once()
    t = []
    for _ in range(repeat):
        c0 = time.process_time()
        once()
        t.append(time.process_time() - c0)
    return 1e3 * float(np.median(t)), res


def _tables(tb) -> dict:
    """The sensor tables as the dict older revisions returned (``bench_ekf.py`` runs this
    file against a base revision's package too)."""
    if isinstance(tb, dict):
        return tb
    ev, se = tb.events, tb.sensors
    return dict(names=tb.names, M=tb.M, meas_fns=tb.meas_fns, ev_t=ev.t, ev_s=ev.s,
                ev_data=ev.data, s_meas=se.meas, s_mpar=se.mpar)


def profile(cache_dir=None) -> dict:
    """Per-part costs and counts of a paper000 ``ekf`` run (see the module docstring)."""
    log = simulate(load_scenario("paper000"), 0, cache_dir or tempfile.mkdtemp())
    setup = setup_for(log, "ekf")
    cfg, sensors = setup.config, setup.sensors_for(log.sensors)
    tb = _tables(_sensor_tables(sensors, {}, {}, None))
    n, M, k0 = cfg.model.n_states, tb["M"], 30000
    tr = log.truth
    nav = strapdown.make_nav(tr.lla[k0], tr.vel_n[k0], tr.q_bn[k0])
    C = np.zeros((3, 3))
    strapdown.quat_to_dcm_into(nav, C)
    P0 = cfg.P0() * 0.1 + 1e-6 * np.eye(n)
    total, res = run_ms(log, setup, sensors)
    bare, _ = run_ms(log, setup, {})
    ev_times = np.unique(np.concatenate([d.time_s for d in sensors.values()]))
    n_prop = ev_times.size  # one propagation per distinct epoch time (max_prop_dt is 1 s)
    n_bare_prop = int(log.imu.time_s[-1] - log.imu.time_s[0])
    parts = {"covariance propagation": (per_call_us(_propagation, (
        P0, nav, C, np.array([0.3, 0.2, 9.8]), cfg.q_diag(), *cfg.model.block_arrays()), 3000),
        n_prop)}
    aux = np.array([0.01, 0.02, 0.01, 0.1, 0.2, 9.8])
    for s, nm in enumerate(tb["names"]):
        mine = np.flatnonzero(tb["ev_s"] == s)  # its epoch nearest the state's time
        e = int(mine[np.argmin(np.abs(tb["ev_t"][mine] - tr.time_s[k0]))])
        z, H, R, chan = np.zeros(M), np.zeros((M, n)), np.zeros(M), np.zeros(M, np.int64)
        margs = (tb["meas_fns"], tb["s_meas"][s], nav, C, aux, tb["ev_data"][e], tb["s_mpar"][s],
                 z, H, R, chan)
        m = _measurement(1, *margs)
        count = int((res.events[nm].flag == loop.EV_ACCEPTED).sum())
        parts[f"{nm} measurement model"] = (per_call_us(_measurement, margs, 2000),
                                            sensors[nm].time_s.size)
        parts[f"{nm} update (m = {m})"] = (per_call_us(_update, (
            P0, H.copy(), np.maximum(R, 1e-6), m, z.copy()), 3000), count)
    K = res.time_s.size
    parts["feedback"] = (per_call_us(_feedback_record, (
        nav, P0, np.zeros(K), np.zeros((K, nav.size)), np.zeros((K, n - 9)), np.zeros((K, n))),
        5000), K)
    mech = bare - n_bare_prop * parts["covariance propagation"][0] * 1e-3
    return {"total_ms": total, "mech_ms": mech, "samples": int(log.imu.n_samples),
            "parts": {k: [us, cnt] for k, (us, cnt) in parts.items()}}


def table(prof: dict) -> list:
    """Markdown rows: part, µs per call, calls, ms, share of the run."""
    tot = prof["total_ms"]
    rows = [f"| mechanization and loop (run without sensors, less its propagations) | "
            f"{1e3 * prof['mech_ms'] / prof['samples']:.3f} | {prof['samples']:,} | "
            f"{prof['mech_ms']:.1f} | {100 * prof['mech_ms'] / tot:.0f} % |"]
    acc = prof["mech_ms"]
    for name, (us, cnt) in prof["parts"].items():
        ms = us * cnt * 1e-3
        acc += ms
        rows.append(f"| {name} | {us:.2f} | {cnt:,} | {ms:.1f} | {100 * ms / tot:.0f} % |")
    rows.append(f"| sum of the parts / measured run | | | {acc:.1f} / {tot:.1f} | |")
    return rows


if __name__ == "__main__":
    out = profile()
    print(json.dumps(out) if "--json" in sys.argv else "\n".join(table(out)))
