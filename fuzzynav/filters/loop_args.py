"""The argument bundles of the compiled filter loop (:mod:`fuzzynav.filters.loop`).

Named tuples of plain arrays and scalars: numba types them field by field, and the loop's
signature stays the same whoever fills them (:mod:`fuzzynav.filters.runner`).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from fuzzynav.filters.bank_beta import ShareControl

__all__ = ["Imu", "Start", "Bank", "BankState", "Model", "Events", "Sensors", "Settings",
           "Outputs", "EventOutputs", "NavCarry", "Propagation", "UpdateWork", "AdaptWork",
           "FusionWork", "Carry", "new_carry"]


class Imu(NamedTuple):
    """IMU increments: ``dth``, ``dv`` (N, 3) [rad, m/s] and ``time_s`` (N+1,)."""

    dth: np.ndarray
    dv: np.ndarray
    time_s: np.ndarray


class Start(NamedTuple):
    """Initial state: ``nav0`` (nav layout) and sensor states ``xs0``."""

    nav0: np.ndarray
    xs0: np.ndarray


class Bank(NamedTuple):
    """The bank: local filter of each sensor, information shares ``beta`` (per local;
    written when ``ctl`` sets them), reset mode (1) or not (0), fusion period [s] (0 = after
    every accepted update), the share controller (:mod:`fuzzynav.filters.bank_beta`)."""

    local: np.ndarray
    beta: np.ndarray
    reset: int
    period: float
    ctl: ShareControl


class BankState(NamedTuple):
    """Per-local covariance ``P`` (L, n, n), error state ``x`` (L, n) and process-noise
    densities ``qd`` (L, n) (initial values in, final values out); the last fused ``Pg``
    (n, n) and ``xg`` (n,)."""

    P: np.ndarray
    x: np.ndarray
    qd: np.ndarray
    Pg: np.ndarray
    xg: np.ndarray


class Model(NamedTuple):
    """Error model: the sensor blocks' start, coupling and 1/tau, and the error-model code
    (:data:`fuzzynav.filters.error_st.ERROR_MODELS`)."""

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
    """Per sensor: measurement-kernel id and constants, adapter id (:data:`NO_ADAPTER` for
    none) and its flat arrays (``afp[afp_off[s]:afp_off[s + 1]]`` ...), chi-square gate
    per row count."""

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
    """Recorded solution (every ``out_stride`` samples): time, nav, sensor states, the
    fused sigma, per local filter its error state ``xl`` and sigma ``sigl`` (K, L, n), and
    the information shares ``beta`` (K, L).  A bank of one writes none of the last three
    (:func:`~fuzzynav.filters.record.record_output`): they may be placeholders of any length."""

    t: np.ndarray
    nav: np.ndarray
    xs: np.ndarray
    sig: np.ndarray
    xl: np.ndarray
    sigl: np.ndarray
    beta: np.ndarray


class EventOutputs(NamedTuple):
    """Per event: residual, S diagonal, NIS, flag, adaptation diagnostics."""

    r: np.ndarray
    S: np.ndarray
    nis: np.ndarray
    flag: np.ndarray
    diag: np.ndarray


class NavCarry(NamedTuple):
    """The navigation side: state ``nav``, the strapdown's previous increments ``prev``, the
    sensor states ``xs``, the attitude matrix ``C``, the total gyro / accelerometer biases
    ``bg``, ``ba`` (formed when ``xs`` changes) and the latest bias-corrected increments
    ``dth_c``, ``dv_c``."""

    nav: np.ndarray
    prev: np.ndarray
    xs: np.ndarray
    C: np.ndarray
    bg: np.ndarray
    ba: np.ndarray
    dth_c: np.ndarray
    dv_c: np.ndarray


class Propagation(NamedTuple):
    """The covariance propagation: the sums of attitude matrix and specific force over the
    interval (``sumC``, ``sumf``; ``dv_sf`` the last sample's), their means ``Cm``, ``fm``,
    ``F``, ``Phi``, ``Qd``, per local the discrete noise since its last update ``Qacc``
    (L, n, n), a full noise density ``Qc`` and scratch ``work`` (n, n), ``dx`` (n,)."""

    sumC: np.ndarray
    sumf: np.ndarray
    dv_sf: np.ndarray
    Cm: np.ndarray
    fm: np.ndarray
    F: np.ndarray
    Phi: np.ndarray
    Qd: np.ndarray
    Qacc: np.ndarray
    Qc: np.ndarray
    work: np.ndarray
    dx: np.ndarray


class UpdateWork(NamedTuple):
    """An epoch's measurement ``z``, ``H``, ``R``, channels, and the update's products and
    scratch (``M`` rows at most: ``P H^T``, ``H P H^T``, ``S`` and its factor ``L``, gain,
    the Joseph form's ``A P`` and ``A P H^T``, correction ``dx``, vector scratch ``wv``)."""

    H: np.ndarray
    z: np.ndarray
    R: np.ndarray
    chan: np.ndarray
    PHt: np.ndarray
    HPH: np.ndarray
    S: np.ndarray
    L: np.ndarray
    K: np.ndarray
    AP: np.ndarray
    APHt: np.ndarray
    dx: np.ndarray
    wv: np.ndarray


class AdaptWork(NamedTuple):
    """What the measurement models and the adaptation policies read and write: the
    policy's weights ``out_a`` (P, Q, R per row), its diagnostics ``diag`` (kept from the
    last epoch), the epoch context ``ctx`` and the models' inputs ``aux``."""

    out_a: np.ndarray
    diag: np.ndarray
    ctx: np.ndarray
    aux: np.ndarray


class FusionWork(NamedTuple):
    """The bank's fusion scratch (:func:`~fuzzynav.filters.bank_fusion.fusion_work`), the
    master's covariance and state between fusions ``Pf``, ``xf``, and the fused ST
    estimate's phi form ``xphi``."""

    work: tuple
    Pf: np.ndarray
    xf: np.ndarray
    xphi: np.ndarray


class Carry(NamedTuple):
    """Everything the loop keeps from one IMU sample to the next that is not in
    :class:`BankState`, by the step that uses it (some scratch holds values between
    epochs, e.g. the last adaptation diagnostics), then the clock scalars and the counters
    (``CN_EVENT`` ... in :mod:`fuzzynav.filters.loop`).  Made by :func:`new_carry`; the loop
    fills it on its first chunk and updates it in place."""

    nv: NavCarry
    acc: Propagation
    up: UpdateWork
    ad: AdaptWork
    fu: FusionWork
    clock: np.ndarray
    count: np.ndarray


def new_carry(n: int, n_local: int, M: int, n_diag: int, ctx_size: int) -> Carry:
    """A fresh :class:`Carry` for ``n`` error states, ``n_local`` locals, ``M`` measurement
    rows at most, ``n_diag`` adaptation diagnostics and a policy context of ``ctx_size``
    (every array zero: the loop's first chunk sets the start)."""
    from fuzzynav.filters.bank_fusion import fusion_work
    from fuzzynav.filters.layout import AUX_XS, N_CORE
    from fuzzynav.nav.state_layout import NAV_SIZE, PREV_SIZE

    z = np.zeros
    dx = z(n)  # the propagation's and the update's vector scratch: never both at once
    return Carry(
        nv=NavCarry(nav=z(NAV_SIZE), prev=z(PREV_SIZE), xs=z(n - N_CORE), C=z((3, 3)),
                    bg=z(3), ba=z(3), dth_c=z(3), dv_c=z(3)),
        acc=Propagation(sumC=z((3, 3)), sumf=z(3), dv_sf=z(3), Cm=z((3, 3)), fm=z(3),
                        F=z((n, n)), Phi=z((n, n)), Qd=z((n, n)),
                        Qacc=z((n_local, n, n)), Qc=z((n, n)), work=z((n, n)), dx=dx),
        up=UpdateWork(H=z((M, n)), z=z(M), R=z(M), chan=z(M, dtype=np.int64),
                      PHt=z((n, M)), HPH=z((M, M)), S=z((M, M)), L=z((M, M)),
                      K=z((n, M)), AP=z((n, n)), APHt=z((n, M)), dx=dx, wv=z(max(n, M))),
        ad=AdaptWork(out_a=z(2 + M), diag=z(n_diag), ctx=z(ctx_size),
                     aux=z(AUX_XS + n - N_CORE)),
        fu=FusionWork(work=fusion_work(n), Pf=z((n, n)), xf=z(n), xphi=z(n)),
        clock=z(2), count=z(6, dtype=np.int64))
