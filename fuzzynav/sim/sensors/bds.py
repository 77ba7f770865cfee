"""BeiDou (BDS) position/velocity fixes: sensor kind ``bds``, a GNSS variant.

The same receiver model and measurement columns as :mod:`fuzzynav.sim.sensors.gnss`, plus
the error paper 001 names ``Me, Mn, Mu`` (the BDS position errors per ENU axis): a
constant per-axis bias, fixed (``bias_m``) and/or drawn once per run (``bias_sigma_m``) —
what the broadcast-ephemeris, ionosphere and geometry errors of a single-frequency BDS fix
look like over a few minutes.  The receiver does not report the bias: the claimed sigma
stays that of the white and Gauss-Markov parts.  The filter uses the GNSS measurement model
(registered again under ``bds``, :mod:`fuzzynav.filters.measurements.bds`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.sim.sensors import register
from fuzzynav.sim.sensors.gnss import MAX_POS_M, Spec as GnssSpec
from fuzzynav.sim.tomltable import Table

__all__ = ["Spec"]

_BIAS_FIELDS = ("bias_m", "bias_sigma_m")


@register("bds")
@dataclass(frozen=True)
class Spec(GnssSpec):
    """BDS receiver: every ``gnss`` key, plus

    Parameters
    ----------
    bias_m : tuple of 3 float
        Fixed ENU position bias [m].
    bias_sigma_m : tuple of 3 float
        1-sigma of a random constant ENU bias drawn once per run [m].
    """

    bias_m: tuple = (0.0, 0.0, 0.0)
    bias_sigma_m: tuple = (0.0, 0.0, 0.0)

    kind = "bds"

    def __post_init__(self):
        super().__post_init__()
        for name in _BIAS_FIELDS:
            value = np.broadcast_to(np.asarray(getattr(self, name), dtype=float), (3,))
            object.__setattr__(self, name, tuple(float(v) for v in value))

    def _errors(self, time_s, rng):
        """The GNSS errors plus this run's constant bias on the position."""
        g_rest, g_bias = rng.spawn(2)
        err_p, err_v, outlier = super()._errors(time_s, g_rest)
        bias = np.asarray(self.bias_m) + np.asarray(self.bias_sigma_m) * g_bias.standard_normal(3)
        return err_p + bias, err_v, outlier

    def true_sigma(self, time_s) -> np.ndarray:
        """GNSS true sigma with the bias's spread (``bias^2 + bias_sigma^2``) added."""
        out = super().true_sigma(time_s)
        extra = np.square(self.bias_m) + np.square(self.bias_sigma_m)
        out[:, :3] = np.sqrt(out[:, :3] ** 2 + extra)
        return out

    @classmethod
    def extra_fields(cls, t: Table) -> dict:
        """The two bias keys."""
        return {name: t.vector(name, 3, (0.0, 0.0, 0.0), lo=-MAX_POS_M if name == "bias_m"
                               else 0.0, hi=MAX_POS_M) for name in _BIAS_FIELDS}
