"""Doppler velocity log: sensor kind ``dvl`` (body-frame velocity over the sea bottom).

Measurement columns (``SensorData.z``): ``v_x, v_y, v_z`` [m/s] in the DVL frame, which is
the body RFU frame (x right, y forward, z up) up to the misalignment below.
``SensorData.sigma`` holds the *claimed* 1-sigma per axis [m/s].

Simulated measurement at each epoch (paper 004's DVL error model, completed)::

    v_dvl = (1 + k) (I - [mu x]) (C_nb v_n + omega_nb_b x l) + e,

* ``k``: scale-factor error (``scale_factor``, paper 004: 0.003), the same on all axes;
* ``mu``: small misalignment angles of the DVL against the body axes [rad]
  (``misalignment_deg``);
* ``l``: lever arm of the DVL from the IMU, body RFU [m] (``lever_arm_b_m``); the
  earth-rate part of the lever-arm velocity is neglected (< 0.1 mm/s for metres);
* ``e``: white noise of 1-sigma ``sigma_mps``; with probability ``contamination`` per epoch
  the variance is ``contamination_factor`` (100) times larger — the contaminated Gaussian
  mixture of paper 004 (it does not say how often: a scenario parameter);
* outliers, with probability ``outlier_rate``, add ``outlier_mps`` in a random direction;
* bottom-lock dropouts: epochs inside ``dropouts`` windows, and random losses of lock that
  start with probability ``dropout_rate`` per epoch and last ``dropout_duration_s``, are
  absent.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from fuzzynav import units
from fuzzynav.errors import InputFileError
from fuzzynav.nav import attitude
from fuzzynav.sim.sensors import SensorData, epoch_indices, register
from fuzzynav.sim.sensors.gnss import in_windows, random_directions
from fuzzynav.sim.tomltable import Table

__all__ = ["Spec"]

_ZERO3 = (0.0, 0.0, 0.0)
_MAX_VEL_MPS = 100.0
_MAX_LEVER_M = 100.0


@register("dvl")
@dataclass(frozen=True)
class Spec:
    """DVL simulation (a ``kind = "dvl"`` sensor table of a scenario).

    Parameters
    ----------
    rate_hz : float
        Ping rate [Hz] (1-2 Hz typical); epochs fall on the nearest IMU sample.
    start_s : float
        Time of the first ping [s].
    sigma_mps : tuple of 3 float
        White-noise 1-sigma per axis [m/s].
    claimed_sigma_mps : tuple of 3 float, optional
        What the filter is told (default: ``sigma_mps``).
    scale_factor : float
        Scale-factor error ``k`` (0.003 = 0.3 %).
    misalignment_deg : tuple of 3 float
        Misalignment angles ``mu`` about body x, y, z [deg].
    lever_arm_b_m : tuple of 3 float
        DVL position relative to the IMU, body RFU [m].
    contamination : float
        Probability per epoch that the noise variance is ``contamination_factor`` times the
        nominal one.
    contamination_factor : float
        Variance factor of contaminated epochs (paper 004: 100).
    outlier_rate, outlier_mps : float
        Probability and size [m/s] of an outlier in a random direction.
    dropouts : tuple of (start_s, end_s)
        Explicit windows without bottom lock.
    dropout_rate, dropout_duration_s : float
        Random losses of lock: probability per epoch that one starts, and its length [s].
    """

    rate_hz: float = 2.0
    start_s: float = 0.0
    sigma_mps: tuple = (0.01, 0.01, 0.01)
    claimed_sigma_mps: tuple | None = None
    scale_factor: float = 0.0
    misalignment_deg: tuple = _ZERO3
    lever_arm_b_m: tuple = _ZERO3
    contamination: float = 0.0
    contamination_factor: float = 100.0
    outlier_rate: float = 0.0
    outlier_mps: float = 0.0
    dropouts: tuple = ()
    dropout_rate: float = 0.0
    dropout_duration_s: float = 10.0

    kind = "dvl"

    def __post_init__(self):
        for name in ("sigma_mps", "claimed_sigma_mps", "misalignment_deg", "lever_arm_b_m"):
            value = getattr(self, name)
            if value is not None:
                value = np.broadcast_to(np.asarray(value, dtype=float), (3,))
                object.__setattr__(self, name, tuple(float(v) for v in value))
        object.__setattr__(self, "dropouts", tuple(tuple(map(float, w)) for w in self.dropouts))
        if not self.rate_hz > 0.0:
            raise InputFileError(None, "rate_hz", f"must be positive, got {self.rate_hz!r}")

    def columns(self) -> int:
        """Measurement columns per epoch (memory budget)."""
        return 3

    def claimed_sigma(self) -> np.ndarray:
        """Claimed 1-sigma per axis [m/s], shape (3,)."""
        c = self.sigma_mps if self.claimed_sigma_mps is None else self.claimed_sigma_mps
        return np.asarray(c, dtype=float)

    def body_velocity(self, truth, idx) -> np.ndarray:
        """Error-free DVL velocity ``(1+k)(I - [mu x])(C_nb v_n + omega_nb_b x l)``, (M, 3)."""
        C_bn = attitude.quat_to_dcm(np.asarray(truth.q_bn)[idx])
        v_b = np.einsum("kji,kj->ki", C_bn, np.asarray(truth.vel_n)[idx])
        v_b += np.cross(np.asarray(truth.omega_nb_b)[idx], np.asarray(self.lever_arm_b_m))
        mu = np.asarray(self.misalignment_deg) * units.DEG
        return (1.0 + self.scale_factor) * (v_b - np.cross(mu, v_b))

    def _noise(self, m, rng):
        """Noise (M, 3), the contaminated-epoch and outlier masks."""
        g_white, g_mix, g_mask, g_dir = rng.spawn(4)
        contaminated = g_mix.random(m) < self.contamination
        scale = np.where(contaminated, np.sqrt(self.contamination_factor), 1.0)
        e = scale[:, None] * np.asarray(self.sigma_mps) * g_white.standard_normal((m, 3))
        outlier = g_mask.random(m) < self.outlier_rate
        e[outlier] += self.outlier_mps * random_directions(g_dir, int(outlier.sum()))
        return e, contaminated, outlier

    def dropout_windows(self, time_s, rng) -> np.ndarray:
        """Explicit plus random loss-of-lock windows, (K, 2) of ``[start, end)`` [s]."""
        starts = time_s[rng.random(time_s.size) < self.dropout_rate]
        rand = np.column_stack([starts, starts + self.dropout_duration_s])
        return np.vstack([np.array(self.dropouts, float).reshape(-1, 2), rand])

    def true_sigma(self, m) -> np.ndarray:
        """1-sigma of the simulated noise distribution per epoch (mixture and outliers)."""
        var = np.square(self.sigma_mps) * (1.0 + self.contamination
                                           * (self.contamination_factor - 1.0))
        var = var + self.outlier_rate * self.outlier_mps ** 2 / 3.0
        return np.tile(np.sqrt(var), (m, 1))

    def simulate(self, truth, rng, start_utc=None) -> SensorData:
        """DVL velocities along ``truth`` (``start_utc`` unused).

        ``meta``: ``lever_arm_b`` [m], ``rate_hz``, ``scale_factor``, ``misalignment_rad``,
        the masks ``contaminated`` and ``outlier_mask``, ``dropout_windows`` and
        ``true_sigma`` (M, 3).
        """
        idx = epoch_indices(truth, self.start_s, self.rate_hz)
        time_s = np.asarray(truth.time_s)[idx]
        g_noise, g_drop = rng.spawn(2)
        e, contaminated, outlier = self._noise(idx.size, g_noise)
        z = self.body_velocity(truth, idx) + e
        windows = self.dropout_windows(time_s, g_drop)
        keep = ~in_windows(time_s, windows)
        sigma = np.tile(self.claimed_sigma(), (int(keep.sum()), 1))
        meta = {"lever_arm_b": np.array(self.lever_arm_b_m, float), "rate_hz": self.rate_hz,
                "scale_factor": float(self.scale_factor),
                "misalignment_rad": np.asarray(self.misalignment_deg) * units.DEG,
                "contaminated": contaminated[keep], "outlier_mask": outlier[keep],
                "dropout_windows": windows, "true_sigma": self.true_sigma(idx.size)[keep]}
        return SensorData(kind="dvl", time_s=time_s[keep], z=z[keep], sigma=sigma, meta=meta)

    @classmethod
    def from_dict(cls, d: dict, where: str) -> "Spec":
        """Parse a sensor table (``kind`` already checked); errors name ``where.key``."""
        t = Table(d, where)
        t.string("kind", "dvl", choices=("dvl",))
        f = cls.__dataclass_fields__
        kw = {"rate_hz": t.number("rate_hz", f["rate_hz"].default, lo=0.0, hi=100.0,
                                  lo_open=True),
              "start_s": t.number("start_s", 0.0, lo=0.0),
              "sigma_mps": t.vector("sigma_mps", 3, f["sigma_mps"].default, lo=0.0,
                                    hi=_MAX_VEL_MPS),
              "claimed_sigma_mps": t.vector("claimed_sigma_mps", 3, None, lo=0.0,
                                            hi=_MAX_VEL_MPS),
              "scale_factor": t.number("scale_factor", 0.0, lo=-0.5, hi=0.5),
              "misalignment_deg": t.vector("misalignment_deg", 3, _ZERO3, lo=-10.0, hi=10.0),
              "lever_arm_b_m": t.vector("lever_arm_b_m", 3, _ZERO3, lo=-_MAX_LEVER_M,
                                        hi=_MAX_LEVER_M),
              "contamination": t.number("contamination", 0.0, lo=0.0, hi=1.0),
              "contamination_factor": t.number("contamination_factor", 100.0, lo=1.0, hi=1e6),
              "outlier_rate": t.number("outlier_rate", 0.0, lo=0.0, hi=1.0),
              "outlier_mps": t.number("outlier_mps", 0.0, lo=0.0, hi=_MAX_VEL_MPS),
              "dropouts": t.windows("dropouts", 2),
              "dropout_rate": t.number("dropout_rate", 0.0, lo=0.0, hi=1.0),
              "dropout_duration_s": t.number("dropout_duration_s", 10.0, lo=0.0)}
        t.finish()
        spec = cls(**kw)
        if not np.all(spec.claimed_sigma() > 0.0):
            key = "claimed_sigma_mps" if kw["claimed_sigma_mps"] is not None else "sigma_mps"
            raise t.error(key, "the claimed 1-sigma is zero on some axis (R = 0 would take "
                               "every ping as exact)")
        return spec

    def to_dict(self) -> dict:
        """The sensor table (TOML-ready, ``None`` fields left out, ``kind`` included)."""
        out = {"kind": self.kind}
        for k, v in asdict(self).items():
            if v is not None:
                out[k] = [list(x) if isinstance(x, tuple) else x for x in v] \
                    if isinstance(v, tuple) else v
        return out
