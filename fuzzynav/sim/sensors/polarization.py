"""Skylight polarization compass: sensor kind ``polarization``.

Two sensor types, both fixed to the body with their frame nominally equal to the body RFU
frame (boresight ``z_b`` up, AoP reference axis ``x_b`` right):

* ``point`` — one zenith-pointing point-source sensor (photodiodes behind polarizers): one
  angle of polarization per epoch, which gives the heading once the tilt is known;
* ``imaging`` — a sky camera reading the AoP along several view directions at once, which
  gives pitch and heading for a known roll (paper 000; roll is not estimated).

Measurement columns (``SensorData.z``)
--------------------------------------
``[aop_1, ..., aop_k, sun_e, sun_n, sun_u]``: the measured AoPs [rad] in [-pi/2, pi/2) of the
``k`` view directions (``k = 1`` for ``point``) followed by the ENU unit vector towards the sun
at the epoch (ephemeris at the true position; 1 km of position error moves it by 0.009°).
``SensorData.sigma`` holds the *claimed* AoP 1-sigma [rad] in the AoP columns and 0 in the
sun columns.  An imaging AoP is NaN where that view's degree of polarization is below the
threshold; epochs with no usable view (``point``) or fewer than two (``imaging``), at night,
or under cloud are absent.  ``meta``: ``sensor_type`` (0 point, 1 imaging), ``views_b``
(k, 3) nominal unit view directions in the body frame, ``rate_hz``, and the truth for
tests and plots — ``err_aop_rad`` (measured minus nominal-mounting model, so it contains
the misalignment), ``dop``, ``cloud_windows`` (K, 2) and ``true_sigma`` (the standard
deviation of the simulated AoP error, shaped like ``sigma``).

Simulated AoP (:mod:`fuzzynav.sim.skylight`, Rayleigh single scattering): the sun is rotated
into the true sensor frame ``C_cn = C_bc^T C_bn^T`` with ``C_bc`` the small mounting
misalignment, then ``aop = AoP(v_c, C_cn sun_n) + e``.  The error ``e`` is ``noise_deg`` times
a standard normal draw, or a Student-t draw when ``student_t_dof > 0`` (its standard deviation
is then ``noise_deg sqrt(dof / (dof - 2))``), plus, with probability ``outlier_rate``, a
normal outlier of 1-sigma ``outlier_scale * noise_deg``.  The filter inverts the model with
:mod:`fuzzynav.nav.polarization_solver`.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.nav import attitude
from fuzzynav.sim import skylight, sun
from fuzzynav.sim.sensors import SensorData, epoch_indices, register
from fuzzynav.sim.tomltable import Table

__all__ = ["SENSOR_TYPES", "MAX_VIEW_ZENITH_DEG", "Spec"]

SENSOR_TYPES = ("point", "imaging")
#: largest angle of a view from the boresight [deg] (the AoP reference needs v != +-x_c)
MAX_VIEW_ZENITH_DEG = 80.0


@register("polarization")
@dataclass(frozen=True)
class Spec:
    """Polarization sensor simulation (a ``kind = "polarization"`` sensor table).

    Parameters
    ----------
    sensor_type : {"point", "imaging"}
        TOML key ``type``.
    rate_hz : float
        Measurement rate [Hz]; epochs fall on the nearest IMU sample.
    start_s : float
        Time of the first measurement [s].
    noise_deg : float
        1-sigma (scale) of the AoP noise [deg]; paper 000: 0.3.
    claimed_sigma_deg : float, optional
        The 1-sigma the sensor reports [deg]; default ``noise_deg``.
    student_t_dof : float
        Degrees of freedom of Student-t AoP errors (heavy tails); 0 = Gaussian.
    outlier_rate, outlier_scale : float
        Probability per AoP of an extra error of 1-sigma ``outlier_scale * noise_deg``.
    dop_max : float
        Degree of polarization 90° from the sun (clear sky 0.6-0.8).
    dop_min : float
        Threshold: views with a lower degree of polarization give no AoP (sun near the
        sensor's view, e.g. near the zenith for the point sensor).
    min_sun_elevation_deg : float
        No measurement while the sun is lower (night) [deg].
    cloud_windows : tuple of (start_s, end_s)
        Explicit cloud cover: no measurement inside.
    cloud_mean_clear_s, cloud_mean_cloudy_s : float
        Random cloud cover: alternating clear and cloudy spells of exponentially distributed
        lengths with these means [s] (both > 0 to enable).
    misalignment_deg : tuple of 3 float
        True mounting error, a rotation vector (sensor to body) about the sensor x, y, z
        axes [deg]; unknown to the filter.  The z part biases the heading one for one.
    ring_zenith_deg : float
        Imaging: angle of the ring of view directions from the boresight [deg] (<= 80).
    ring_views : int
        Imaging: number of views on the ring, evenly spaced in azimuth starting at the
        forward axis ``y_c`` and going clockwise seen from above.
    zenith_view : bool
        Imaging: also read the AoP on the boresight.  Ignored by ``point`` (always one view
        on the boresight).
    """

    sensor_type: str = "point"
    rate_hz: float = 10.0
    start_s: float = 0.0
    noise_deg: float = 0.3
    claimed_sigma_deg: float | None = None
    student_t_dof: float = 0.0
    outlier_rate: float = 0.0
    outlier_scale: float = 10.0
    dop_max: float = skylight.DOP_MAX_CLEAR
    dop_min: float = 0.1
    min_sun_elevation_deg: float = 0.0
    cloud_windows: tuple = ()
    cloud_mean_clear_s: float = 0.0
    cloud_mean_cloudy_s: float = 0.0
    misalignment_deg: tuple = (0.0, 0.0, 0.0)
    ring_zenith_deg: float = 30.0
    ring_views: int = 6
    zenith_view: bool = True

    kind = "polarization"

    def __post_init__(self):
        object.__setattr__(self, "cloud_windows",
                           tuple(tuple(map(float, w)) for w in self.cloud_windows))
        object.__setattr__(self, "misalignment_deg", tuple(map(float, self.misalignment_deg)))
        if self.sensor_type not in SENSOR_TYPES:
            raise InputFileError(None, "type", f"must be one of {', '.join(SENSOR_TYPES)}, "
                                               f"got {self.sensor_type!r}")
        if not self.rate_hz > 0.0:
            raise InputFileError(None, "rate_hz", f"must be positive, got {self.rate_hz!r}")
        if self.sensor_type == "imaging" and self.ring_views + self.zenith_view < 2:
            raise InputFileError(None, "ring_views", "an imaging sensor needs at least two "
                                                     "views (ring_views + zenith_view)")

    def columns(self) -> int:
        """Measurement columns per epoch: one AoP per view and the sun vector (budget)."""
        return self.views_c().shape[0] + 3

    def spell_count(self, t_end_s: float) -> tuple:
        """``(key, expected number of cloud spells)`` over ``t_end_s`` (memory budget)."""
        mean_cycle = self.cloud_mean_clear_s + self.cloud_mean_cloudy_s
        if self.cloud_mean_clear_s <= 0.0 or self.cloud_mean_cloudy_s <= 0.0:
            return "cloud_mean_clear_s", 0
        return "cloud_mean_clear_s", 2.0 * t_end_s / mean_cycle

    # -- geometry -----------------------------------------------------------------------
    def views_c(self) -> np.ndarray:
        """Unit view directions in the sensor frame (= nominal body frame), shape (k, 3)."""
        if self.sensor_type == "point":
            return np.array([[0.0, 0.0, 1.0]])
        az = np.arange(self.ring_views) * (2.0 * np.pi / max(self.ring_views, 1))
        ring = skylight.view_direction(np.radians(self.ring_zenith_deg), az)
        return np.vstack([[[0.0, 0.0, 1.0]]] * self.zenith_view + [ring])

    def claimed_sigma_rad(self) -> float:
        """Claimed AoP 1-sigma [rad]."""
        s = self.noise_deg if self.claimed_sigma_deg is None else self.claimed_sigma_deg
        return float(np.radians(s))

    def epochs(self, truth) -> np.ndarray:
        """Indices of the IMU samples at which the sensor reads."""
        return epoch_indices(truth, self.start_s, self.rate_hz)

    # -- errors -------------------------------------------------------------------------
    def aop_errors(self, shape, rng) -> np.ndarray:
        """AoP errors [rad] (noise, heavy tails, outliers), array of ``shape``."""
        g_noise, g_mask, g_out = rng.spawn(3)
        if self.student_t_dof > 0.0:
            core = g_noise.standard_t(self.student_t_dof, shape)
        else:
            core = g_noise.standard_normal(shape)
        err = self.noise_deg * core
        hit = g_mask.random(shape) < self.outlier_rate
        err = err + np.where(hit, self.outlier_scale * self.noise_deg
                             * g_out.standard_normal(shape), 0.0)
        return np.radians(err)

    def true_sigma_rad(self) -> float:
        """Standard deviation of the simulated AoP error [rad] (heavy tails and outliers)."""
        core = self.noise_deg ** 2
        if self.student_t_dof > 0.0:
            core *= self.student_t_dof / (self.student_t_dof - 2.0)
        return float(np.radians(np.sqrt(core + self.outlier_rate
                                        * (self.outlier_scale * self.noise_deg) ** 2)))

    def clouds(self, t_end_s, rng) -> np.ndarray:
        """All cloudy windows up to ``t_end_s``, array (K, 2) of ``[start_s, end_s)``."""
        out = list(self.cloud_windows)
        clear, cloudy = self.cloud_mean_clear_s, self.cloud_mean_cloudy_s
        if clear > 0.0 and cloudy > 0.0:
            # start in the stationary state of the two-state process
            is_cloudy = rng.random() < cloudy / (clear + cloudy)
            t = 0.0
            while t < t_end_s:
                spell = rng.exponential(cloudy if is_cloudy else clear)
                if is_cloudy:
                    out.append((t, t + spell))
                t += spell
                is_cloudy = not is_cloudy
        return np.array(sorted(out), dtype=float).reshape(-1, 2)

    # -- simulation ---------------------------------------------------------------------
    def simulate(self, truth, rng, start_utc) -> SensorData:
        """Angles of polarization along ``truth``.

        Parameters
        ----------
        truth : Trajectory
        rng : numpy.random.Generator
            Split internally into error and cloud streams.
        start_utc : datetime, numpy.datetime64 or ISO string
            UTC epoch of ``truth.time_s[0]`` (fixes the sun).

        Returns
        -------
        SensorData
            Columns as in the module docstring.
        """
        if start_utc is None:
            raise InputFileError(None, "start_utc", "the polarization sensor needs the "
                                                    "scenario's UTC start time (the sun)")
        g_err, g_cloud = rng.spawn(2)
        idx = self.epochs(truth)
        time_s = np.asarray(truth.time_s)[idx]
        lla = np.asarray(truth.lla)[idx]
        jd = sun.julian_day(start_utc) + (time_s - truth.time_s[0]) / 86400.0
        sp = sun.sun_position(jd, lla[:, 0], lla[:, 1])
        sun_n = sp.sun_n
        C_bn = attitude.quat_to_dcm(np.asarray(truth.q_bn)[idx])
        views = self.views_c()
        sun_b = np.einsum("kji,kj->ki", C_bn, sun_n)
        C_bc = attitude.rotvec_to_dcm(np.radians(self.misalignment_deg))
        sun_c = sun_b @ C_bc  # rows: C_bc^T s_b
        aop_true = skylight.angle_of_polarization(views[None], sun_c[:, None])
        aop_nominal = skylight.angle_of_polarization(views[None], sun_b[:, None])
        dop = skylight.degree_of_polarization(views[None], sun_c[:, None], self.dop_max)
        aop = skylight.fold_half_pi(aop_true + self.aop_errors(aop_true.shape, g_err))
        seen = (dop >= self.dop_min) & np.isfinite(aop)
        aop = np.where(seen, aop, np.nan)
        clouds = self.clouds(truth.time_s[-1] - truth.time_s[0], g_cloud)
        keep = ((seen.sum(1) >= (1 if self.sensor_type == "point" else 2))
                & (sp.elevation_rad >= np.radians(self.min_sun_elevation_deg))
                & ~_in_windows(time_s - truth.time_s[0], clouds))
        k = views.shape[0]
        z = np.hstack([aop, sun_n])[keep]
        sigma = np.hstack([np.full(k, self.claimed_sigma_rad()), np.zeros(3)])
        meta = {"sensor_type": SENSOR_TYPES.index(self.sensor_type), "views_b": views,
                "rate_hz": float(self.rate_hz),
                "err_aop_rad": skylight.fold_half_pi(aop - aop_nominal)[keep],
                "dop": dop[keep], "cloud_windows": clouds,
                "true_sigma": np.broadcast_to(np.hstack([np.full(k, self.true_sigma_rad()),
                                                         np.zeros(3)]), z.shape).copy()}
        return SensorData(kind=self.kind, time_s=time_s[keep], z=z,
                          sigma=np.broadcast_to(sigma, z.shape).copy(), meta=meta)

    # -- TOML ---------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, d: dict, where: str) -> "Spec":
        """Parse a sensor table; errors name ``where.key``."""
        t = Table(d, where)
        t.string("kind", "polarization", choices=("polarization",))
        kw = {"sensor_type": t.string("type", "point", choices=SENSOR_TYPES),
              "rate_hz": t.number("rate_hz", 10.0, lo=0.0, hi=1000.0, lo_open=True),
              "start_s": t.number("start_s", 0.0, lo=0.0),
              "noise_deg": t.number("noise_deg", 0.3, lo=0.0, hi=90.0),
              "claimed_sigma_deg": t.number("claimed_sigma_deg", None, lo=0.0, hi=90.0,
                                            lo_open=True),
              "student_t_dof": t.number("student_t_dof", 0.0, lo=0.0),
              "outlier_rate": t.number("outlier_rate", 0.0, lo=0.0, hi=1.0),
              "outlier_scale": t.number("outlier_scale", 10.0, lo=0.0, hi=1e3),
              "dop_max": t.number("dop_max", skylight.DOP_MAX_CLEAR, lo=0.0, hi=1.0,
                                  lo_open=True),
              "dop_min": t.number("dop_min", 0.1, lo=0.0, hi=1.0),
              "min_sun_elevation_deg": t.number("min_sun_elevation_deg", 0.0, lo=-90.0,
                                                hi=90.0),
              "cloud_windows": t.windows("cloud_windows", 2),
              "cloud_mean_clear_s": t.number("cloud_mean_clear_s", 0.0, lo=0.0),
              "cloud_mean_cloudy_s": t.number("cloud_mean_cloudy_s", 0.0, lo=0.0),
              "misalignment_deg": t.vector("misalignment_deg", 3, (0.0, 0.0, 0.0),
                                           lo=-10.0, hi=10.0)}
        if kw["claimed_sigma_deg"] is None and kw["noise_deg"] == 0.0:
            raise t.error("claimed_sigma_deg", "must be given (> 0) when noise_deg is 0")
        if 0.0 < kw["student_t_dof"] <= 2.0:
            raise t.error("student_t_dof", f"must be 0 (Gaussian) or above 2 (finite "
                                           f"variance), got {kw['student_t_dof']!r}")
        if (kw["cloud_mean_clear_s"] > 0.0) != (kw["cloud_mean_cloudy_s"] > 0.0):
            raise t.error("cloud_mean_cloudy_s", "random clouds need both cloud_mean_clear_s "
                                                 "and cloud_mean_cloudy_s")
        if kw["dop_min"] >= kw["dop_max"]:
            raise t.error("dop_min", f"must be below dop_max ({kw['dop_max']!r}), "
                                     f"got {kw['dop_min']!r}")
        kw["ring_zenith_deg"] = t.number("ring_zenith_deg", 30.0, lo=0.0,
                                         hi=MAX_VIEW_ZENITH_DEG, lo_open=True)
        kw["ring_views"] = t.integer("ring_views", 6, lo=0, hi=360)
        kw["zenith_view"] = t.boolean("zenith_view", True)
        if kw["sensor_type"] == "imaging" and kw["ring_views"] + kw["zenith_view"] < 2:
            raise t.error("ring_views", "an imaging sensor needs at least two views "
                                        "(ring_views + zenith_view)")
        t.finish()
        return cls(**kw)

    def to_dict(self) -> dict:
        """The sensor table (TOML-ready, ``None`` left out, ``kind`` included)."""
        out = {"kind": self.kind}
        for k, v in asdict(self).items():
            if v is None:
                continue
            if isinstance(v, tuple):
                v = [list(x) if isinstance(x, tuple) else x for x in v]
            out["type" if k == "sensor_type" else k] = v
        return out


def _in_windows(time_s, windows) -> np.ndarray:
    """Mask of times inside any ``[start, end)`` row of ``windows`` (K, 2)."""
    mask = np.zeros(np.shape(time_s), dtype=bool)
    for start, end in windows:
        mask |= (time_s >= start) & (time_s < end)
    return mask
