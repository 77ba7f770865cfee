"""Non-holonomic constraint pseudo-measurements of a ship: sensor kind ``nhc``.

The constraint says the body lateral (``x_b``) and vertical (``z_b``) velocities over ground
are zero; it is fed to the filter's ``nhc`` model (:mod:`fuzzynav.filters.measurements.nhc`)
as the rows ``[v_x, v_z, sigma_x, sigma_z]``.  What makes it wrong on a ship:

* the hull's own motion — yaw swinging the bow off the track (``v sin(yaw)`` sideways),
  heave and pitch (vertical) — already in the truth (:mod:`fuzzynav.sim.sea`);
* the current's lateral component and the leeway (wind drift, ``v tan(leeway)``): a real
  ship's ground track has them sideways.  Our truth keeps the ground track along the keel,
  so they are put into the pseudo-measurement instead, ``v_x = -(c_x + v tan(leeway))``:
  the residual ``INS - constraint`` is then what it would be on the real ship;
* optional white noise ``noise_mps``.

``sigma`` is the claimed 1-sigma (paper 003: 0.2 m/s); ``meta["true_sigma"]`` is the RMS of
the simulated error per column over the run (a single figure; the error is not white).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from fuzzynav.sim.sensors import EpochStream, SensorData, epoch_indices, register
from fuzzynav.sim.sensors.log import body_velocity
from fuzzynav.sim.tomltable import Table

__all__ = ["NhcStream", "Spec"]


@register("nhc")
@dataclass(frozen=True)
class Spec:
    """Ship non-holonomic constraints (a ``kind = "nhc"`` sensor table).

    Parameters
    ----------
    rate_hz : float
        Pseudo-measurement rate [Hz].
    sigma_mps : float
        Claimed 1-sigma of both rows [m/s] (paper 003: 0.2).
    noise_mps : float
        White noise added to both rows [m/s].
    leeway_deg : float
        Leeway angle: a sideways drift of ``speed tan(leeway)`` [deg].
    current_error : bool
        Put the current's lateral component into the pseudo-measurement.
    """

    rate_hz: float = 10.0
    sigma_mps: float = 0.2
    noise_mps: float = 0.0
    leeway_deg: float = 0.0
    current_error: bool = True

    kind = "nhc"
    #: ``meta`` of the whole run only (an RMS over it), left out of a chunk of a longer run
    whole_run_meta = ("true_sigma",)

    def columns(self) -> int:
        """Measurement columns per epoch (memory budget)."""
        return 2

    def simulate(self, truth, rng, start_utc=None) -> SensorData:
        """Constraint pseudo-measurements along ``truth``."""
        return self.stream(truth, rng).chunk(truth, 0, 0, whole=True)

    def stream(self, grid, rng, start_utc=None) -> "NhcStream":
        """The pseudo-measurements chunk by chunk (:class:`~fuzzynav.sim.sensors.
        EpochStream`)."""
        return NhcStream(self, epoch_indices(grid, 0.0, self.rate_hz), rng)

    @classmethod
    def from_dict(cls, d: dict, where: str) -> "Spec":
        """Parse a sensor table; errors name ``where.key``."""
        t = Table(d, where)
        t.string("kind", "nhc", choices=("nhc",))
        kw = {"rate_hz": t.number("rate_hz", 10.0, lo=0.0, hi=1000.0, lo_open=True),
              "sigma_mps": t.number("sigma_mps", 0.2, lo=0.0, hi=100.0, lo_open=True),
              "noise_mps": t.number("noise_mps", 0.0, lo=0.0, hi=100.0),
              "leeway_deg": t.number("leeway_deg", 0.0, lo=-30.0, hi=30.0),
              "current_error": t.boolean("current_error", True)}
        t.finish()
        return cls(**kw)

    def to_dict(self) -> dict:
        """The sensor table (TOML-ready)."""
        return {"kind": self.kind, **asdict(self)}


class NhcStream(EpochStream):
    """Ship constraints simulated chunk by chunk: one white-noise draw per epoch, in order.

    ``meta["true_sigma"]`` is the RMS of the error over the whole run, known only once the
    run is over: a chunk of a longer run (``whole=False``) leaves it out, so the oracle
    filter (``ekf-true``) refuses a streamed run rather than being told another figure.
    """

    def __init__(self, spec: Spec, idx, rng):
        super().__init__(idx)
        self.spec, self.rng = spec, rng

    def chunk(self, truth, k0: int, lo: int, whole: bool = False) -> SensorData:
        """The pseudo-measurements at samples ``lo..`` of ``truth`` (rows from ``k0``)."""
        sp = self.spec
        idx = self.local(k0, lo, k0 + truth.time_s.size - 1)
        z = np.zeros((idx.size, 2))
        water_b = body_velocity(truth, idx)
        ground_b = body_velocity(truth, idx, through_water=False)
        if sp.current_error:
            # body-lateral current = lateral ground velocity minus lateral water velocity
            z[:, 0] -= ground_b[:, 0] - water_b[:, 0]
        z[:, 0] -= water_b[:, 1] * np.tan(np.deg2rad(sp.leeway_deg))
        z += sp.noise_mps * self.rng.standard_normal(z.shape)
        meta = {"rate_hz": float(sp.rate_hz)}
        if whole:
            # the error a filter meets: the true body velocity minus the pseudo-measurement
            err = ground_b[:, [0, 2]] - z
            rms = np.sqrt(np.mean(err**2, axis=0)) if idx.size else np.zeros(2)
            meta = {"true_sigma": np.tile(rms, (idx.size, 1)), **meta}
        return SensorData(kind=sp.kind, time_s=np.asarray(truth.time_s)[idx], z=z,
                          sigma=np.full((idx.size, 2), sp.sigma_mps), meta=meta)
