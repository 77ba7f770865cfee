"""The result bundle of a filter run."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fuzzynav.nav import attitude


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
class FilterResult:
    """Navigation solution, uncertainty and per-sensor logs of a run.

    Attributes
    ----------
    time_s : (K,) output times [s].
    lla : (K, 3) latitude [rad], longitude [rad], height [m].
    vel_n : (K, 3) ENU velocity [m/s].
    q_bn : (K, 4) attitude quaternion.
    sensor_states : (K, n-9) estimated sensor errors per block (SI).
    sigma : (K, n) square roots of the covariance diagonal (SI; position in metres).
    state_labels : names of the n states.
    events : sensor name -> :class:`EventLog`.
    status : ``"ok"`` or a description of why the run stopped early.
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
    gyro_blocks: tuple = (0,)
    accel_blocks: tuple = (1,)

    @property
    def att(self) -> np.ndarray:
        """Pitch, roll, heading [rad] (heading in [0, 2 pi))."""
        return attitude.quat_to_euler(self.q_bn)

    @property
    def gyro_bias(self) -> np.ndarray:
        """Total estimated gyro bias [rad/s], shape (K, 3)."""
        return sum(self.sensor_states[:, 3 * b:3 * b + 3] for b in self.gyro_blocks)

    @property
    def accel_bias(self) -> np.ndarray:
        """Total estimated accelerometer bias [m/s^2], shape (K, 3)."""
        return sum(self.sensor_states[:, 3 * b:3 * b + 3] for b in self.accel_blocks)

    @property
    def ok(self) -> bool:
        """True when the run reached the end."""
        return self.status == "ok"
