"""The validation protocol on a real recording: what the filter is fed and how it is scored.

The filter is fed a *degraded copy* of the recording's GNSS fixes — white noise added to
the positions (and optionally the velocities), simulated outages (60 s every 180 s, as in
the KF-GINS evaluation) — and scored against the untouched RTK-fixed epochs
(``reference``): horizontal error RMS, and the horizontal drift at the end of each outage.

The receiver's velocities may lag its positions (RTKLIB's by about 0.14 s on the
rtklib-drive, ``docs/data.md`` §3.5); :attr:`ProtocolSettings.velocity` says what the fed
copy does about it:

* ``shift`` — read each velocity ``velocity_lag_s`` later (the default; best measured);
* ``raw`` — as recorded;
* ``inflate`` — as recorded, with ``velocity_inflate_mps`` added in quadrature to the claimed
  sigma (the RMS velocity difference the lag causes);
* ``off`` — positions only (the KF-GINS set-up).

The reference velocities, used only for the velocity RMS, are always read
``velocity_lag_s`` later.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from fuzzynav.errors import FuzzynavError
from fuzzynav.realdata import degrade
from fuzzynav.sim.sensors import SensorData
from fuzzynav.sim.sensors.gnss import outage_windows

__all__ = ["VELOCITY_MODES", "LIMITS", "ProtocolSettings", "read_later", "degraded_fixes",
           "windows_after", "with_outages"]

VELOCITY_MODES = ("shift", "raw", "inflate", "off")


#: the range of each number of :class:`ProtocolSettings` (infinities and NaN refused):
#: noises beyond these are no longer a GNSS receiver's, lags and outages no longer a run's
LIMITS = {"noise_pos_m": (0.0, 1e3), "noise_vel_mps": (0.0, 1e2),
          "outage_period_s": (0.0, 1e6), "outage_duration_s": (0.0, 1e6),
          "first_outage_s": (0.0, 1e6), "velocity_lag_s": (-10.0, 10.0),
          "velocity_inflate_mps": (0.0, 1e2), "t_start_s": (0.0, 1e7),
          "nhc_sigma_mps": (0.0, 1e2), "nhc_rate_hz": (0.0, 1e4)}


@dataclass(frozen=True)
class ProtocolSettings:
    """Every number of the protocol.

    Parameters
    ----------
    noise_pos_m : float
        1-sigma white noise added to each ENU position axis [m]; the fed sigma is the RTK
        sigma and this in quadrature.
    noise_vel_mps : float
        1-sigma white noise added to each velocity axis [m/s].
    outage_period_s, outage_duration_s : float
        Simulated outages: ``outage_duration_s`` without fixes every ``outage_period_s``
        (duration 0 = none).
    first_outage_s : float or None
        Start of the first outage, seconds after the filter's start (the end of the
        opening rest); ``None`` = one period.
    velocity : str
        One of :data:`VELOCITY_MODES` (module docstring).
    velocity_lag_s : float
        How late the receiver's velocities are [s].
    velocity_inflate_mps : float
        Added in quadrature to the velocity sigma in ``inflate`` mode [m/s].
    t_start_s : float
        Scoring starts here [s on the recording's clock] (or at the filter's start if later).
    nhc_sigma_mps : float
        1-sigma of the non-holonomic constraints (zero lateral and vertical body velocity,
        :mod:`fuzzynav.filters.measurements.nhc`) fed at ``nhc_rate_hz``; 0 = none.
    nhc_rate_hz : float
        Rate of the constraint pseudo-measurements [Hz].
    """

    noise_pos_m: float = 2.0
    noise_vel_mps: float = 0.0
    outage_period_s: float = 180.0
    outage_duration_s: float = 60.0
    first_outage_s: float | None = None
    velocity: str = "shift"
    velocity_lag_s: float = 0.14
    velocity_inflate_mps: float = 0.16
    t_start_s: float = 0.0
    nhc_sigma_mps: float = 0.0
    nhc_rate_hz: float = 10.0

    def __post_init__(self):
        if self.velocity not in VELOCITY_MODES:
            raise FuzzynavError(f"velocity mode {self.velocity!r}: expected one of "
                                f"{', '.join(VELOCITY_MODES)}")
        for name, (lo, hi) in LIMITS.items():
            value = getattr(self, name)
            if value is not None and not lo <= value <= hi:  # NaN fails too
                raise FuzzynavError(f"{name} must lie in [{lo:g}, {hi:g}], got {value}")
        if self.outage_duration_s > 0.0 and not (self.outage_period_s > self.outage_duration_s):
            raise FuzzynavError(f"outage_period_s ({self.outage_period_s}) must exceed "
                                f"outage_duration_s ({self.outage_duration_s})")
        if not self.nhc_rate_hz > 0.0:
            raise FuzzynavError(f"nhc_rate_hz must be > 0, got {self.nhc_rate_hz}")

    @property
    def use_velocity(self) -> bool:
        """Whether the filter is fed the GNSS velocities."""
        return self.velocity != "off"

    def as_dict(self) -> dict:
        """The settings as plain numbers and strings (JSON, reports)."""
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def read_later(vel: np.ndarray, time_s: np.ndarray, lag_s: float) -> np.ndarray:
    """Velocities read ``lag_s`` later (linear interpolation; ends held), shape (M, 3)."""
    if not lag_s:
        return vel.copy()
    return np.column_stack([np.interp(time_s + lag_s, time_s, vel[:, j]) for j in range(3)])


def degraded_fixes(gnss: SensorData, settings: ProtocolSettings, rng) -> SensorData:
    """The noisy copy of the fixes with the velocity treatment applied (no outages yet).

    Parameters
    ----------
    gnss : SensorData
        The recording's fixes (kind ``gnss``).
    settings : ProtocolSettings
    rng : numpy.random.Generator
        Source of the added noise.
    """
    z, sigma = gnss.z.copy(), gnss.sigma.copy()
    # the receiver's lag is treated first, so that the added noise stays white
    if settings.velocity == "shift":
        z[:, 3:6] = read_later(z[:, 3:6], gnss.time_s, settings.velocity_lag_s)
    elif settings.velocity == "inflate":
        sigma[:, 3:6] = np.hypot(sigma[:, 3:6], settings.velocity_inflate_mps)
    return degrade.add_white_noise(replace(gnss, z=z, sigma=sigma), settings.noise_pos_m, rng,
                                   sigma_vel_mps=settings.noise_vel_mps)


def windows_after(start_s: float, end_s: float, settings: ProtocolSettings) -> np.ndarray:
    """Outage windows ``[a, b)`` (K, 2) that start after ``start_s`` and before ``end_s``."""
    if settings.outage_duration_s <= 0.0:
        return np.zeros((0, 2))
    first = settings.outage_period_s if settings.first_outage_s is None \
        else settings.first_outage_s
    return outage_windows(end_s, (), settings.outage_period_s, settings.outage_duration_s,
                          start_s + first)


def with_outages(fed: SensorData, windows: np.ndarray) -> SensorData:
    """The fixes without the epochs inside ``windows`` (``meta['outage_windows']`` set)."""
    return degrade.with_outages(fed, period_s=0.0, duration_s=0.0, windows=windows)

