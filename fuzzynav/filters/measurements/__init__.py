"""Measurement models: one module per sensor kind, each returning ``(z, H, R)`` per epoch.

A model is a numba kernel with the fixed signature :data:`MEAS_SIG`::

    m = kernel(nav, C_bn, aux, row, par, dt_back, z, H, R, chan)

* ``nav`` — strapdown state (:mod:`fuzzynav.nav.strapdown` layout), ``C_bn`` its DCM;
* ``aux`` — ``[omega_ib_b (3) rad/s, f_b (3) m/s^2]`` of the latest IMU interval, then the
  current sensor-state estimates ``xs`` (the states after the core, from ``aux[AUX_XS]``, :mod:`fuzzynav.filters.layout`), so
  that a model with its own states (a DVL scale factor) forms its residual with them;
* ``row`` — this epoch's data row (by default ``[z..., sigma...]`` of the SensorData);
* ``par`` — constants packed by the model's ``pack`` function (lever arms, switches);
* ``dt_back`` — how long ago [s] the measurement was taken (it is processed at the first
  IMU sample at or after its time; models move the INS quantities back by this much);
* outputs: ``z[:m]`` the residual *INS minus sensor* (so ``z = H dx + v``), ``H[:m, :]``
  (zeroed by the caller), ``R[:m]`` the diagonal variance, ``chan[:m]`` a channel id per row
  (indices into the model's ``channels``, used by adaptation policies).

Returns ``m``, the number of rows (0 to skip the epoch).  A new sensor is one module here
plus :func:`register`; the filter loop dispatches through numba first-class functions.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from numba import types

from fuzzynav.errors import UnknownNameError
from fuzzynav.filters.numba_lazy import njit_signature, table_of
from fuzzynav.registry import Registry

MEAS_SIG = types.int64(types.float64[:], types.float64[:, :], types.float64[:],
                       types.float64[:], types.float64[:], types.float64,
                       types.float64[:], types.float64[:, :], types.float64[:],
                       types.int64[:])


def default_rows(data) -> np.ndarray:
    """Data rows ``[z..., sigma...]`` of a :class:`~fuzzynav.sim.sensors.SensorData`."""
    return np.hstack([data.z, data.sigma]).astype(float, copy=False)


@dataclass(frozen=True)
class MeasurementModel:
    """A registered measurement model.

    Attributes
    ----------
    kind : str
        Sensor kind it serves (``SensorData.kind``).
    kernel : numba dispatcher compiled with :data:`MEAS_SIG`.
    max_rows : int
        Largest ``m`` it returns.
    channels : tuple of str
        Names of the channel ids it writes into ``chan``.
    pack : callable
        ``pack(sensor_data, options: dict) -> float64 array`` of constants ``par``.
    rows : callable
        ``rows(sensor_data) -> (M, W) float64`` data rows.
    states : callable, optional
        ``states(sensor_data, options) -> tuple of (block, tau_s, sigma0, steady_sigma)``:
        state blocks the model wants in the layout
        (:func:`fuzzynav.filters.sensor_states.with_sensor_states` adds them and passes
        their starts to ``pack`` as ``options["state_start"]``).
    quality : tuple of (str, int)
        Receiver-quality columns of ``rows`` by statistic name (e.g. ``("n_sat", 13)``),
        readable by adaptation policies (:mod:`fuzzynav.filters.adaptation.context`).
    """

    kind: str
    kernel: object
    max_rows: int
    channels: tuple
    pack: Callable
    rows: Callable = default_rows
    states: Callable | None = None
    quality: tuple = ()

    def channel_index(self, name: str) -> int:
        """Index of channel ``name`` (clear error when the model has no such channel)."""
        if name == "all":
            return -1
        try:
            return self.channels.index(name)
        except ValueError:
            raise UnknownNameError(f"channel of the {self.kind} model", name,
                                   self.channels + ("all",)) from None


MODELS = Registry("measurement model", __name__, ("gnss", "polarization", "nhc", "magnetometer",
                                                  "bds", "log", "neutral_point", "dvl"))


def register(model: MeasurementModel) -> MeasurementModel:
    """Register a measurement model under its sensor kind."""
    return MODELS.add(model.kind, model)


def get(kind: str) -> MeasurementModel:
    """The model registered for sensor ``kind``."""
    return MODELS.lookup(kind)


@njit_signature(MEAS_SIG)
def unused_kernel(nav, C_bn, aux, row, par, dt_back, z, H, R, chan):
    """Stands in a kernel table for the models a run does not use (never called: no rows)."""
    return 0


def kernel_table(used=None):
    """``(tuple of kernels, {kind: index})`` for the filter loop.

    ``used``: the indices the run dispatches to; the other entries are
    :func:`unused_kernel`, so that only the used models get compiled (the table's numba
    type, and so the loop's cache entry, is the same either way).  None: every model.
    """
    index = MODELS.index()
    kernels = [MODELS[k].kernel for k in index]
    return table_of(kernels, used, unused_kernel), index
