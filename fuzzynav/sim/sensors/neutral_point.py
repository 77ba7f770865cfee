"""Neutral-point polarization camera: sensor kind ``neutral_point`` (paper 003).

A fisheye polarization camera fixed to the body images the sky; the neutral points
(:mod:`fuzzynav.nav.neutral_points`) are found as the zeros of the degree of polarization and
the angle ``beta`` of the line through two of them is reported.  The pair: Arago and Babinet
(the paper's) when both are inside the field of view, else Brewster and Babinet (both near
the sun, a baseline of only ``2 delta``), else nothing.

Errors: each detected point's image position carries white noise of 1-sigma
``point_sigma = angle_noise_rad * L0 / sqrt(2)``, with ``L0 = pi - 2 delta`` the nominal
Arago-Babinet baseline, so that ``beta`` has the paper's accuracy (0.005 rad) on that pair
and a proportionally worse one on a shorter baseline (the Babinet-Brewster pair of a high
sun).  A detector faster than the IMU (paper 003: 100 Hz on a 50-Hz IMU) is reported once
per IMU sample as the mean of its ``rate_hz / imu_rate`` detections in that interval: the
heading hardly moves in 20 ms, so the mean carries the same information, with the point
noise (and the claimed sigma) divided by the square root of that number.  ``clouds`` rows ``[start_s, end_s, scale]`` multiply the point noise by
``scale`` under cloud (0 = no detection at all).  No output above ``max_sun_elevation_deg``
(the points crowd around the zenith and the detector loses them) or below
``min_sun_elevation_deg``.

Columns: ``z = [beta, sun_e, sun_n, sun_u, pair]`` (``pair`` 0 Arago-Babinet, 1
Brewster-Babinet) and ``sigma = [claimed beta sigma, 0, 0, 0, 0]``.  ``meta``: ``delta_rad``,
``fov_deg``, ``true_sigma`` (the beta standard deviation of each epoch), ``rate_hz``.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.nav import attitude
from fuzzynav.nav.neutral_points import images
from fuzzynav.sim import sun
from fuzzynav.sim.sensors import EpochStream, SensorData, epoch_indices, register, skipped
from fuzzynav.sim.tomltable import Table

__all__ = ["NeutralPointStream", "Spec"]


@register("neutral_point")
@dataclass(frozen=True)
class Spec:
    """Neutral-point camera simulation (a ``kind = "neutral_point"`` sensor table).

    Parameters
    ----------
    rate_hz : float
        Detection rate [Hz] (paper 003: 100); above the IMU rate the detections of each IMU
        interval are averaged into one output.
    angle_noise_rad : float
        1-sigma of ``beta`` on the Arago-Babinet baseline [rad] (paper 003: 0.005).
    claimed_sigma_rad : float, optional
        The sigma the filter is told [rad]; default ``angle_noise_rad``.
    delta_deg : float
        Angular distance of the neutral points from the sun/antisun [deg] (15-25).
    fov_deg : float
        Half field of view of the fisheye [deg] (points beyond are not seen).
    max_sun_elevation_deg, min_sun_elevation_deg : float
        No output with the sun higher / lower [deg].
    clouds : tuple of (start_s, end_s, scale)
        Cloud: point noise times ``scale`` (0: no output).
    """

    rate_hz: float = 10.0
    angle_noise_rad: float = 0.005
    claimed_sigma_rad: float | None = None
    delta_deg: float = 20.0
    fov_deg: float = 90.0
    max_sun_elevation_deg: float = 75.0
    min_sun_elevation_deg: float = 0.0
    clouds: tuple = ()

    kind = "neutral_point"

    def __post_init__(self):
        object.__setattr__(self, "clouds",
                           tuple(tuple(map(float, w)) for w in self.clouds))

    def columns(self) -> int:
        """Measurement columns per epoch (memory budget)."""
        return 5

    def point_sigma(self) -> float:
        """1-sigma of a point's image position [rad of the equidistant fisheye]."""
        return self.angle_noise_rad * (np.pi - 2 * np.deg2rad(self.delta_deg)) / np.sqrt(2.0)

    def _cloud_scale(self, t) -> np.ndarray:
        scale = np.ones_like(t)
        for t0, t1, s in self.clouds:
            scale = np.where((t >= t0) & (t < t1), s, scale)
        return scale

    def simulate(self, truth, rng, start_utc) -> SensorData:
        """Line angles through the neutral points along ``truth``."""
        return self.stream(truth, rng, start_utc).chunk(truth, 0, 0)

    def stream(self, grid, rng, start_utc) -> "NeutralPointStream":
        """The line angles chunk by chunk (:class:`~fuzzynav.sim.sensors.EpochStream`)."""
        if start_utc is None:
            raise InputFileError(None, "start_utc", "the neutral-point sensor needs the "
                                                    "scenario's UTC start time (the sun)")
        per_epoch = max(1.0, self.rate_hz / float(grid.imu_rate_hz))  # detections averaged
        idx = epoch_indices(grid, 0.0, self.rate_hz / per_epoch)
        t0 = grid.grid[0] if hasattr(grid, "grid") else float(np.asarray(grid.time_s)[0])
        return NeutralPointStream(self, idx, rng, start_utc, per_epoch, t0)

    @classmethod
    def from_dict(cls, d: dict, where: str) -> "Spec":
        """Parse a sensor table; errors name ``where.key``."""
        t = Table(d, where)
        t.string("kind", "neutral_point", choices=("neutral_point",))
        kw = {"rate_hz": t.number("rate_hz", 10.0, lo=0.0, hi=1000.0, lo_open=True),
              "angle_noise_rad": t.number("angle_noise_rad", 0.005, lo=0.0, hi=1.0),
              "claimed_sigma_rad": t.number("claimed_sigma_rad", None, lo=0.0, hi=1.0,
                                            lo_open=True),
              "delta_deg": t.number("delta_deg", 20.0, lo=5.0, hi=40.0),
              "fov_deg": t.number("fov_deg", 90.0, lo=30.0, hi=100.0),
              "max_sun_elevation_deg": t.number("max_sun_elevation_deg", 75.0, lo=0.0, hi=90.0),
              "min_sun_elevation_deg": t.number("min_sun_elevation_deg", 0.0, lo=-10.0,
                                                hi=90.0),
              "clouds": t.windows("clouds", 3)}
        for i, w in enumerate(kw["clouds"]):
            if not 0.0 <= w[2] <= 1e3:
                raise t.error(f"clouds[{i}]", f"scale must lie in [0, 1000], got {w[2]!r}")
        if kw["claimed_sigma_rad"] is None and kw["angle_noise_rad"] == 0.0:
            raise t.error("claimed_sigma_rad", "must be given (> 0) when angle_noise_rad is 0")
        t.finish()
        return cls(**kw)

    def to_dict(self) -> dict:
        """The sensor table (TOML-ready, ``None`` left out)."""
        out = {"kind": self.kind}
        for k, v in asdict(self).items():
            if v is not None:
                out[k] = [list(w) for w in v] if k == "clouds" else v
        return out


class NeutralPointStream(EpochStream):
    """Neutral points simulated chunk by chunk.

    The whole run draws the first point's noise for every epoch, then the second's, from
    one generator: the second draw's generator is a copy advanced past the first's
    (:func:`~fuzzynav.sim.sensors.skipped`), so each chunk draws both in epoch order.
    """

    def __init__(self, spec: Spec, idx, rng, start_utc, per_epoch: float, t0_s: float):
        super().__init__(idx)
        self.spec, self.per_epoch, self.t0_s = spec, per_epoch, t0_s
        self.jd0 = sun.julian_day(start_utc)
        self.g_a, self.g_b = rng, skipped(rng, 2 * self.idx.size)

    def chunk(self, truth, k0: int, lo: int, whole: bool = False) -> SensorData:
        """The line angles at samples ``lo..`` of ``truth`` (rows from sample ``k0``;
        ``whole``: the run is this one chunk)."""
        sp, per_epoch = self.spec, self.per_epoch
        idx = self.local(k0, lo, k0 + truth.time_s.size - 1)
        time_s = np.asarray(truth.time_s)[idx]
        lla = np.asarray(truth.lla)[idx]
        jd = self.jd0 + (time_s - self.t0_s) / 86400.0
        sp_ = sun.sun_position(jd, lla[:, 0], lla[:, 1])
        C_bn = attitude.quat_to_dcm(np.asarray(truth.q_bn)[idx])
        delta, fov = np.deg2rad(sp.delta_deg), np.deg2rad(sp.fov_deg)
        img = np.array([images(C, s, delta) for C, s in zip(C_bn, sp_.sun_n)]).reshape(-1, 4, 3)
        seen = img[:, :, 2] < fov
        pair = np.where(seen[:, 2] & seen[:, 0], 0, np.where(seen[:, 1] & seen[:, 0], 1, -1))
        scale = sp._cloud_scale(time_s - self.t0_s)
        elev = np.rad2deg(sp_.elevation_rad)
        keep = ((pair >= 0) & (scale > 0) & (elev <= sp.max_sun_elevation_deg)
                & (elev >= sp.min_sun_elevation_deg))
        a = np.where(pair == 0, 2, 1)
        k = np.arange(idx.size)
        sig = sp.point_sigma() * scale / np.sqrt(per_epoch)
        pa = img[k, a, :2] + sig[:, None] * self.g_a.standard_normal((idx.size, 2))
        pb = img[k, 0, :2] + sig[:, None] * self.g_b.standard_normal((idx.size, 2))
        beta = np.arctan2(pb[:, 1] - pa[:, 1], pb[:, 0] - pa[:, 0])
        base = np.hypot(*(img[k, 0, :2] - img[k, a, :2]).T)
        z = np.column_stack([beta, sp_.sun_n, pair])[keep]
        claimed = sp.angle_noise_rad if sp.claimed_sigma_rad is None else sp.claimed_sigma_rad
        sigma = np.zeros_like(z)
        sigma[:, 0] = claimed / np.sqrt(per_epoch)
        true = np.zeros_like(z)
        true[:, 0] = (np.sqrt(2.0) * sig / np.maximum(base, 1e-9))[keep]
        meta = {"delta_rad": float(delta), "fov_deg": float(sp.fov_deg), "true_sigma": true,
                "rate_hz": float(sp.rate_hz)}
        return SensorData(kind=sp.kind, time_s=time_s[keep], z=z, sigma=sigma, meta=meta)
