"""The result bundle of a filter run."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fuzzynav.filters.layout import LAYOUT_15, StateLayout
from fuzzynav.nav import attitude

__all__ = ["EventLog", "LocalStates", "FilterResult"]


@dataclass(frozen=True)
class EventLog:
    """Per-epoch record of one sensor stream.

    Attributes
    ----------
    time_s : (E,) measurement times [s].
    residual : (E, m) INS-minus-sensor residuals (the innovations; NaN where absent).
    S_diag : (E, m) innovation variances after adaptation.
    nis : (E,) normalised innovation squared (NaN when not formed).
    flag : (E,) int: 1 accepted, 2 gated, 3 no rows, 4 S not positive definite,
        5 before the first IMU sample, 0 after the last.
    diag : (E, k) adaptation diagnostics named by ``diag_names``.
    """

    time_s: np.ndarray
    residual: np.ndarray
    S_diag: np.ndarray
    nis: np.ndarray
    flag: np.ndarray
    diag: np.ndarray
    diag_names: tuple = ()
    channels: tuple = ()

    def diagnostic(self, name: str) -> np.ndarray:
        """One adaptation diagnostic over time (e.g. ``"alpha"``)."""
        return self.diag[:, self.diag_names.index(name)]

    @property
    def accepted(self) -> np.ndarray:
        """Boolean mask of epochs used in an update."""
        return self.flag == 1


@dataclass(frozen=True)
class LocalStates:
    """The local filters of a bank (:mod:`fuzzynav.filters.bank`; one for a single filter).

    Attributes
    ----------
    x : (K, L, n) each local's error state about the recorded navigation solution (its own
        estimate of the truth is the solution minus ``x``), as of the local's last update or
        covariance propagation: between measurement epochs it lags the solution.
    sigma : (K, L, n) each local's 1-sigma (the fused one is ``FilterResult.sigma``).
    P_end : (L, n, n) each local's covariance at the end of the run.
    P_fused : (n, n) the master's covariance at the last fusion (a bank of one never fuses:
        there it is the initial covariance).
    beta : (K, L) each local's information share (constant unless a share controller sets
        them, :mod:`fuzzynav.filters.bank_beta`).
    """

    x: np.ndarray
    sigma: np.ndarray
    P_end: np.ndarray
    P_fused: np.ndarray
    beta: np.ndarray | None = None


@dataclass(frozen=True)
class FilterResult:
    """Navigation solution, uncertainty and per-sensor logs of a run.

    Attributes
    ----------
    time_s : (K,) output times [s].
    lla : (K, 3) latitude [rad], longitude [rad], height [m].
    vel_n : (K, 3) ENU velocity [m/s].
    q_bn : (K, 4) attitude quaternion.
    sensor_states : (K, n - N_CORE) estimated sensor errors, the blocks after the
        navigation core in ``layout`` order (SI).
    sigma : (K, n) square roots of the covariance diagonal (SI; position in metres).
    state_labels : names of the n states.
    events : sensor name -> :class:`EventLog`.
    status : ``"ok"`` or a description of why the run stopped early.
    layout : the :class:`~fuzzynav.filters.layout.StateLayout` of the error state.
    locals : :class:`LocalStates` or None, the local filters of the bank.
    """

    time_s: np.ndarray
    lla: np.ndarray
    vel_n: np.ndarray
    q_bn: np.ndarray
    sensor_states: np.ndarray
    sigma: np.ndarray
    state_labels: tuple
    events: dict = field(default_factory=dict)
    status: str = "ok"
    layout: StateLayout = LAYOUT_15
    locals: LocalStates | None = None

    @property
    def att(self) -> np.ndarray:
        """Pitch, roll, heading [rad] (heading in [0, 2 pi))."""
        return attitude.quat_to_euler(self.q_bn)

    @property
    def gyro_bias(self) -> np.ndarray:
        """Total estimated gyro bias [rad/s], shape (K, 3)."""
        return self._block_sum("gyro_bias")

    @property
    def accel_bias(self) -> np.ndarray:
        """Total estimated accelerometer bias [m/s^2], shape (K, 3)."""
        return self._block_sum("accel_bias")

    def _block_sum(self, kind):
        return sum(self.sensor_states[:, self.layout.sensor_slice(nm)]
                   for nm in self.layout.of_kind(kind))

    def state_sigma(self, block: str) -> np.ndarray:
        """1-sigma of the states of ``block`` (e.g. ``"pos"``), shape (K, block size)."""
        return self.sigma[:, self.layout[block]]

    @property
    def ok(self) -> bool:
        """True when the run reached the end."""
        return self.status == "ok"
