"""Electromagnetic log: sensor kind ``log`` (a ship's speed through the water).

An electromagnetic log measures the water flowing past the hull along the keel (body
forward axis ``y_b``).  With the ground velocity ``v_n`` (truth) and the current ``c_n``
(water over ground, :meth:`fuzzynav.sim.sea.SeaState.current_n`)::

    v_log = (1 + k) (C_bn^T (v_n - c_n))_y + b + w,

``k`` the scale-factor error, ``b`` the constant error and ``w`` white noise.  Paper 003
writes ``V_L = V_w + V_g + dV_L`` (current, ground speed, log error) with the current taken
as the water's contribution to the reading; here the current is the water's velocity over
ground, so it enters with a minus sign.  Its figures: white noise 0.5 m/s and constant
error 0.5 m/s at 50 Hz.

Columns: ``z = [v_log]`` [m/s], ``sigma = [claimed 1-sigma]``.  ``meta``: ``true_sigma``
(the white noise's standard deviation, shaped like ``sigma``), ``bias_mps``, ``scale``,
``current_fwd_mps`` (the truth's current along the keel at each epoch) and ``rate_hz``.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from fuzzynav.nav import attitude
from fuzzynav.sim.sensors import EpochStream, SensorData, epoch_indices, register
from fuzzynav.sim.tomltable import Table

__all__ = ["body_velocity", "LogStream", "Spec"]


def body_velocity(truth, idx, through_water: bool = True) -> np.ndarray:
    """Hull velocity in body axes at samples ``idx``, (k, 3) [m/s].

    Through the water (ground velocity minus the current of ``truth.sea``) or over ground.
    """
    vel = np.asarray(truth.vel_n)[idx]
    if through_water and truth.sea is not None:
        vel = vel - truth.sea.current_n(np.asarray(truth.time_s)[idx])
    C_bn = attitude.quat_to_dcm(np.asarray(truth.q_bn)[idx])
    return np.einsum("kji,kj->ki", C_bn, vel)


@register("log")
@dataclass(frozen=True)
class Spec:
    """Electromagnetic log simulation (a ``kind = "log"`` sensor table).

    Parameters
    ----------
    rate_hz : float
        Output rate [Hz] (paper 003: 50).
    start_s : float
        First output [s].
    noise_mps : float
        1-sigma white noise [m/s] (paper 003: 0.5).
    bias_mps : float
        Constant error [m/s] (paper 003: 0.5).
    scale : float
        Scale-factor error [-] (e.g. 0.01 for 1 %).
    claimed_sigma_mps : float, optional
        The 1-sigma the filter is told [m/s]; default ``noise_mps``.
    """

    rate_hz: float = 50.0
    start_s: float = 0.0
    noise_mps: float = 0.5
    bias_mps: float = 0.5
    scale: float = 0.0
    claimed_sigma_mps: float | None = None

    kind = "log"

    def columns(self) -> int:
        """Measurement columns per epoch (memory budget)."""
        return 1

    def claimed(self) -> float:
        """Claimed 1-sigma [m/s]."""
        return float(self.noise_mps if self.claimed_sigma_mps is None else self.claimed_sigma_mps)

    def simulate(self, truth, rng, start_utc=None) -> SensorData:
        """Log readings along ``truth`` (the current from ``truth.sea``, none without one)."""
        return self.stream(truth, rng).chunk(truth, 0, 0)

    def stream(self, grid, rng, start_utc=None) -> "LogStream":
        """The readings chunk by chunk (:class:`~fuzzynav.sim.sensors.EpochStream`)."""
        return LogStream(self, epoch_indices(grid, self.start_s, self.rate_hz), rng)


    @classmethod
    def from_dict(cls, d: dict, where: str) -> "Spec":
        """Parse a sensor table; errors name ``where.key``."""
        t = Table(d, where)
        t.string("kind", "log", choices=("log",))
        kw = {"rate_hz": t.number("rate_hz", 50.0, lo=0.0, hi=1000.0, lo_open=True),
              "start_s": t.number("start_s", 0.0, lo=0.0),
              "noise_mps": t.number("noise_mps", 0.5, lo=0.0, hi=100.0),
              "bias_mps": t.number("bias_mps", 0.5, lo=-100.0, hi=100.0),
              "scale": t.number("scale", 0.0, lo=-0.5, hi=0.5),
              "claimed_sigma_mps": t.number("claimed_sigma_mps", None, lo=0.0, hi=100.0,
                                            lo_open=True)}
        if kw["claimed_sigma_mps"] is None and kw["noise_mps"] == 0.0:
            raise t.error("claimed_sigma_mps", "must be given (> 0) when noise_mps is 0")
        t.finish()
        return cls(**kw)

    def to_dict(self) -> dict:
        """The sensor table (TOML-ready, ``None`` left out)."""
        return {"kind": self.kind, **{k: v for k, v in asdict(self).items() if v is not None}}


class LogStream(EpochStream):
    """A log simulated chunk by chunk: one white-noise draw per epoch, in order."""

    def __init__(self, spec: Spec, idx, rng):
        super().__init__(idx)
        self.spec, self.rng = spec, rng

    def chunk(self, truth, k0: int, lo: int, whole: bool = False) -> SensorData:
        """The readings at samples ``lo..`` of ``truth`` (rows from sample ``k0``; ``whole``:
        the run is this one chunk)."""
        sp = self.spec
        idx = self.local(k0, lo, k0 + truth.time_s.size - 1)
        time_s = np.asarray(truth.time_s)[idx]
        fwd = body_velocity(truth, idx)[:, 1]
        z = (1.0 + sp.scale) * fwd + sp.bias_mps + sp.noise_mps * self.rng.standard_normal(
            idx.size)
        current = (np.zeros((idx.size, 3)) if truth.sea is None
                   else truth.sea.current_n(time_s))
        C_bn = attitude.quat_to_dcm(np.asarray(truth.q_bn)[idx])
        meta = {"true_sigma": np.full((idx.size, 1), sp.noise_mps),
                "bias_mps": float(sp.bias_mps), "scale": float(sp.scale),
                "current_fwd_mps": np.einsum("kj,kj->k", C_bn[:, :, 1], current),
                "rate_hz": float(sp.rate_hz)}
        return SensorData(kind=sp.kind, time_s=time_s, z=z[:, None],
                          sigma=np.full((idx.size, 1), sp.claimed()), meta=meta)
