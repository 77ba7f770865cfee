"""Three-axis magnetometer used as a compass: sensor kind ``magnetometer``.

Measurement columns (``SensorData.z``): ``[heading_rad, m_x, m_y, m_z]`` — the magnetic
heading corrected to true north (clockwise from north, in [0, 2 pi)) and the measured body
field (RFU, tesla; NaN when ``vector = false``).  ``SensorData.sigma``: the claimed heading
1-sigma [rad] and the claimed per-axis field 1-sigma [T].

Simulated field, at each epoch (body RFU)::

    m_b = S C_nb R_u(-d(t)) B_n + b + n,

* ``B_n`` — the main field at the true position and the scenario's date
  (:mod:`fuzzynav.sim.geomag`, IGRF via ``ppigrf`` by default);
* ``R_u(-d)`` — a disturbance zone: a local anomaly that turns the horizontal field by
  ``d(t)`` about the vertical (so the compass heading is off by ``+d``), ramping in and out
  with raised-cosine edges; the field magnitude may change too (``field_scale``);
* ``S`` (soft iron, a 3x3 matrix, identity when calibrated) and ``b`` (hard iron [nT]):
  the uncalibrated residue of the vehicle's own field; they give the classic one- and
  two-cycle heading errors;
* ``n`` — white noise of ``noise_nt`` per axis.

The heading is computed as a compass does: the field is levelled with the (true) tilt, its
horizontal direction gives the magnetic heading, and the declination of the field *model*
(without the anomaly, which the compass cannot know) turns it to true north.  In terms of
the attitude matrix, the heading is ``atan2(C_bn[0, 1], C_bn[1, 1])`` of the attitude the
field implies — the relation paper 001 writes as ``tan phi' = -C12 / C22`` in its own axis
and sign convention.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav import units
from fuzzynav.errors import InputFileError
from fuzzynav.nav import attitude
from fuzzynav.sim import geomag
from fuzzynav.sim.sensors import SensorData, epoch_indices, register, spec_table
from fuzzynav.sim.tomltable import Table

__all__ = ["Disturbance", "Spec"]

_IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
#: largest sensible figures [nT]: the earth's field is at most ~65 000 nT
_MAX_NT = 1e6
_MAX_DEFLECTION_DEG = 90.0


@dataclass(frozen=True)
class Disturbance:
    """A magnetic disturbance zone (local anomaly) along the run.

    Parameters
    ----------
    start_s, end_s : float
        The zone in run time [s] (a scenario may give ``start_sample`` / ``end_sample`` of
        this sensor's epochs instead; they are converted with its rate and start).
    deflection_deg : float
        Heading error inside the zone [deg] (the horizontal field turned by minus this).
    ramp_s : float
        Length of the raised-cosine entry and exit [s] (0: a jump).
    field_scale : float
        Factor on the field magnitude inside the zone.
    """

    start_s: float
    end_s: float
    deflection_deg: float = 5.0
    ramp_s: float = 5.0
    field_scale: float = 1.0

    def weight(self, time_s) -> np.ndarray:
        """Share of the full disturbance at ``time_s`` (0 outside, 1 in the core)."""
        t = np.asarray(time_s, float)
        w = ((t >= self.start_s) & (t < self.end_s)).astype(float)
        if self.ramp_s > 0.0:
            edge = np.minimum(t - self.start_s, self.end_s - t) / self.ramp_s
            w *= np.where(edge < 1.0, 0.5 - 0.5 * np.cos(np.pi * np.clip(edge, 0.0, 1.0)), 1.0)
        return w

    @classmethod
    def from_table(cls, t: Table, rate_hz: float, first_s: float) -> "Disturbance":
        by_sample = t.has("start_sample") or t.has("end_sample")
        if by_sample:
            start = first_s + t.integer("start_sample", lo=0) / rate_hz
            end = first_s + t.integer("end_sample", lo=0) / rate_hz
            key = "end_sample"
        else:
            start, end, key = t.number("start_s", lo=0.0), t.number("end_s"), "end_s"
        if not start < end:
            raise t.error(key, "the zone must end after it starts")
        d = cls(start, end,
                t.number("deflection_deg", 5.0, lo=-_MAX_DEFLECTION_DEG, hi=_MAX_DEFLECTION_DEG),
                t.number("ramp_s", 5.0, lo=0.0),
                t.number("field_scale", 1.0, lo=0.0, hi=10.0, lo_open=True))
        if 2.0 * d.ramp_s > end - start:
            raise t.error("ramp_s", f"the two ramps ({2.0 * d.ramp_s:g} s) do not fit in the "
                                    f"zone ({end - start:g} s)")
        t.finish()
        return d


@register("magnetometer")
@dataclass(frozen=True)
class Spec:
    """Magnetometer (compass) simulation: a ``kind = "magnetometer"`` sensor table.

    Parameters
    ----------
    rate_hz, start_s : float
        Measurement rate [Hz] and first epoch [s].
    noise_nt : float
        White noise per axis [nT].
    claimed_sigma_deg : float, optional
        Heading 1-sigma the compass reports [deg]; default: the white noise seen through
        the horizontal field, ``noise_nt / H``.
    hard_iron_nt : tuple of 3 float
        Uncalibrated hard-iron offset, body RFU [nT].
    soft_iron : 3x3 tuple
        Soft-iron matrix (identity = calibrated).
    field_model : {"igrf", "dipole"}
    vector : bool
        Also output the 3-axis field (for the vector measurement model).
    disturbances : tuple of Disturbance
    """

    rate_hz: float = 10.0
    start_s: float = 0.0
    noise_nt: float = 100.0
    claimed_sigma_deg: float | None = None
    hard_iron_nt: tuple = (0.0, 0.0, 0.0)
    soft_iron: tuple = _IDENTITY
    field_model: str = "igrf"
    vector: bool = True
    disturbances: tuple = ()

    kind = "magnetometer"

    def __post_init__(self):
        if not self.rate_hz > 0.0:
            raise InputFileError(None, "rate_hz", f"must be positive, got {self.rate_hz!r}")
        if self.field_model not in geomag.FIELD_MODELS:
            raise InputFileError(None, "field_model", f"must be one of "
                                 f"{', '.join(geomag.FIELD_MODELS)}, got {self.field_model!r}")
        object.__setattr__(self, "disturbances", tuple(self.disturbances))
        if abs(np.linalg.det(np.asarray(self.soft_iron, float))) < 1e-6:
            raise InputFileError(None, "soft_iron", "must be invertible")

    def columns(self) -> int:
        """Measurement columns per epoch (memory budget)."""
        return 4

    def spell_count(self, t_end_s: float) -> tuple:
        """No random spells (memory budget)."""
        return "disturbances", 0

    def epochs(self, truth) -> np.ndarray:
        """Indices of the IMU samples at which the magnetometer reads."""
        return epoch_indices(truth, self.start_s, self.rate_hz)

    def deflection_rad(self, time_s) -> tuple:
        """Heading deflection [rad] and field-magnitude factor of the zones at ``time_s``."""
        defl = np.zeros(np.shape(time_s))
        scale = np.ones(np.shape(time_s))
        for d in self.disturbances:
            w = d.weight(time_s)
            defl += w * d.deflection_deg * units.DEG
            scale *= 1.0 + w * (d.field_scale - 1.0)
        return defl, scale

    def horizontal_sigma_rad(self, field_n) -> float:
        """Heading 1-sigma the white noise gives: ``noise / H`` [rad] (level sensor)."""
        return float(self.noise_nt * units.NT / np.hypot(field_n[0], field_n[1]))

    def simulate(self, truth, rng, start_utc=None) -> SensorData:
        """Headings (and body fields) along ``truth``.

        Returns
        -------
        SensorData
            ``meta``: ``rate_hz``, ``field_n_t`` (model field at the start, ENU [T]),
            ``err_heading_rad`` (measured minus true heading), ``deflection_rad`` (the
            zones' share of it) and ``true_sigma`` (heading: white-noise sigma combined
            with the deflection, which an oracle filter is told; field: the white noise).
        """
        idx = self.epochs(truth)
        time_s = np.asarray(truth.time_s)[idx]
        lla = np.asarray(truth.lla)[idx]
        field = geomag.field_enu_t(lla[:, 0], lla[:, 1], lla[:, 2], start_utc, self.field_model)
        defl, scale = self.deflection_rad(time_s - truth.time_s[0])
        c, s = np.cos(defl), np.sin(defl)
        disturbed = scale[:, None] * np.column_stack(  # turned by -defl about up
            [c * field[:, 0] - s * field[:, 1], s * field[:, 0] + c * field[:, 1], field[:, 2]])
        C_bn = attitude.quat_to_dcm(np.asarray(truth.q_bn)[idx])
        m_b = np.einsum("kji,kj->ki", C_bn, disturbed) @ np.asarray(self.soft_iron, float).T
        m_b += np.asarray(self.hard_iron_nt, float) * units.NT
        m_b += self.noise_nt * units.NT * rng.standard_normal(m_b.shape)
        heading_true = np.arctan2(C_bn[:, 0, 1], C_bn[:, 1, 1])
        m_n = np.einsum("kij,kj->ki", C_bn, m_b)  # levelled with the true tilt
        heading = attitude.wrap_2pi(heading_true + geomag.declination_rad(field)
                                    - np.arctan2(m_n[:, 0], m_n[:, 1]))
        sig_h = self.claimed_sigma_rad(field[0])
        sig_b = self.noise_nt * units.NT
        z = np.column_stack([heading, m_b if self.vector else np.full_like(m_b, np.nan)])
        sigma = np.tile([sig_h, sig_b, sig_b, sig_b], (z.shape[0], 1))
        if not self.vector:
            sigma[:, 1:] = np.nan
        white = self.horizontal_sigma_rad(field[0])
        true_sigma = sigma.copy()
        true_sigma[:, 0] = np.hypot(white, defl)
        meta = {"rate_hz": float(self.rate_hz), "field_n_t": field[0].copy(),
                "err_heading_rad": attitude.wrap_pi(heading - heading_true),
                "deflection_rad": defl, "true_sigma": true_sigma}
        return SensorData(kind=self.kind, time_s=time_s, z=z, sigma=sigma, meta=meta)

    def claimed_sigma_rad(self, field_n) -> float:
        """Claimed heading 1-sigma [rad]."""
        if self.claimed_sigma_deg is not None:
            return float(self.claimed_sigma_deg * units.DEG)
        return self.horizontal_sigma_rad(field_n)

    # -- TOML ---------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, d: dict, where: str) -> "Spec":
        """Parse a sensor table (``kind`` already checked); errors name ``where.key``."""
        t = Table(d, where)
        t.string("kind", "magnetometer", choices=("magnetometer",))
        rate = t.number("rate_hz", 10.0, lo=0.0, hi=1000.0, lo_open=True)
        start = t.number("start_s", 0.0, lo=0.0)
        kw = {"rate_hz": rate, "start_s": start,
              "noise_nt": t.number("noise_nt", 100.0, lo=0.0, hi=_MAX_NT),
              "claimed_sigma_deg": t.number("claimed_sigma_deg", None, lo=0.0, hi=90.0,
                                            lo_open=True),
              "hard_iron_nt": t.vector("hard_iron_nt", 3, (0.0, 0.0, 0.0), lo=-_MAX_NT,
                                       hi=_MAX_NT),
              "soft_iron": t.matrix("soft_iron", 3, _IDENTITY, lo=-10.0, hi=10.0),
              "field_model": t.string("field_model", "igrf", choices=geomag.FIELD_MODELS),
              "vector": t.boolean("vector", True),
              "disturbances": tuple(Disturbance.from_table(x, rate, start)
                                    for x in t.tables("disturbances", required=False))}
        if kw["noise_nt"] == 0.0 and kw["claimed_sigma_deg"] is None:
            raise t.error("claimed_sigma_deg", "must be given (> 0) when noise_nt is 0")
        if abs(np.linalg.det(np.asarray(kw["soft_iron"]))) < 1e-6:
            raise t.error("soft_iron", "must be invertible (a calibrated sensor: identity)")
        t.finish()
        return cls(**kw)

    def to_dict(self) -> dict:
        """The sensor table (TOML-ready, ``None`` fields left out, ``kind`` included)."""
        return spec_table(self)
