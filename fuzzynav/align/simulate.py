"""IMU data of a base at a fixed place: at rest, or swaying with gusts (a moored ship, a car
with its engine running).

The body attitude is ``(pitch, roll, heading)(t) = att0 + A sin(2 pi t / P + phase)`` per
angle; the base's velocity is a sum of a periodic surge/sway/heave ``v_amp sin(2 pi t/P_v)``
and gusts, a first-order Gauss-Markov velocity (``gust_sigma_mps``, ``gust_tau_s``) — the
position wanders by centimetres, so the earth terms are those of the fixed place.

Ideal increments are exact to the simulation's own integration: the angle increment is the
rotation vector of ``C_b^i(t_k)^T C_b^i(t_k+1)`` with ``C_b^i = exp([w_ie^n x] t) C_b^n``
(so the gyros see the earth rate and the sway), and the velocity increment is
``int C_b^n(t)^T f^n(t) dt`` by Simpson's rule, ``f^n = a + 2 w_ie x v - g^n``.  The IMU
errors are those of :class:`fuzzynav.sim.imu.ImuSpec` (datasheet units).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.nav import attitude, earth
from fuzzynav.sim.imu import ImuData, ImuSpec

__all__ = ["Sway", "AlignLog", "AlignChunk", "AlignChunks", "ideal_increments", "gradient",
           "grid", "simulate_alignment"]


@dataclass(frozen=True)
class Sway:
    """Angular sway and linear disturbance of the base (all zero: a stationary base).

    Attributes
    ----------
    amp_deg, period_s, phase_deg : tuple of 3 float
        Amplitude [deg], period [s] and phase [deg] of pitch, roll, heading.
    vel_amp_mps, vel_period_s : tuple of 3 float
        Periodic ENU velocity of the base [m/s] and its periods [s].
    gust_sigma_mps, gust_tau_s : float
        Gusts: Gauss-Markov velocity per horizontal axis [m/s] and correlation time [s].
    """

    amp_deg: tuple = (0.0, 0.0, 0.0)
    period_s: tuple = (8.0, 6.0, 10.0)
    phase_deg: tuple = (0.0, 30.0, 60.0)
    vel_amp_mps: tuple = (0.0, 0.0, 0.0)
    vel_period_s: tuple = (7.0, 9.0, 5.0)
    gust_sigma_mps: float = 0.0
    gust_tau_s: float = 2.0


@dataclass(frozen=True)
class AlignLog:
    """A simulated alignment run.

    Attributes
    ----------
    imu : ImuData
        Measured increments with the applied biases.
    lat_rad, h_m : float
        The fixed place.
    C_bn : ndarray, shape (N+1, 3, 3)
        True attitude at the IMU sample times.
    vel_n : ndarray, shape (N+1, 3)
        True velocity [m/s] (zero on a stationary base).
    """

    imu: ImuData
    lat_rad: float
    h_m: float
    C_bn: np.ndarray
    vel_n: np.ndarray


def _attitude(t, att0_rad, sway: Sway):
    a = np.radians(sway.amp_deg)
    w = 2.0 * np.pi / np.asarray(sway.period_s, dtype=float)
    ph = np.radians(sway.phase_deg)
    return att0_rad + a * np.sin(np.outer(t, w) + ph)


class _Gusts:
    """The Gauss-Markov gust velocity (E, N), exact discretisation, made for consecutive
    pieces of the grid: each piece draws its own normals in turn and carries the last
    point, so the pieces are one draw over the whole grid to the last bit."""

    def __init__(self, sway: Sway, rng):
        self.sway, self.rng, self.last = sway, rng, None   # (t, value) of the last point

    def next(self, t) -> np.ndarray:
        """The gusts at the grid points ``t`` following those made before."""
        out = np.zeros((t.size, 3))
        sigma = self.sway.gust_sigma_mps
        if sigma <= 0.0 or not t.size:
            return out
        e = self.rng.standard_normal((t.size, 2))
        if self.last is None:
            prev_t, k0 = t[:1], 1
            out[0, :2] = sigma * e[0]
        else:
            prev_t, k0 = np.array([self.last[0]]), 0
            out_prev = self.last[1]
        phi = np.exp(-np.diff(np.concatenate([prev_t, t[k0:]])) / self.sway.gust_tau_s)
        for k in range(k0, t.size):
            before = out[k - 1, :2] if k > 0 else out_prev
            out[k, :2] = phi[k - k0] * before + sigma * np.sqrt(1.0 - phi[k - k0] ** 2) * e[k]
        self.last = (t[-1], out[-1, :2].copy())
        return out


def _velocity(t, sway: Sway, gusts):
    w = 2.0 * np.pi / np.asarray(sway.vel_period_s, dtype=float)
    v = np.asarray(sway.vel_amp_mps) * np.sin(np.outer(t, w)) + gusts
    return v


def ideal_increments(t, C_bn, vel_n, lat_rad, h_m, acc_n=None):
    """Exact angle and Simpson velocity increments between the samples of ``t``.

    ``t`` holds the IMU samples and the mid-points between them (length 2N+1); ``acc_n``
    the acceleration at them (default: :func:`gradient` of ``vel_n``).
    """
    w_ie = earth.omega_ie_n(lat_rad)
    C_in = attitude.rotvec_to_dcm(np.outer(t, w_ie))
    C_ib = C_in @ C_bn
    dtheta = attitude.dcm_to_rotvec(np.swapaxes(C_ib[:-2:2], -1, -2) @ C_ib[2::2])
    acc = gradient(vel_n, t) if acc_n is None else acc_n
    f_n = acc + 2.0 * np.cross(w_ie, vel_n) + np.array([0.0, 0.0, earth.gravity(lat_rad, h_m)])
    f_b = np.einsum("kji,kj->ki", C_bn, f_n)
    h = t[2::2] - t[:-2:2]
    dv = (f_b[:-2:2] + 4.0 * f_b[1::2] + f_b[2::2]) * (h / 6.0)[:, None]
    return dtheta, dv


def gradient(f, t) -> np.ndarray:
    """``np.gradient(f, t, axis=0)`` by its formula for an uneven grid, always: numpy takes
    another formula when the spacing is exactly even, which a piece of a grid may be when
    the whole is not, so a chunk would differ from the whole run in its last bits."""
    dx = np.diff(t)
    dx1, dx2 = dx[:-1], dx[1:]
    a = (-(dx2) / (dx1 * (dx1 + dx2)))[:, None]
    b = ((dx2 - dx1) / (dx1 * dx2))[:, None]
    c = (dx1 / (dx2 * (dx1 + dx2)))[:, None]
    out = np.empty_like(f, dtype=float)
    out[1:-1] = a * f[:-2] + b * f[1:-1] + c * f[2:]
    out[0] = (f[1] - f[0]) / dx[0]
    out[-1] = (f[-1] - f[-2]) / dx[-1]
    return out


def grid(j0: int, j1: int, num: int, stop: float) -> np.ndarray:
    """Points ``j0 .. j1-1`` of ``np.linspace(0, stop, num)``, to the last bit (numpy's
    ``j * (stop / (num - 1))``, the last point ``stop`` itself)."""
    t = np.arange(j0, j1, dtype=float) * (stop / (num - 1))
    if j1 == num:
        t[-1] = stop
    return t


@dataclass(frozen=True)
class AlignChunk:
    """IMU samples ``k0 .. k1`` of an alignment run: the increments between them (``imu``,
    ``time_s`` of the ``k1 - k0 + 1`` samples) and the truth at them."""

    k0: int
    k1: int
    imu: ImuData
    C_bn: np.ndarray
    vel_n: np.ndarray


class AlignChunks:
    """An alignment run's IMU data and truth made chunk by chunk, each the whole run's to
    the last bit (:func:`simulate_alignment` is the one-chunk case).

    The time grid (samples and mid-points) is :func:`grid`'s; each chunk's acceleration is
    :func:`gradient` over its piece of the grid widened by a point each side (only the run's
    own ends take the one-sided formula); the gusts (:class:`_Gusts`) and the IMU errors
    (:class:`~fuzzynav.sim.imu.ImuStream`) carry their random processes across chunks.

    Parameters
    ----------
    imu, lat_rad, h_m, att0_rad, duration_s, rng, sway
        As :func:`simulate_alignment`.
    chunk_samples : int, optional
        IMU samples per chunk (default: the whole run in one).
    """

    def __init__(self, imu: ImuSpec, lat_rad, h_m, att0_rad, duration_s, rng,
                 sway: Sway = Sway(), chunk_samples: int | None = None):
        self.imu_spec, self.lat_rad, self.h_m, self.sway = imu, float(lat_rad), float(h_m), sway
        self.att0 = np.asarray(att0_rad, dtype=float)
        self.n = int(round(duration_s * imu.rate_hz))
        self.chunk = self.n if chunk_samples is None else max(1, int(chunk_samples))
        self.g_gust, self.g_imu = rng.spawn(2)

    def __iter__(self):
        n, num, stop = self.n, 2 * self.n + 1, self.n / self.imu_spec.rate_hz
        gusts, errors = _Gusts(self.sway, self.g_gust), self.imu_spec.stream(self.g_imu)
        made, tail = 0, np.zeros((0, 3))   # grid points whose gusts are drawn; the last few
        for k0 in range(0, max(n, 1), self.chunk):
            k1 = min(k0 + self.chunk, n)
            lo, hi = max(2 * k0 - 1, 0), min(2 * k1 + 2, num)
            t = grid(lo, hi, num, stop)
            g = np.vstack([tail[tail.shape[0] - (made - lo):], gusts.next(t[made - lo:])])
            made, tail = hi, g[-3:]
            vel = _velocity(t, self.sway, g)
            C = attitude.euler_to_dcm(_attitude(t, self.att0, self.sway))
            a, b = 2 * k0 - lo, 2 * k1 - lo + 1           # this chunk's grid points
            dtheta, dv = ideal_increments(t[a:b], C[a:b], vel[a:b], self.lat_rad, self.h_m,
                                          gradient(vel, t)[a:b])
            ideal = ImuData(time_s=t[a:b:2], dtheta_b=dtheta, dv_b=dv)
            yield AlignChunk(k0, k1, errors.corrupt(ideal), C[a:b:2], vel[a:b:2])


def simulate_alignment(imu: ImuSpec, lat_rad, h_m, att0_rad, duration_s, rng,
                       sway: Sway = Sway()) -> AlignLog:
    """IMU data and truth of an alignment run (:class:`AlignChunks` in one chunk).

    Parameters
    ----------
    imu : ImuSpec
        Sensor errors (datasheet units) and rate.
    lat_rad, h_m : float
        Place.
    att0_rad : array_like, shape (3,)
        Mean (pitch, roll, heading) of the base [rad].
    duration_s : float
    rng : numpy.random.Generator
    sway : Sway
        Base motion (default: at rest).
    """
    (whole,) = AlignChunks(imu, lat_rad, h_m, att0_rad, duration_s, rng, sway)
    return AlignLog(imu=whole.imu, lat_rad=float(lat_rad), h_m=float(h_m), C_bn=whole.C_bn,
                    vel_n=whole.vel_n)
