"""Aiding-sensor simulators and the registry of sensor kinds.

A sensor kind is one module here defining a frozen ``Spec`` dataclass with

* ``Spec.from_dict(d: dict, where: str) -> Spec`` — parse a scenario-file table, raising
  :class:`fuzzynav.errors.InputFileError` with ``where`` (the TOML key path) on bad input;
* ``spec.simulate(truth: Trajectory, rng: numpy.random.Generator, start_utc) -> SensorData``;

and registering it with :func:`register`.  The filter side pairs each kind with a
measurement model of the same name (:mod:`fuzzynav.filters.measurements`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fuzzynav.errors import UnknownNameError

#: kind name -> Spec class
SENSOR_KINDS: dict[str, type] = {}


def register(kind: str):
    """Class decorator registering a sensor ``Spec`` under ``kind``."""

    def deco(cls):
        SENSOR_KINDS[kind] = cls
        cls.kind = kind
        return cls

    return deco


def spec_class(kind: str) -> type:
    """The ``Spec`` class registered for ``kind`` (clear error when unknown)."""
    _load_builtin_kinds()
    try:
        return SENSOR_KINDS[kind]
    except KeyError:
        raise UnknownNameError("sensor kind", kind, SENSOR_KINDS) from None


def _load_builtin_kinds():
    """Import the built-in sensor modules so that they register themselves."""
    import importlib

    for mod in BUILTIN_MODULES:
        importlib.import_module(f"fuzzynav.sim.sensors.{mod}")


#: modules of this package that register built-in sensor kinds
BUILTIN_MODULES: tuple[str, ...] = ("gnss", "polarization")


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
