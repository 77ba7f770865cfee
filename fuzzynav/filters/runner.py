"""Run a filter: pack Python objects into arrays, call the compiled loop, bundle the result."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters import adaptation, measurements
from fuzzynav.filters.adaptation import N_DIAG, NoAdaptation
from fuzzynav.filters.bank_beta import share_control
from fuzzynav.filters.config import FilterConfig
from fuzzynav.filters.error_st import EM_ST, error_model_code, st_covariance
from fuzzynav.filters.layout import N_CORE
from fuzzynav.filters import loop
from fuzzynav.filters.numba_patch_dispatch import memoise_kernel_addresses
from fuzzynav.filters.result import EventLog, FilterResult, LocalStates
from fuzzynav.nav import strapdown
from fuzzynav.nav.state_layout import LLA_SLICE, NAV_SIZE, Q_SLICE, VEL_SLICE

# the kernel tables are the same few tuples run after run: numba types them once (every
# loop's tables: fuzzynav.filters.loop), and looks their kernels' addresses up once
memoise_kernel_addresses()


@dataclass(frozen=True)
class InitialState:
    """The filter's initial navigation state.

    Attributes
    ----------
    time_s : float
        Time of the state (must equal the first IMU sample time).
    lla : (3,) latitude [rad], longitude [rad], height [m].
    vel_n : (3,) ENU velocity [m/s].
    q_bn : (4,) attitude quaternion.
    """

    time_s: float
    lla: np.ndarray
    vel_n: np.ndarray
    q_bn: np.ndarray


def _imu_arrays(imu):
    """The IMU arrays as the loop takes them, checked, and the nominal sample interval."""
    time_s = np.ascontiguousarray(imu.time_s, dtype=float)
    dth = np.ascontiguousarray(imu.dtheta_b, dtype=float)
    dv = np.ascontiguousarray(imu.dv_b, dtype=float)
    if time_s.shape != (dth.shape[0] + 1,) or dv.shape != dth.shape:
        raise FuzzynavError(f"IMU arrays disagree: time {time_s.shape}, dtheta {dth.shape}, "
                            f"dv {dv.shape} (time needs one entry more than the increments)")
    step = np.diff(time_s)
    if np.any(step <= 0):
        raise FuzzynavError("IMU sample times must increase strictly")
    dt_nom = float(np.median(step))
    return time_s, dth, dv, dt_nom


def _sensor_tables(sensors, adapters, options, gate_probability):
    """Per-sensor kernel ids, parameters, adapter arrays and gates; the merged event list."""
    names = sorted(sensors)
    models = [measurements.get(sensors[nm].kind) for nm in names]
    # only the models this run uses are compiled (the others' slots hold a stand-in)
    meas_fns, meas_index = measurements.kernel_table({measurements.MODELS.index()[m.kind]
                                                      for m in models})
    M = max([mdl.max_rows for mdl in models], default=1)
    rows = [mdl.rows(sensors[nm]) for nm, mdl in zip(names, models)]
    bounds = [adapters.get(nm, NoAdaptation()).bind(mdl, r)
              for nm, mdl, r in zip(names, models, rows)]
    pars = [np.asarray(mdl.pack(sensors[nm], options.get(nm, {})), float)
            for nm, mdl in zip(names, models)]
    s_mpar = np.zeros((max(len(names), 1), max([p.size for p in pars], default=1)))
    for i, p in enumerate(pars):
        s_mpar[i, :p.size] = p
    W = max([r.shape[1] for r in rows], default=1)
    ev_t = np.concatenate([sensors[nm].time_s for nm in names] or [np.zeros(0)]).astype(float)
    ev_s = np.concatenate([np.full(len(r), i) for i, r in enumerate(rows)] or [np.zeros(0)])
    ev_data = np.zeros((ev_t.size, W))
    o = 0
    for r in rows:
        ev_data[o:o + len(r), :r.shape[1]] = r
        o += len(r)
    order = np.argsort(ev_t, kind="stable")
    gate = np.zeros((max(len(names), 1), M + 1))
    if gate_probability is not None:
        gate[:, 1:] = chi2.ppf(gate_probability, np.arange(1, M + 1))

    def flat(arrs, dtype):
        off = np.concatenate([[0], np.cumsum([a.size for a in arrs])]).astype(np.int64)
        cat = np.concatenate(arrs).astype(dtype) if arrs else np.zeros(1, dtype)
        return (cat if cat.size else np.zeros(1, dtype)), off

    afp, afp_off = flat([b.fp for b in bounds], float)
    aip, aip_off = flat([b.ip for b in bounds], np.int64)
    ast, ast_off = flat([b.state for b in bounds], float)
    return dict(names=names, models=models, bounds=bounds, M=M, meas_fns=meas_fns,
                s_meas=np.array([meas_index[m.kind] for m in models] or [0], np.int64),
                s_mpar=s_mpar, ev_t=np.ascontiguousarray(ev_t[order]),
                ev_s=np.ascontiguousarray(ev_s[order].astype(np.int64)),
                ev_data=np.ascontiguousarray(ev_data[order]), order=order,
                s_adapt=_adapter_ids(bounds),
                afp=afp, afp_off=afp_off, aip=aip, aip_off=aip_off, ast=ast, ast_off=ast_off,
                gate=gate)


def run_filter(imu, sensors, init: InitialState, config: FilterConfig = FilterConfig(),
               adapters=None, sensor_options=None) -> FilterResult:
    """Run the closed-loop error-state filter.

    Parameters
    ----------
    imu : object
        With ``time_s`` (N+1,), ``dtheta_b`` (N, 3) [rad] and ``dv_b`` (N, 3) [m/s]
        (a :class:`~fuzzynav.sim.trajectory.Trajectory` or a simulated/real IMU log).
    sensors : mapping name -> SensorData
        Aiding measurements; each kind needs a registered measurement model.
    init : InitialState
        Initial navigation state at ``imu.time_s[0]``.
    config : FilterConfig
    adapters : mapping name -> Adapter, optional
        Adaptation policy per sensor (default: none, the plain EKF).
    sensor_options : mapping name -> dict, optional
        Options for the measurement models (e.g. ``{"gnss": {"use_velocity": False}}``).

    Returns
    -------
    FilterResult
    """
    time_s, dth, dv, dt_nom = _imu_arrays(imu)
    tb = _sensor_tables(dict(sensors), dict(adapters or {}), dict(sensor_options or {}),
                        config.gate_probability)
    blk_start, blk_kind, blk_inv_tau = config.model.block_arrays()
    n = config.model.n_states
    em = error_model_code(config.error_model)
    bank, state = _bank(config, tb["names"], init, em)
    stride = max(1, int(round(1.0 / (config.out_rate_hz * dt_nom))))
    K, NL = dth.shape[0] // stride + 1, bank.beta.size
    E, M = tb["ev_t"].size, tb["M"]
    # the loop writes whole output rows, in order; the time column (NaN until written) tells
    # how many it wrote, so the other arrays need no filling
    KL = K if NL > 1 else 1  # a bank of one records no local outputs (record.record_output)
    out = dict(t=np.full(K, np.nan), nav=np.empty((K, NAV_SIZE)), xs=np.empty((K, n - N_CORE)),
               sig=np.empty((K, n)), xl=np.empty((KL, NL, n)), sigl=np.empty((KL, NL, n)),
               beta=np.empty((KL, NL)))
    ev = dict(r=np.full((E, M), np.nan), S=np.full((E, M), np.nan), nis=np.full(E, np.nan),
              flag=np.zeros(E, np.int64), diag=np.full((E, N_DIAG), np.nan))
    nav0 = strapdown.make_nav(init.lla, init.vel_n, init.q_bn)
    adapt_fns, _ = adaptation.kernel_table(used=tb["s_adapt"])  # the used policies only
    # the loop without the bank's / the ST model's code when the run has none (cold start)
    run_loop = loop.loop_for(NL, em, bank.ctl.on)
    status, done = run_loop(
        loop.Imu(dth, dv, time_s), loop.Start(nav0, np.zeros(n - N_CORE)),
        loop.Model(blk_start, blk_kind, blk_inv_tau, em),
        loop.Events(tb["ev_t"], tb["ev_s"], tb["ev_data"]),
        loop.Sensors(tb["s_meas"], tb["s_mpar"], tb["s_adapt"], tb["afp"], tb["afp_off"],
                     tb["aip"], tb["aip_off"], tb["ast"], tb["ast_off"], tb["gate"]),
        bank, state, tb["meas_fns"], adapt_fns,
        loop.Settings(float(config.max_prop_dt_s), int(stride)),
        loop.Outputs(**out), loop.EventOutputs(**ev))
    return _bundle(out, ev, tb, config, status, done, time_s, state, bank.beta)


def _adapter_ids(bounds) -> np.ndarray:
    """The loop's adapter id per sensor: :data:`~fuzzynav.filters.loop.NO_ADAPTER` where the
    plain EKF's policy is bound (its call, all ones, is skipped)."""
    none = adaptation.kernel_table()[1][NoAdaptation.name]
    ids = [loop.NO_ADAPTER if b.kernel_id == none else b.kernel_id for b in bounds]
    return np.array(ids or [0], np.int64)


def _bank(config: FilterConfig, names, init: InitialState, em: int):
    """The loop's :class:`~fuzzynav.filters.loop.Bank` and initial
    :class:`~fuzzynav.filters.loop.BankState`: local ``i`` starts from ``P0 / beta_i`` with
    noise densities ``q / beta_i`` (no bank: the bank of one, every sensor, ``beta = 1``)."""
    spec = config.bank
    if spec is None:
        local, beta, reset, period = np.zeros(max(len(names), 1), np.int64), (1.0,), 1, 0.0
        ctl = share_control(1)
    else:
        local, beta = spec.sensor_locals(names), spec.beta
        reset, period = spec.mode_code(), float(spec.fusion_period_s)
        ctl = share_control(spec.n_local) if spec.controller is None else \
            spec.controller.share_control(spec.n_local)
    P0 = st_covariance(config.P0(), init.vel_n) if em == EM_ST else config.P0()
    b = np.asarray(beta, float)
    n = P0.shape[0]
    # beta = 1 divides exactly: the bank of one starts from the single filter's arrays
    state = loop.BankState(P=np.ascontiguousarray(P0[None] / b[:, None, None]),
                           x=np.zeros((b.size, n)),
                           qd=np.ascontiguousarray(config.q_diag()[None] / b[:, None]),
                           Pg=P0.copy(), xg=np.zeros(n))
    return loop.Bank(local, b.copy(), int(reset), period, ctl), state


def _bundle(out, ev, tb, config, status, done, time_s, state, beta) -> FilterResult:
    # rows are written in order from the first: the written ones are a prefix, kept as views
    kept = int(np.count_nonzero(np.isfinite(out["t"])))
    keep = slice(0, kept)
    events = {}
    for i, (nm, mdl, bd) in enumerate(zip(tb["names"], tb["models"], tb["bounds"])):
        # an index array: take() gathers the rows several times faster than a boolean mask
        sel = np.flatnonzero(tb["ev_s"] == i)
        events[nm] = EventLog(time_s=tb["ev_t"].take(sel), residual=ev["r"].take(sel, 0),
                              S_diag=ev["S"].take(sel, 0), nis=ev["nis"].take(sel),
                              flag=ev["flag"].take(sel),
                              diag=ev["diag"][:, :len(bd.diag_names)].take(sel, 0),
                              diag_names=bd.diag_names, channels=mdl.channels)
    nav = out["nav"][keep]
    msg = "ok" if status == loop.ST_OK else (
        f"stopped at t = {time_s[done]:.2f} s: covariance lost positive definiteness")
    layout = config.model.layout
    return FilterResult(time_s=out["t"][keep], lla=nav[:, LLA_SLICE], vel_n=nav[:, VEL_SLICE],
                        q_bn=nav[:, Q_SLICE], sensor_states=out["xs"][keep],
                        sigma=out["sig"][keep], state_labels=layout.labels(), events=events,
                        status=msg, layout=layout,
                        locals=_locals(out, keep, kept, state, beta))


def _locals(out, keep, kept, state, beta) -> LocalStates:
    """The locals' outputs; a bank of one's are its master's (zero error state after each
    feedback, the fused sigma, a constant share), which the loop leaves unrecorded."""
    if beta.size > 1:
        return LocalStates(out["xl"][keep], out["sigl"][keep], state.P, state.Pg,
                           out["beta"][keep])
    return LocalStates(np.zeros((kept, 1, state.x.shape[1])), out["sig"][keep][:, None, :],
                       state.P, state.Pg, np.full((kept, 1), beta[0]))
