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
    """Indices of the IMU samples nearest to a sensor's epochs ``start_s + k / rate_hz``.

    ``truth`` is a :class:`~fuzzynav.sim.trajectory.Trajectory`, or anything with a
    ``grid`` ``(t0_s, t_end_s, n_rows)`` and ``imu_rate_hz`` (:class:`Grid`, the run of a
    chunked simulation) and optionally ``remap(idx)`` (a truth holding some rows only).
    """
    grid = getattr(truth, "grid", None)
    if grid is None:
        t = np.asarray(truth.time_s)
        grid = (t[0], t[-1], t.size)
    t0, t_end, size = grid
    t_meas = np.arange(start_s, t_end + 1e-9, 1.0 / rate_hz)
    idx = np.round((t_meas - t0) * truth.imu_rate_hz).astype(np.int64)
    idx = np.unique(idx[(idx >= 0) & (idx < size)])
    remap = getattr(truth, "remap", None)
    return idx if remap is None else remap(idx)


@dataclass(frozen=True)
class Grid:
    """The IMU sample grid of a run, without its samples: what a sensor's stream needs to
    place its epochs (:func:`epoch_indices`) and time its processes.

    Attributes
    ----------
    t0_s, t_end_s : float
        First and last sample time [s].
    n_rows : int
        Number of samples (increments + 1).
    imu_rate_hz : float
    sea : SeaState or None
    """

    t0_s: float
    t_end_s: float
    n_rows: int
    imu_rate_hz: float
    sea: object = None

    @property
    def grid(self) -> tuple:
        return self.t0_s, self.t_end_s, self.n_rows


class EpochStream:
    """Base of a sensor simulated chunk by chunk: the run's epoch indices, and those of a
    chunk (:meth:`local`).

    A chunk of the run is the truth at samples ``k0..k1``; it carries the epochs at samples
    ``lo..k1`` (``lo = k0`` for the run's first chunk, ``k0 + 1`` after: the chunk before
    carried sample ``k0``), so every epoch is simulated once, in order.  A subclass
    ``chunk(truth, k0, lo, whole=False)`` (``whole``: the run is one chunk) draws each random term from its own generator in epoch order,
    so the chunks' draws are the whole run's (numpy draws of ``n1`` then ``n2`` values
    are the draw of ``n1 + n2``) and the one-chunk case is ``simulate``.
    """

    def __init__(self, idx):
        self.idx = np.asarray(idx, np.int64)

    def local(self, k0: int, lo: int, k1: int) -> np.ndarray:
        """Indices, into a chunk whose first row is sample ``k0``, of the epochs at
        samples ``lo..k1``."""
        a, b = np.searchsorted(self.idx, [lo, k1 + 1])
        return self.idx[a:b] - k0


def skipped(rng, count: int, block: int = 1 << 20):
    """A copy of ``rng`` advanced past ``count`` standard normals (drawn in blocks and
    dropped): where a second draw of the same generator starts, without holding the first."""
    g = np.random.Generator(type(rng.bit_generator)())
    g.bit_generator.state = rng.bit_generator.state
    for a in range(0, int(count), block):
        g.standard_normal(min(block, int(count) - a))
    return g


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
