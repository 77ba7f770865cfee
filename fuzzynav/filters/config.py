"""Filter configuration: initial uncertainty, process noise, gating, output rate.

Datasheet units at this edge (deg, °/h, µg, °/√h, µg/√Hz); :meth:`FilterConfig.P0` and
:meth:`FilterConfig.q_diag` return the SI arrays the loop uses.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from fuzzynav import units
from fuzzynav.errors import InputFileError
from fuzzynav.filters.bank import BankSpec
from fuzzynav.filters.error_model import MODEL_15, ErrorModel
from fuzzynav.filters.error_st import error_model_code

__all__ = ["FilterConfig"]


def _per_block(values, n_blocks, name):
    values = tuple(values) if np.ndim(values) else (values,) * n_blocks
    if len(values) != n_blocks:
        raise InputFileError(None, name, f"needs one value per block ({n_blocks}), got {len(values)}")
    return values


@dataclass(frozen=True)
class FilterConfig:
    """Everything a filter run needs besides data, initial state and adaptation policies.

    Parameters
    ----------
    model : ErrorModel
        Sensor-error state layout (15 states by default).
    init_att_sigma_deg : (3,) tuple
        Initial 1-sigma attitude error phi (east, north, up) [deg].
    init_vel_sigma_mps, init_pos_sigma_m : float
        Initial 1-sigma velocity [m/s] and position [m] errors.
    gyro_sigma_dph, accel_sigma_ug : tuple per block
        1-sigma of each sensor-error block: initial uncertainty of a random constant, or the
        steady-state sigma of a Gauss-Markov block [°/h, µg].
    gyro_rw_dph_psh, accel_rw_ug_psqrts : tuple per block
        Random-walk densities added to random-constant blocks [°/h/√h, µg/√s] (0 = none).
    arw_dpsh, vrw_ug_psqrthz : float
        Angle and velocity random walk the filter assumes [°/√h, µg/√Hz].
    gate_probability : float or None
        Chi-square gate: epochs whose NIS exceeds this quantile are rejected (None = off).
    max_prop_dt_s : float
        Longest covariance-propagation interval [s] (also propagated at every measurement).
    out_rate_hz : float
        Rate of the recorded solution [Hz] (rounded to a whole number of IMU samples).
    extra_noise_si : tuple of (sigma, q) per ``model.extra`` block
        Initial 1-sigma and driving-noise density (SI) of each extra block.
    error_model : {"phi", "st"}
        The error definition: the classical phi model, or the state-transformation model
        (velocity error ``dv - [v x] phi``, :mod:`fuzzynav.filters.error_st`).  Initial
        sigmas above are always of the phi-model states; the ST model maps them.
    bank : BankSpec or None
        Local filters and their master (:mod:`fuzzynav.filters.bank`); None is the single
        filter with every sensor (the bank of one).
    """

    model: ErrorModel = MODEL_15
    init_att_sigma_deg: tuple = (0.1, 0.1, 1.0)
    init_vel_sigma_mps: float = 0.1
    init_pos_sigma_m: float = 3.0
    gyro_sigma_dph: tuple = (10.0,)
    accel_sigma_ug: tuple = (1000.0,)
    gyro_rw_dph_psh: tuple = (0.0,)
    accel_rw_ug_psqrts: tuple = (0.0,)
    arw_dpsh: float = 0.1
    vrw_ug_psqrthz: float = 100.0
    gate_probability: float | None = None
    max_prop_dt_s: float = 1.0
    out_rate_hz: float = 10.0
    extra_noise_si: tuple = ()
    error_model: str = "phi"
    bank: BankSpec | None = None

    def __post_init__(self):
        error_model_code(self.error_model)  # refuse an unknown name here, not in the loop

    def with_(self, **changes) -> "FilterConfig":
        """A copy with some fields changed."""
        return replace(self, **changes)

    def _blocks(self):
        ng, na = len(self.model.gyro_tau_s), len(self.model.accel_tau_s)
        return (_per_block(self.gyro_sigma_dph, ng, "gyro_sigma_dph"),
                _per_block(self.accel_sigma_ug, na, "accel_sigma_ug"),
                _per_block(self.gyro_rw_dph_psh, ng, "gyro_rw_dph_psh"),
                _per_block(self.accel_rw_ug_psqrts, na, "accel_rw_ug_psqrts"))

    def _block_noise(self) -> dict:
        """Block name -> ``(initial sigmas, noise densities)`` per state (SI)."""
        gs, as_, grw, arw = self._blocks()
        lay, taus = self.model.layout, dict(self.model.block_taus())
        out = {"att": (list(np.asarray(self.init_att_sigma_deg, float) * units.DEG),
                       [(self.arw_dpsh * units.DPSH) ** 2] * 3),
               "vel": ([self.init_vel_sigma_mps] * 3, [(self.vrw_ug_psqrthz * units.UG) ** 2] * 3),
               "pos": ([self.init_pos_sigma_m] * 3, [0.0] * 3)}
        for kind, sigmas, rws, unit, rw_unit in (("gyro_bias", gs, grw, units.DPH, units.DPH_PSH),
                                                 ("accel_bias", as_, arw, units.UG, units.UG)):
            for nm, sig, rw in zip(lay.of_kind(kind), sigmas, rws):
                out[nm] = ([sig * unit] * 3, [_block_q(sig * unit, rw * rw_unit, taus[nm])] * 3)
        for (nm, _), (sig, q) in zip(self.model.extra, self._extra_noise()):
            size = lay[nm].stop - lay[nm].start
            out[nm] = ([float(sig)] * size, [float(q)] * size)
        return out

    def _extra_noise(self):
        pairs = _per_block(self.extra_noise_si, len(self.model.extra), "extra_noise_si")
        for i, pair in enumerate(pairs):
            ok = np.shape(pair) == (2,) and np.all(np.isfinite(pair))
            if not (ok and pair[0] > 0.0 and pair[1] >= 0.0):
                raise InputFileError(None, f"extra_noise_si[{i}]",
                                     f"needs (sigma > 0, noise density >= 0), got {pair!r}")
        return pairs

    @cached_property
    def _noise_arrays(self):
        # the config is frozen: assembled once per instance (every filter run asks), kept
        # read-only so that only the copies below ever leave
        noise = self._block_noise()
        names = self.model.layout.names
        P0 = np.diag(np.square([s for nm in names for s in noise[nm][0]]))
        q = np.array([q for nm in names for q in noise[nm][1]])
        P0.flags.writeable = q.flags.writeable = False
        return P0, q

    def P0(self) -> np.ndarray:
        """Initial covariance (n x n, diagonal, SI), assembled from the blocks present
        (a fresh array the caller may change)."""
        return self._noise_arrays[0].copy()

    def q_diag(self) -> np.ndarray:
        """Continuous process-noise spectral densities per state (SI), block by block (a
        fresh array the caller may change)."""
        return self._noise_arrays[1].copy()


def _block_q(sigma, rw, tau):
    """Driving-noise density of a sensor block: 2 sigma^2 / tau for Gauss-Markov, rw^2 else."""
    return rw * rw if math.isinf(tau) else 2.0 * sigma * sigma / tau
