"""GNSS (GPS/BDS) position and velocity fixes: sensor kind ``gnss``.

Measurement columns (``SensorData.z``): ``lat_rad, lon_rad, h_m, vel_e, vel_n, vel_u`` of
the antenna.  ``SensorData.sigma`` holds the *claimed* 1-sigma of the ENU residuals a filter
forms, in metres and m/s: ``[east_m, north_m, up_m, vel_e_mps, vel_n_mps, vel_u_mps]`` (the
position part is in metres and in ENU order, not in the lat/lon order of ``z``).  A NaN in
``z`` means "not measured" (e.g. a receiver without velocity output); epochs inside outages
are absent.

Simulated error, per ENU axis, at each epoch:

    e = s(t) n_white + x_gm + x_col(t) + outlier,

* ``n_white``: white noise of 1-sigma ``pos_sigma_m`` / ``vel_sigma_mps``;
* ``x_gm``: multipath-like first-order Gauss-Markov error (``gm_*_sigma``, ``gm_tau_s``);
* inside a noise window, ``s(t)`` scales the white noise and ``x_col`` adds a coloured
  (Gauss-Markov) error that the receiver does not report: the claimed sigma stays the same,
  which is the mismatch adaptive filters are built for;
* an outlier, with probability ``outlier_rate`` per epoch, adds an error of length
  ``outlier_pos_m`` (``outlier_vel_mps``) in a uniformly random 3-D direction.

The antenna sits at ``lever_arm_b_m`` (body RFU, metres) from the IMU:
``p_ant = p + C_bn l`` and ``v_ant = v + C_bn (omega_eb_b x l)``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.nav import attitude, earth
from fuzzynav.sim.gauss_markov import gauss_markov_series
from fuzzynav.sim.sensors import SensorData, epoch_indices, register, spec_table
from fuzzynav.sim.tomltable import Table

__all__ = ["MAX_POS_M", "MAX_LEVER_ARM_M", "outage_windows", "in_windows", "random_directions",
           "NoiseWindow", "Spec", "antenna_truth"]

_ZERO3 = (0.0, 0.0, 0.0)
#: largest sensible figures: anything beyond describes no receiver and overflows squares
MAX_POS_M = 1e5          # a 100-km error is no longer a fix
_MAX_VEL_MPS = 1e3
_MAX_SCALE = 1e4
#: largest antenna lever arm component [m] (larger than any vehicle), in scenarios,
#: mounting files and start options alike
MAX_LEVER_ARM_M = 1e3
_VECTOR_FIELDS = ("pos_sigma_m", "vel_sigma_mps", "gm_pos_sigma_m", "gm_vel_sigma_mps",
                  "claimed_pos_sigma_m", "claimed_vel_sigma_mps", "lever_arm_b_m")


def outage_windows(t_end_s, windows=(), period_s=0.0, duration_s=0.0, first_s=None):
    """All outage windows up to ``t_end_s`` as an array (K, 2) of ``[start_s, end_s)``.

    Parameters
    ----------
    t_end_s : float
        End of the run [s].
    windows : sequence of (start_s, end_s)
        Explicit outages.
    period_s, duration_s : float
        A periodic pattern, e.g. 60 s of outage every 180 s (0 = none).
    first_s : float, optional
        Start of the first periodic outage (default: one period after ``t = 0``).
    """
    out = [tuple(w[:2]) for w in windows]
    if period_s > 0.0 and duration_s > 0.0:
        t = period_s if first_s is None else first_s
        while t < t_end_s:
            out.append((t, t + duration_s))
            t += period_s
    return np.array(sorted(out), dtype=float).reshape(-1, 2)


def in_windows(time_s, windows) -> np.ndarray:
    """Mask of times inside any ``[start, end)`` window of ``windows`` (K, 2)."""
    time_s = np.asarray(time_s, dtype=float)
    mask = np.zeros(time_s.shape, dtype=bool)
    for start, end in np.asarray(windows, dtype=float).reshape(-1, 2):
        mask |= (time_s >= start) & (time_s < end)
    return mask


def random_directions(rng, n) -> np.ndarray:
    """``n`` unit vectors uniformly distributed on the sphere, shape (n, 3)."""
    v = rng.standard_normal((n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


@dataclass(frozen=True)
class NoiseWindow:
    """A time window where the real noise differs from the claimed noise.

    Parameters
    ----------
    start_s, end_s : float
        The window [s].
    scale : float
        Factor on the white noise inside the window.
    coloured_pos_m, coloured_vel_mps : float
        1-sigma of an extra Gauss-Markov error per axis inside the window.
    coloured_tau_s : float
        Its correlation time [s].
    """

    start_s: float
    end_s: float
    scale: float = 1.0
    coloured_pos_m: float = 0.0
    coloured_vel_mps: float = 0.0
    coloured_tau_s: float = 30.0

    @classmethod
    def from_table(cls, t: Table) -> "NoiseWindow":
        start = t.number("start_s", lo=0.0)
        end = t.number("end_s")
        if not start < end:
            raise t.error("end_s", f"must be after start_s ({start!r}), got {end!r}")
        w = cls(start, end, t.number("scale", 1.0, lo=0.0, hi=_MAX_SCALE),
                t.number("coloured_pos_m", 0.0, lo=0.0, hi=MAX_POS_M),
                t.number("coloured_vel_mps", 0.0, lo=0.0, hi=_MAX_VEL_MPS),
                t.number("coloured_tau_s", 30.0, lo=0.0, lo_open=True))
        t.finish()
        return w


@register("gnss")
@dataclass(frozen=True)
class Spec:
    """GNSS receiver simulation (a ``kind = "gnss"`` sensor table of a scenario).

    Parameters
    ----------
    rate_hz : float
        Fix rate [Hz]; epochs fall on the nearest IMU sample.
    start_s : float
        Time of the first fix [s].
    pos_sigma_m, vel_sigma_mps : tuple of 3 float
        White-noise 1-sigma per ENU axis [m], [m/s].
    velocity : bool
        Whether the receiver reports velocity (else those columns are NaN).
    gm_pos_sigma_m, gm_vel_sigma_mps : tuple of 3 float
        Stationary 1-sigma of the multipath-like Gauss-Markov error per ENU axis.
    gm_tau_s : float
        Its correlation time [s].
    claimed_pos_sigma_m, claimed_vel_sigma_mps : tuple of 3 float, optional
        What the receiver reports as 1-sigma per ENU axis; default: the true total
        ``sqrt(white^2 + gm^2)`` (outside noise windows).
    outlier_rate : float
        Probability of an outlier per epoch.
    outlier_pos_m, outlier_vel_mps : float
        Size of an outlier [m], [m/s].
    outages : tuple of (start_s, end_s)
        Explicit outage windows.
    outage_period_s, outage_duration_s : float
        Periodic outages (e.g. 180 and 60: 60 s without fixes every 180 s).
    outage_first_s : float, optional
        Start of the first periodic outage (default: one period after start).
    lever_arm_b_m : tuple of 3 float
        Antenna position relative to the IMU in body RFU [m].
    noise_windows : tuple of NoiseWindow
        Windows of mismatched noise.
    """

    rate_hz: float = 1.0
    start_s: float = 0.0
    pos_sigma_m: tuple = (1.5, 1.5, 3.0)
    vel_sigma_mps: tuple = (0.05, 0.05, 0.1)
    velocity: bool = True
    gm_pos_sigma_m: tuple = _ZERO3
    gm_vel_sigma_mps: tuple = _ZERO3
    gm_tau_s: float = 60.0
    claimed_pos_sigma_m: tuple | None = None
    claimed_vel_sigma_mps: tuple | None = None
    outlier_rate: float = 0.0
    outlier_pos_m: float = 0.0
    outlier_vel_mps: float = 0.0
    outages: tuple = ()
    outage_period_s: float = 0.0
    outage_duration_s: float = 0.0
    outage_first_s: float | None = None
    lever_arm_b_m: tuple = _ZERO3
    noise_windows: tuple = ()

    kind = "gnss"

    def __post_init__(self):
        for name in _VECTOR_FIELDS:
            value = getattr(self, name)
            if value is not None:  # a single number means the same on all three axes
                value = np.broadcast_to(np.asarray(value, dtype=float), (3,))
                object.__setattr__(self, name, tuple(float(v) for v in value))
        object.__setattr__(self, "outages", tuple(tuple(map(float, w)) for w in self.outages))
        object.__setattr__(self, "noise_windows", tuple(self.noise_windows))
        if not self.rate_hz > 0.0:
            raise InputFileError(None, "rate_hz", f"must be positive, got {self.rate_hz!r}")

    def columns(self) -> int:
        """Measurement columns per epoch (memory budget)."""
        return 6

    def spell_count(self, t_end_s: float) -> tuple:
        """``(key, number of periodic outages)`` over a run of ``t_end_s`` (memory budget)."""
        if self.outage_period_s <= 0.0:
            return "outage_period_s", 0
        first = self.outage_period_s if self.outage_first_s is None else self.outage_first_s
        return "outage_period_s", max(0.0, (t_end_s - first) / self.outage_period_s)

    # -- claimed noise ------------------------------------------------------------------
    def claimed_sigma(self) -> np.ndarray:
        """Claimed 1-sigma columns ``[E, N, U (m), vE, vN, vU (m/s)]``, shape (6,)."""
        pos = (np.hypot(self.pos_sigma_m, self.gm_pos_sigma_m)
               if self.claimed_pos_sigma_m is None else np.asarray(self.claimed_pos_sigma_m))
        vel = (np.hypot(self.vel_sigma_mps, self.gm_vel_sigma_mps)
               if self.claimed_vel_sigma_mps is None else np.asarray(self.claimed_vel_sigma_mps))
        return np.concatenate([pos, vel]).astype(float)

    # -- simulation ---------------------------------------------------------------------
    def epochs(self, truth) -> np.ndarray:
        """Indices of the IMU samples at which fixes are taken."""
        return epoch_indices(truth, self.start_s, self.rate_hz)

    def _errors(self, time_s, rng):
        """ENU position [m] and velocity [m/s] errors and the outlier mask."""
        g_wp, g_wv, g_gm, g_win, g_out = rng.spawn(5)
        m = time_s.size
        scale = np.ones(m)
        col_p, col_v = np.zeros((m, 3)), np.zeros((m, 3))
        for w, g in zip(self.noise_windows, g_win.spawn(len(self.noise_windows))):
            inside = (time_s >= w.start_s) & (time_s < w.end_s)
            scale[inside] *= w.scale
            gp, gv = g.spawn(2)
            col_p[inside] += w.coloured_pos_m * gauss_markov_series(
                time_s[inside], 1.0, w.coloured_tau_s, gp, 3)
            col_v[inside] += w.coloured_vel_mps * gauss_markov_series(
                time_s[inside], 1.0, w.coloured_tau_s, gv, 3)
        gp, gv = g_gm.spawn(2)
        err_p = (scale[:, None] * np.asarray(self.pos_sigma_m) * g_wp.standard_normal((m, 3))
                 + np.asarray(self.gm_pos_sigma_m)
                 * gauss_markov_series(time_s, 1.0, self.gm_tau_s, gp, 3) + col_p)
        err_v = (scale[:, None] * np.asarray(self.vel_sigma_mps) * g_wv.standard_normal((m, 3))
                 + np.asarray(self.gm_vel_sigma_mps)
                 * gauss_markov_series(time_s, 1.0, self.gm_tau_s, gv, 3) + col_v)
        g_mask, g_dp, g_dv = g_out.spawn(3)
        outlier = g_mask.random(m) < self.outlier_rate
        k = int(outlier.sum())
        err_p[outlier] += self.outlier_pos_m * random_directions(g_dp, k)
        err_v[outlier] += self.outlier_vel_mps * random_directions(g_dv, k)
        return err_p, err_v, outlier

    def true_sigma(self, time_s) -> np.ndarray:
        """The 1-sigma of the simulated error's distribution at each epoch, ``(M, 6)``.

        White noise (scaled inside noise windows), the Gauss-Markov and coloured parts at
        their stationary sigma, and the outliers' share of the variance (probability times
        the per-axis spread of a fixed length in a random direction, ``L^2 / 3``) — the noise
        an oracle EKF (``ekf-true``) is told; it knows the distribution, not the draws.
        ENU metres and m/s.
        """
        m = time_s.size
        scale = np.ones(m)
        col = np.zeros((m, 2))
        for w in self.noise_windows:
            inside = (time_s >= w.start_s) & (time_s < w.end_s)
            scale[inside] *= w.scale
            col[inside] += (w.coloured_pos_m ** 2, w.coloured_vel_mps ** 2)
        var_p = ((scale[:, None] * np.asarray(self.pos_sigma_m)) ** 2
                 + np.square(self.gm_pos_sigma_m) + col[:, :1])
        var_v = ((scale[:, None] * np.asarray(self.vel_sigma_mps)) ** 2
                 + np.square(self.gm_vel_sigma_mps) + col[:, 1:])
        var_p += self.outlier_rate * self.outlier_pos_m ** 2 / 3.0
        var_v += self.outlier_rate * self.outlier_vel_mps ** 2 / 3.0
        return np.sqrt(np.hstack([var_p, var_v]))

    def simulate(self, truth, rng, start_utc=None) -> SensorData:
        """Fixes of this receiver along ``truth``.

        Parameters
        ----------
        truth : Trajectory
        rng : numpy.random.Generator
            Split internally: white noise, Gauss-Markov, noise windows and outliers each
            have their own stream.
        start_utc : datetime, optional
            Unused (GNSS errors here do not depend on the epoch).

        Returns
        -------
        SensorData
            ``meta``: ``lever_arm_b`` [m], ``rate_hz``, the true errors ``err_pos_enu_m`` and
            ``err_vel_enu_mps``, ``outlier_mask``, ``outage_windows`` (K, 2) and
            ``true_sigma`` (M, 6), the 1-sigma of the simulated noise per epoch.
        """
        idx = self.epochs(truth)
        time_s = np.asarray(truth.time_s)[idx]
        lla_ant, vel_ant = antenna_truth(truth, idx, self.lever_arm_b_m)
        err_p, err_v, outlier = self._errors(time_s, rng)
        dlat, dlon, dh = earth.enu_to_delta_lla(err_p, lla_ant[:, 0], lla_ant[:, 2])
        z = np.column_stack([lla_ant[:, 0] + dlat, lla_ant[:, 1] + dlon, lla_ant[:, 2] + dh,
                             vel_ant + err_v])
        sigma = np.broadcast_to(self.claimed_sigma(), z.shape).copy()
        if not self.velocity:
            z[:, 3:] = np.nan
            sigma[:, 3:] = np.nan
        windows = outage_windows(truth.time_s[-1], self.outages, self.outage_period_s,
                                 self.outage_duration_s, self.outage_first_s)
        keep = ~in_windows(time_s, windows)
        meta = {"lever_arm_b": np.array(self.lever_arm_b_m, dtype=float),
                "rate_hz": float(self.rate_hz), "err_pos_enu_m": err_p[keep],
                "err_vel_enu_mps": err_v[keep], "outlier_mask": outlier[keep],
                "outage_windows": windows,
                "true_sigma": self.true_sigma(time_s)[keep]}
        return SensorData(kind=self.kind, time_s=time_s[keep], z=z[keep], sigma=sigma[keep],
                          meta=meta)

    # -- TOML ---------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, d: dict, where: str) -> "Spec":
        """Parse a sensor table (``kind`` already checked); errors name ``where.key``."""
        t = Table(d, where)
        t.string("kind", cls.kind, choices=(cls.kind,))
        f = cls.__dataclass_fields__
        kw = {"rate_hz": t.number("rate_hz", f["rate_hz"].default, lo=0.0, hi=100.0,
                                  lo_open=True),
              "start_s": t.number("start_s", 0.0, lo=0.0),
              "velocity": t.boolean("velocity", True),
              "gm_tau_s": t.number("gm_tau_s", f["gm_tau_s"].default, lo=0.0, lo_open=True),
              "outlier_rate": t.number("outlier_rate", 0.0, lo=0.0, hi=1.0),
              "outages": t.windows("outages", 2),
              "outage_first_s": t.number("outage_first_s", None, lo=0.0)}
        for name in ("pos_sigma_m", "vel_sigma_mps", "gm_pos_sigma_m", "gm_vel_sigma_mps",
                     "claimed_pos_sigma_m", "claimed_vel_sigma_mps"):
            kw[name] = t.vector(name, 3, f[name].default, lo=0.0,
                                hi=MAX_POS_M if "pos" in name else _MAX_VEL_MPS)
        kw["outlier_pos_m"] = t.number("outlier_pos_m", 0.0, lo=0.0, hi=MAX_POS_M)
        kw["outlier_vel_mps"] = t.number("outlier_vel_mps", 0.0, lo=0.0, hi=_MAX_VEL_MPS)
        for name in ("outage_period_s", "outage_duration_s"):
            kw[name] = t.number(name, 0.0, lo=0.0)
        kw["lever_arm_b_m"] = t.vector("lever_arm_b_m", 3, _ZERO3, lo=-MAX_LEVER_ARM_M,
                                       hi=MAX_LEVER_ARM_M)
        kw["noise_windows"] = tuple(NoiseWindow.from_table(w)
                                    for w in t.tables("noise_windows", required=False))
        if (kw["outage_period_s"] > 0.0) != (kw["outage_duration_s"] > 0.0):
            raise t.error("outage_duration_s", "periodic outages need both outage_period_s "
                                               "and outage_duration_s")
        if kw["outage_duration_s"] >= kw["outage_period_s"] > 0.0:
            raise t.error("outage_duration_s", "must be shorter than outage_period_s")
        kw.update(cls.extra_fields(t))
        t.finish()
        spec = cls(**kw)
        claimed = spec.claimed_sigma()
        for key, part in (("claimed_pos_sigma_m", claimed[:3]),
                          ("claimed_vel_sigma_mps", claimed[3:] if spec.velocity else 1.0)):
            # a zero claimed sigma tells the filter R = 0: every fix is taken as exact
            if not np.all(part > 0.0):
                raise t.error(key, f"the claimed 1-sigma is zero on some axis (give {key} "
                                   "> 0, or a non-zero noise)")
        return spec

    @classmethod
    def extra_fields(cls, t: Table) -> dict:
        """Keys a variant (e.g. ``bds``) reads beyond these; none here."""
        return {}

    def to_dict(self) -> dict:
        """The sensor table (TOML-ready, ``None`` fields left out, ``kind`` included)."""
        return spec_table(self)


def antenna_truth(truth, idx, lever_arm_b_m):
    """True antenna position (lat, lon, h) and ENU velocity at trajectory samples ``idx``.

    ``p_ant = p + C_bn l`` (ENU offset converted with the local radii, exact to well below
    a millimetre for lever arms of metres) and ``v_ant = v + C_bn (omega_eb_b x l)`` with
    ``omega_eb_b = omega_nb_b + C_nb omega_en_n``.
    """
    lla = np.asarray(truth.lla)[idx]
    vel = np.asarray(truth.vel_n)[idx]
    lever = np.asarray(lever_arm_b_m, dtype=float)
    if not np.any(lever):
        return lla.copy(), vel.copy()
    C_bn = attitude.quat_to_dcm(np.asarray(truth.q_bn)[idx])
    offset_n = C_bn @ lever
    dlat, dlon, dh = earth.enu_to_delta_lla(offset_n, lla[:, 0], lla[:, 2])
    w_en_b = np.einsum("kji,kj->ki", C_bn, earth.omega_en_n(lla[:, 0], lla[:, 2], vel))
    w_eb_b = np.asarray(truth.omega_nb_b)[idx] + w_en_b
    vel_ant = vel + np.einsum("kij,kj->ki", C_bn, np.cross(w_eb_b, lever))
    return np.column_stack([lla[:, 0] + dlat, lla[:, 1] + dlon, lla[:, 2] + dh]), vel_ant

