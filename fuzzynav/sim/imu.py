"""IMU error model in datasheet units and its application to ideal increments.

Each sensor triad (gyro, accelerometer) outputs over the interval ``[t_k, t_k+1]`` of
length ``h`` the increment

    y_k = (I + S + M) u_k + (b_c + b_0) h + I_gm,k + I_rw,k + N sqrt(h) w_k,

with ``u_k`` the ideal increment (``dtheta_b`` [rad] or ``dv_b`` [m/s]), ``S = diag(scale)``
the scale-factor error, ``M`` the misalignment (small angles off the diagonal, ``M[i, j]``
the sensitivity of axis i to true axis j), ``b_c`` a fixed bias, ``b_0`` a turn-on bias
drawn once per run, ``I_gm`` and ``I_rw`` the exact interval integrals of a first-order
Gauss-Markov bias instability and of a rate random walk (:mod:`fuzzynav.sim.gauss_markov`),
and ``N`` the white-noise density: a rate noise of density ``N`` [unit/sqrt(Hz)] integrates
to an increment noise of standard deviation ``N sqrt(h)`` (ARW for the gyro, VRW for the
accelerometer).  All axes have the same noise figures; the fixed bias, scale factor and
misalignment are per axis.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields

import numpy as np

from fuzzynav import units
from fuzzynav.errors import InputFileError
from fuzzynav.sim.tomltable import Table
from fuzzynav.sim.triad_stream import TriadStream

__all__ = ["FILTER_STATES", "TriadNoise", "TriadStream", "ImuNoise", "ImuData", "ImuSpec",
           "ImuStream", "rate_hz_of"]

_ZERO3 = (0.0, 0.0, 0.0)
_ZERO33 = (_ZERO3, _ZERO3, _ZERO3)
#: how filters model the biases (ImuSpec.filter_states)
FILTER_STATES = ("constant", "markov")
#: per root-hour: sqrt(3600 s) = 60 [sqrt(s)]
_ROOT_HOUR = 60.0


@dataclass(frozen=True)
class TriadNoise:
    """Error figures of one sensor triad in SI units (the filter's view of a datasheet).

    Attributes
    ----------
    bias : tuple of 3 float
        Fixed bias [rad/s or m/s^2].
    bias_sigma : float
        Standard deviation of the turn-on bias, per axis [rad/s or m/s^2].
    white : float
        White-noise density: ARW [rad/sqrt(s)] or VRW [m/s/sqrt(s)].
    gm_sigma : float
        Stationary standard deviation of the Gauss-Markov bias instability.
    gm_tau_s : float
        Its correlation time [s].
    rrw : float
        Rate random walk [rad/s/sqrt(s)] or acceleration random walk [m/s^2/sqrt(s)].
    scale : tuple of 3 float
        Scale-factor errors [-].
    misalign : 3x3 tuple
        Misalignment angles [rad], zero diagonal.
    """

    bias: tuple = _ZERO3
    bias_sigma: float = 0.0
    white: float = 0.0
    gm_sigma: float = 0.0
    gm_tau_s: float = 3600.0
    rrw: float = 0.0
    scale: tuple = _ZERO3
    misalign: tuple = _ZERO33

    @property
    def matrix(self) -> np.ndarray:
        """``I + S + M``: true increment to measured increment (3x3)."""
        return np.eye(3) + np.diag(self.scale) + np.asarray(self.misalign, dtype=float)

    @property
    def bias_p0(self) -> np.ndarray:
        """Per-axis a-priori bias spread ``sqrt(bias^2 + bias_sigma^2 + gm_sigma^2)``."""
        return np.sqrt(np.square(self.bias) + self.bias_sigma**2 + self.gm_sigma**2)

    def corrupt(self, ideal, h_s, rng):
        """Apply the errors to ideal increments.

        Parameters
        ----------
        ideal : ndarray, shape (N, 3)
            Ideal increments.
        h_s : ndarray, shape (N,)
            Interval lengths [s].
        rng : numpy.random.Generator

        Returns
        -------
        measured : ndarray, shape (N, 3)
        bias : ndarray, shape (N+1, 3)
            Total bias (fixed + turn-on + Gauss-Markov + random walk) at the sample times.
        turn_on : ndarray, shape (3,)
            The turn-on bias drawn for this run.
        """
        stream = TriadStream(self, rng)
        out, bias = stream.corrupt(ideal, h_s)
        return out, bias, stream.turn_on


@dataclass(frozen=True)
class ImuNoise:
    """SI noise figures of both triads, for a filter's process noise and initial covariance.

    Attributes
    ----------
    gyro, accel : TriadNoise
    filter_states : {"constant", "markov"}
        How a filter configured from these figures models the biases
        (:func:`fuzzynav.filters.named.config_from_imu`).
    """

    gyro: TriadNoise
    accel: TriadNoise
    filter_states: str = "constant"

    @property
    def arw_rad_psqrts(self) -> float:
        """Angle random walk [rad/sqrt(s)] (gyro white-noise density)."""
        return self.gyro.white

    @property
    def vrw_mps_psqrts(self) -> float:
        """Velocity random walk [m/s/sqrt(s)] (accelerometer white-noise density)."""
        return self.accel.white


def rate_hz_of(imu) -> float:
    """The rate of an IMU log's increments [Hz] (anything with ``time_s``): one over the
    median interval (a recording's gaps and jitter aside), what a chunk length in seconds
    is counted in."""
    return 1.0 / float(np.median(np.diff(imu.time_s)))


@dataclass(frozen=True)
class ImuData:
    """IMU increments over a run, with the truth of the applied errors when simulated.

    Attributes
    ----------
    time_s : ndarray, shape (N+1,)
        Sample times [s]; increment k covers ``[time_s[k], time_s[k+1]]``.
    dtheta_b : ndarray, shape (N, 3)
        Angle increments [rad], body frame.
    dv_b : ndarray, shape (N, 3)
        Velocity increments (specific force integrated) [m/s], body frame.
    gyro_bias_rps, accel_bias_mps2 : ndarray, shape (N+1, 3), or None
        Total applied bias at the sample times [rad/s], [m/s^2] (``None`` for real data).
    meta : dict
        Numbers and arrays: for simulations ``gyro_turn_on_rps``, ``accel_turn_on_mps2``
        and the applied ``gyro_matrix`` / ``accel_matrix`` (``I + S + M``).
    """

    time_s: np.ndarray
    dtheta_b: np.ndarray
    dv_b: np.ndarray
    gyro_bias_rps: np.ndarray | None = None
    accel_bias_mps2: np.ndarray | None = None
    meta: dict = field(default_factory=dict)

    @property
    def rate_hz(self) -> float:
        """The increments' rate [Hz] (:func:`rate_hz_of`)."""
        return rate_hz_of(self)

    def __post_init__(self):
        n = self.dtheta_b.shape[0]
        if (self.time_s.shape != (n + 1,) or self.dtheta_b.shape != (n, 3)
                or self.dv_b.shape != (n, 3)):
            raise ValueError(f"ImuData: inconsistent shapes time {self.time_s.shape}, "
                             f"dtheta {self.dtheta_b.shape}, dv {self.dv_b.shape}")

    @property
    def n_samples(self) -> int:
        """Number of increments N."""
        return self.dtheta_b.shape[0]

    @property
    def span_s(self) -> tuple:
        """The first and last sample time [s]."""
        return float(self.time_s[0]), float(self.time_s[-1])

    @property
    def rate_hz(self) -> float:
        """Nominal rate: the inverse of the median interval [Hz]."""
        return float(1.0 / np.median(np.diff(self.time_s)))


# datasheet field -> (triad, TriadNoise field, SI factor, constraint)
_FIELDS = {
    "gyro_bias_dph": ("gyro", "bias", units.DPH, "vec"),
    "gyro_bias_sigma_dph": ("gyro", "bias_sigma", units.DPH, "nonneg"),
    "gyro_arw_dpsh": ("gyro", "white", units.DPSH, "nonneg"),
    "gyro_bi_sigma_dph": ("gyro", "gm_sigma", units.DPH, "nonneg"),
    "gyro_bi_tau_s": ("gyro", "gm_tau_s", 1.0, "pos"),
    "gyro_rrw_dph_psh": ("gyro", "rrw", units.DPH_PSH, "nonneg"),
    "gyro_sf_ppm": ("gyro", "scale", units.PPM, "vec"),
    "gyro_misalign_deg": ("gyro", "misalign", units.DEG, "mat"),
    "accel_bias_ug": ("accel", "bias", units.UG, "vec"),
    "accel_bias_sigma_ug": ("accel", "bias_sigma", units.UG, "nonneg"),
    "accel_vrw_ug_psqrthz": ("accel", "white", units.UG_PSQRTHZ, "nonneg"),
    "accel_bi_sigma_ug": ("accel", "gm_sigma", units.UG, "nonneg"),
    "accel_bi_tau_s": ("accel", "gm_tau_s", 1.0, "pos"),
    "accel_rrw_ug_psh": ("accel", "rrw", units.UG / _ROOT_HOUR, "nonneg"),
    "accel_sf_ppm": ("accel", "scale", units.PPM, "vec"),
    "accel_misalign_deg": ("accel", "misalign", units.DEG, "mat"),
}


#: largest magnitude of each datasheet figure: far beyond any real IMU (a 1-g accelerometer
#: bias, a 100 000 deg/h gyro bias, a 10 % scale error), below anything that overflows
_LIMITS = {"dph": 1e5, "dpsh": 1e3, "ug": 1e6, "ppm": 1e5, "misalign_deg": 10.0,
           "tau_s": 1e7}


def _limit(name: str) -> float:
    return next(v for k, v in _LIMITS.items() if k in name.split("_", 1)[1])


@dataclass(frozen=True)
class ImuSpec:
    """IMU specification in datasheet units (the ``[imu]`` table of a scenario).

    Parameters
    ----------
    rate_hz : float
        Sampling rate [Hz] (the models are exact at any rate; 50-200 Hz is typical).
    gyro_bias_dph : tuple of 3 float
        Fixed gyro bias [deg/h].
    gyro_bias_sigma_dph : float
        Turn-on gyro bias, 1-sigma per axis, drawn once per run [deg/h].
    gyro_arw_dpsh : float
        Angle random walk [deg/sqrt(h)] (a density of D deg/h/sqrt(Hz) is D/60 deg/sqrt(h)).
    gyro_bi_sigma_dph, gyro_bi_tau_s : float
        Bias instability as a first-order Gauss-Markov process: stationary 1-sigma [deg/h]
        and correlation time [s].
    gyro_rrw_dph_psh : float
        Rate random walk [deg/h/sqrt(h)].
    gyro_sf_ppm : tuple of 3 float
        Scale-factor errors [ppm].
    gyro_misalign_deg : 3x3 tuple
        Misalignment [deg], zero diagonal: ``M[i][j]`` couples true axis j into axis i.
    accel_bias_ug, accel_bias_sigma_ug : tuple, float
        Fixed and turn-on accelerometer bias [micro-g].
    accel_vrw_ug_psqrthz : float
        Velocity random walk as a noise density [micro-g/sqrt(Hz)].
    accel_bi_sigma_ug, accel_bi_tau_s : float
        Accelerometer bias instability (Gauss-Markov) [micro-g], [s].
    accel_rrw_ug_psh : float
        Acceleration random walk [micro-g/sqrt(h)].
    accel_sf_ppm, accel_misalign_deg
        As for the gyro.
    filter_states : {"constant", "markov"}
        The filters' bias states: random constants with a random walk (default), or as
        paper 003 a gyro constant, a gyro Gauss-Markov and an accelerometer Gauss-Markov
        block with the ``*_bi_tau_s`` correlation times (18 states).  Not an IMU property,
        but the datasheet is where the filter's IMU model is chosen.
    """

    rate_hz: float = 100.0
    gyro_bias_dph: tuple = _ZERO3
    gyro_bias_sigma_dph: float = 0.0
    gyro_arw_dpsh: float = 0.0
    gyro_bi_sigma_dph: float = 0.0
    gyro_bi_tau_s: float = 3600.0
    gyro_rrw_dph_psh: float = 0.0
    gyro_sf_ppm: tuple = _ZERO3
    gyro_misalign_deg: tuple = _ZERO33
    accel_bias_ug: tuple = _ZERO3
    accel_bias_sigma_ug: float = 0.0
    accel_vrw_ug_psqrthz: float = 0.0
    accel_bi_sigma_ug: float = 0.0
    accel_bi_tau_s: float = 3600.0
    accel_rrw_ug_psh: float = 0.0
    accel_sf_ppm: tuple = _ZERO3
    accel_misalign_deg: tuple = _ZERO33
    filter_states: str = "constant"

    def __post_init__(self):
        # tuples of floats, so that specs built from lists compare and hash alike
        for name, (_, _, _, kind) in _FIELDS.items():
            value = getattr(self, name)
            if kind == "vec":
                object.__setattr__(self, name, tuple(float(v) for v in value))
            elif kind == "mat":
                object.__setattr__(self, name, tuple(tuple(float(v) for v in r) for r in value))
        if not (np.isfinite(self.rate_hz) and 0.0 < self.rate_hz <= 2000.0):
            raise InputFileError(None, "imu.rate_hz", f"must lie in (0, 2000] Hz, "
                                                      f"got {self.rate_hz!r}")
        if self.filter_states not in FILTER_STATES:
            raise InputFileError(None, "imu.filter_states", f"must be one of "
                                 f"{', '.join(FILTER_STATES)}, got {self.filter_states!r}")
        for name in ("gyro_misalign_deg", "accel_misalign_deg"):
            if any(getattr(self, name)[i][i] != 0.0 for i in range(3)):
                raise InputFileError(None, f"imu.{name}",
                                     "the diagonal must be zero (scale errors go in *_sf_ppm)")

    # -- SI view ------------------------------------------------------------------------
    def _triad(self, triad: str) -> TriadNoise:
        kw = {}
        for name, (tri, attr, factor, kind) in _FIELDS.items():
            if tri != triad:
                continue
            value = getattr(self, name)
            if kind == "vec":
                value = tuple(float(v) * factor for v in value)
            elif kind == "mat":
                value = tuple(tuple(float(v) * factor for v in row) for row in value)
            else:
                value = float(value) * factor
            kw[attr] = value
        return TriadNoise(**kw)

    def noise_si(self) -> ImuNoise:
        """The error figures in SI units (ARW [rad/sqrt(s)], VRW [m/s/sqrt(s)], ...)."""
        return ImuNoise(gyro=self._triad("gyro"), accel=self._triad("accel"),
                        filter_states=self.filter_states)

    # -- application --------------------------------------------------------------------
    def corrupt(self, ideal, rng) -> ImuData:
        """Corrupt ideal increments with this error model.

        Parameters
        ----------
        ideal : Trajectory or ImuData
            Anything with ``time_s`` (N+1,), ``dtheta_b`` and ``dv_b`` (N, 3).
        rng : numpy.random.Generator
            Split internally (``spawn``) so that each error term has its own stream:
            changing one figure does not change the realisation of the others.

        Returns
        -------
        ImuData
            Measured increments with the applied bias series as truth.
        """
        return self.stream(rng).corrupt(ideal)

    def stream(self, rng) -> "ImuStream":
        """The errors applied chunk by chunk (:class:`ImuStream`; :meth:`corrupt` is the
        one-chunk case)."""
        return ImuStream(self.noise_si(), rng)

    # -- TOML ---------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, d: dict, where: str = "imu") -> "ImuSpec":
        """Parse the ``[imu]`` table (errors name ``where.key``)."""
        t = Table(d, where)
        kw = {"rate_hz": t.number("rate_hz", cls.rate_hz, lo=0.0, hi=2000.0, lo_open=True)}
        kw["filter_states"] = t.string("filter_states", "constant", choices=FILTER_STATES)
        for f in fields(cls):
            if f.name in ("rate_hz", "filter_states"):
                continue
            kind, hi = _FIELDS[f.name][3], _limit(f.name)
            if kind == "vec":
                kw[f.name] = t.vector(f.name, 3, f.default, lo=-hi, hi=hi)
            elif kind == "mat":
                kw[f.name] = t.matrix(f.name, 3, f.default, lo=-hi, hi=hi)
            else:
                kw[f.name] = t.number(f.name, f.default, lo=0.0, hi=hi, lo_open=kind == "pos")
        t.finish()
        try:
            return cls(**kw)
        except InputFileError as exc:
            raise InputFileError(None, exc.where.replace("imu", where, 1), exc.what) from None

    def to_dict(self) -> dict:
        """The ``[imu]`` table (TOML-ready; round-trips through :meth:`from_dict`)."""
        # filter_states only when set, so that older scenarios keep their cache keys
        return {k: (list(map(list, v)) if k.endswith("misalign_deg") else
                    list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()
                if k != "filter_states" or v != "constant"}


class ImuStream:
    """An IMU's errors applied to consecutive chunks of ideal increments, to the last bit
    those of one :meth:`ImuSpec.corrupt` over the whole run (:class:`TriadStream`)."""

    def __init__(self, noise: ImuNoise, rng):
        g_gyro, g_accel = rng.spawn(2)
        self.gyro, self.accel = TriadStream(noise.gyro, g_gyro), TriadStream(noise.accel, g_accel)
        self.meta = {"gyro_turn_on_rps": self.gyro.turn_on,
                     "accel_turn_on_mps2": self.accel.turn_on,
                     "gyro_matrix": noise.gyro.matrix, "accel_matrix": noise.accel.matrix}

    def corrupt(self, ideal) -> ImuData:
        """The next chunk: ``ideal`` with ``time_s`` (N+1,) starting at the last chunk's
        end, ``dtheta_b`` and ``dv_b`` (N, 3)."""
        time_s = np.array(ideal.time_s, dtype=float)
        h_s = np.diff(time_s)
        dtheta, gyro_bias = self.gyro.corrupt(np.asarray(ideal.dtheta_b), h_s)
        dv, accel_bias = self.accel.corrupt(np.asarray(ideal.dv_b), h_s)
        return ImuData(time_s=time_s, dtheta_b=dtheta, dv_b=dv, gyro_bias_rps=gyro_bias,
                       accel_bias_mps2=accel_bias, meta=dict(self.meta))
