"""Trajectories from motion segments: truth at IMU rate and consistent ideal IMU increments.

A vehicle moves along its body forward axis (no side-slip) with speed ``s``, heading ``psi``,
pitch ``theta`` and roll ``gamma``; each segment changes these smoothly (cycloidal profiles,
continuous rates), so the angular rate and specific force are continuous functions of time.
The ideal increments are the exact integrals

    dtheta_b[k] = int_{t_k}^{t_k+1} omega_ib_b dt,   dv_b[k] = int_{t_k}^{t_k+1} f_b dt,

evaluated by Gauss-Legendre quadrature (split at segment boundaries) from the analytic
rates — not by inverting the mechanization — so replaying them through
:mod:`fuzzynav.nav.strapdown` is an independent check of both.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fuzzynav.errors import InputFileError

SEGMENT_KINDS = ("static", "accelerate", "cruise", "turn", "climb", "figure8", "s-turns")


@dataclass(frozen=True)
class Segment:
    """One motion segment of a trajectory.

    Parameters
    ----------
    kind : str
        ``static`` (speed forced to zero), ``accelerate`` (speed changes by
        ``speed_change_mps``), ``cruise`` (everything held), ``turn`` (heading changes by
        ``turn_deg``, or at ``turn_rate_dps`` mean rate, or on ``radius_m``), ``climb``
        (flight-path angle rises to ``pitch_deg``, is held, and returns to level; negative
        dives), ``figure8`` (a full right turn then a full left turn), ``s-turns``
        (``n_turns`` alternating turns of ``turn_deg`` each).
    duration_s : float
        Length of the segment [s].
    speed_change_mps : float
        Speed change of an ``accelerate`` segment [m/s].
    turn_deg : float
        Heading change [deg], positive clockwise (to the right).
    turn_rate_dps, radius_m : float, optional
        Alternatives to ``turn_deg`` for ``turn``: mean turn rate [deg/s] or turn radius [m]
        at the current speed (sign of ``turn_deg`` or of the rate gives the direction).
    pitch_deg : float
        Held pitch of a ``climb`` segment [deg].
    bank : bool
        Bank into turns as a coordinated aircraft turn (roll = atan(v r / g)); ``False``
        keeps the wings level (cars, ships).
    n_turns : int
        Number of alternating turns of an ``s-turns`` segment.
    """

    kind: str
    duration_s: float
    speed_change_mps: float = 0.0
    turn_deg: float = 0.0
    turn_rate_dps: float | None = None
    radius_m: float | None = None
    pitch_deg: float = 0.0
    bank: bool = False
    n_turns: int = 2

    def __post_init__(self):
        if self.kind not in SEGMENT_KINDS:
            raise InputFileError(None, "segment.kind",
                                 f"unknown segment kind {self.kind!r}; known: "
                                 + ", ".join(SEGMENT_KINDS))
        if not (np.isfinite(self.duration_s) and self.duration_s > 0):
            raise InputFileError(None, "segment.duration_s",
                                 f"must be a positive number of seconds, got {self.duration_s!r}")
        if not -80.0 < self.pitch_deg < 80.0:
            raise InputFileError(None, "segment.pitch_deg",
                                 f"must lie within (-80, 80) deg, got {self.pitch_deg!r}")
        if self.kind == "s-turns" and self.n_turns < 1:
            raise InputFileError(None, "segment.n_turns", "must be >= 1")


@dataclass(frozen=True)
class Trajectory:
    """Truth at IMU rate and the ideal IMU increments between samples.

    Attributes
    ----------
    time_s : ndarray, shape (N+1,)
        Sample times [s], uniformly spaced at ``1 / imu_rate_hz``.
    lla : ndarray, shape (N+1, 3)
        Geodetic latitude [rad], longitude [rad], height [m].
    vel_n : ndarray, shape (N+1, 3)
        ENU velocity [m/s].
    att : ndarray, shape (N+1, 3)
        Pitch, roll, heading [rad] (conventions of :mod:`fuzzynav.nav.attitude`).
    q_bn : ndarray, shape (N+1, 4)
        Attitude quaternion of ``C_bn``.
    dtheta_b : ndarray, shape (N, 3)
        Ideal angle increments [rad] over ``[t_k, t_k+1]`` (gyro output, body RFU).
    dv_b : ndarray, shape (N, 3)
        Ideal velocity increments [m/s] over ``[t_k, t_k+1]`` (accelerometer output).
    omega_nb_b : ndarray, shape (N+1, 3)
        Body angular rate relative to the navigation frame [rad/s] at the samples (for
        lever-arm velocity effects of aiding sensors).
    imu_rate_hz : float
    """

    time_s: np.ndarray
    lla: np.ndarray
    vel_n: np.ndarray
    att: np.ndarray
    q_bn: np.ndarray
    dtheta_b: np.ndarray
    dv_b: np.ndarray
    omega_nb_b: np.ndarray
    imu_rate_hz: float
    segments: tuple = field(default=())

    @property
    def n_samples(self) -> int:
        """Number of increments N (one fewer than the truth samples)."""
        return self.dtheta_b.shape[0]

    @property
    def duration_s(self) -> float:
        """Length of the trajectory [s]."""
        return float(self.time_s[-1] - self.time_s[0])
