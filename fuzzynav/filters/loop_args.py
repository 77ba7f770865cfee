"""The argument bundles of the compiled filter loop (:mod:`fuzzynav.filters.loop`).

Named tuples of plain arrays and scalars: numba types them field by field, and the loop's
signature stays the same whoever fills them (:mod:`fuzzynav.filters.runner`).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from fuzzynav.filters.bank_beta import ShareControl


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
