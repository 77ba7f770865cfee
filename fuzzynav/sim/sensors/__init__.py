"""Aiding-sensor simulators and the registry of sensor kinds.

A sensor kind is one module here defining a frozen ``Spec`` dataclass with

* ``Spec.from_dict(d: dict, where: str) -> Spec`` — parse a scenario-file table, raising
  :class:`fuzzynav.errors.InputFileError` with ``where`` (the TOML key path) on bad input;
* ``spec.simulate(truth: Trajectory, rng: numpy.random.Generator, start_utc) -> SensorData``;

and registering it with :func:`register` (and naming its module in
``SENSOR_KINDS.builtin_modules`` for built-ins).  The filter side pairs each kind with a
measurement model of the same name (:mod:`fuzzynav.filters.measurements`).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from fuzzynav.registry import Registry

#: kind name -> Spec class
SENSOR_KINDS = Registry("sensor kind", __name__, ("gnss", "polarization", "magnetometer", "bds",
                                                  "log", "nhc", "neutral_point", "dvl"))


def register(kind: str):
    """Class decorator registering a sensor ``Spec`` under ``kind``."""

    def deco(cls):
        cls.kind = kind
        return SENSOR_KINDS.add(kind, cls)

    return deco


def spec_class(kind: str) -> type:
    """The ``Spec`` class registered for ``kind`` (clear error when unknown)."""
    return SENSOR_KINDS.lookup(kind)


def spec_table(spec, rename=None) -> dict:
    """A sensor ``Spec`` as its scenario table (TOML-ready, what ``from_dict`` reads back).

    ``kind`` first, ``None`` fields left out, tuples as lists, nested dataclasses (noise
    windows, disturbance zones) as tables; ``rename`` maps field names to TOML keys.
    """
    rename = rename or {}
    out = {"kind": spec.kind}
    for k, v in asdict(spec).items():
        if v is None:
            continue
        if isinstance(v, tuple):
            v = [list(x) if isinstance(x, tuple) else x for x in v]
        out[rename.get(k, k)] = v
    return out


def epoch_indices(truth, start_s: float, rate_hz: float) -> np.ndarray:
    """Indices of the IMU samples nearest to a sensor's epochs ``start_s + k / rate_hz``."""
    t = np.asarray(truth.time_s)
    t_meas = np.arange(start_s, t[-1] + 1e-9, 1.0 / rate_hz)
    idx = np.round((t_meas - t[0]) * truth.imu_rate_hz).astype(np.int64)
    return np.unique(idx[(idx >= 0) & (idx < t.size)])


@dataclass(frozen=True)
class SensorData:
    """Measurements of one aiding sensor over a run.

    Attributes
    ----------
    kind : str
        Registered sensor kind (selects the filter's measurement model).
    time_s : ndarray, shape (M,)
        Measurement times [s] on the IMU clock.
    z : ndarray, shape (M, m)
        Measurements in SI units; the columns are documented by each kind.
    sigma : ndarray, shape (M, m)
        The 1-sigma each measurement *claims* (what a filter is told); the simulated error
        may differ from it (noise mismatch is what adaptive filters are for).
    meta : dict
        Kind-specific constants (e.g. ``lever_arm_b`` [m]); numbers or numpy arrays only.
    """

    kind: str
    time_s: np.ndarray
    z: np.ndarray
    sigma: np.ndarray
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        m = self.z.shape[0]
        if self.time_s.shape != (m,) or self.sigma.shape != self.z.shape:
            raise ValueError(f"SensorData({self.kind}): inconsistent shapes "
                             f"time {self.time_s.shape}, z {self.z.shape}, sigma {self.sigma.shape}")
