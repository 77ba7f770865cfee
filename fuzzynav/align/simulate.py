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

__all__ = ["Sway", "AlignLog", "ideal_increments", "simulate_alignment"]


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


def _gusts(t, sway: Sway, rng):
    """Gauss-Markov gust velocity (E, N) on the grid ``t`` (exact discretisation)."""
    out = np.zeros((t.size, 3))
    if sway.gust_sigma_mps <= 0.0:
        return out
    phi = np.exp(-np.diff(t) / sway.gust_tau_s)
    e = rng.standard_normal((t.size, 2))
    out[0, :2] = sway.gust_sigma_mps * e[0]
    for k in range(1, t.size):
        out[k, :2] = phi[k - 1] * out[k - 1, :2] + sway.gust_sigma_mps * np.sqrt(
            1.0 - phi[k - 1] ** 2) * e[k]
    return out


def _velocity(t, sway: Sway, gusts):
    w = 2.0 * np.pi / np.asarray(sway.vel_period_s, dtype=float)
    v = np.asarray(sway.vel_amp_mps) * np.sin(np.outer(t, w)) + gusts
    return v


def ideal_increments(t, C_bn, vel_n, lat_rad, h_m):
    """Exact angle and Simpson velocity increments between the samples of ``t``.

    ``t`` holds the IMU samples and the mid-points between them (length 2N+1).
    """
    w_ie = earth.omega_ie_n(lat_rad)
    C_in = attitude.rotvec_to_dcm(np.outer(t, w_ie))
    C_ib = C_in @ C_bn
    dtheta = attitude.dcm_to_rotvec(np.swapaxes(C_ib[:-2:2], -1, -2) @ C_ib[2::2])
    acc = np.gradient(vel_n, t, axis=0)
    f_n = acc + 2.0 * np.cross(w_ie, vel_n) + np.array([0.0, 0.0, earth.gravity(lat_rad, h_m)])
    f_b = np.einsum("kji,kj->ki", C_bn, f_n)
    h = t[2::2] - t[:-2:2]
    dv = (f_b[:-2:2] + 4.0 * f_b[1::2] + f_b[2::2]) * (h / 6.0)[:, None]
    return dtheta, dv


def simulate_alignment(imu: ImuSpec, lat_rad, h_m, att0_rad, duration_s, rng,
                       sway: Sway = Sway()) -> AlignLog:
    """IMU data and truth of an alignment run.

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
    g_gust, g_imu = rng.spawn(2)
    n = int(round(duration_s * imu.rate_hz))
    t = np.linspace(0.0, n / imu.rate_hz, 2 * n + 1)
    C_bn = attitude.euler_to_dcm(_attitude(t, np.asarray(att0_rad, dtype=float), sway))
    vel = _velocity(t, sway, _gusts(t, sway, g_gust))
    dtheta, dv = ideal_increments(t, C_bn, vel, lat_rad, h_m)
    ideal = ImuData(time_s=t[::2], dtheta_b=dtheta, dv_b=dv)
    return AlignLog(imu=imu.corrupt(ideal, g_imu), lat_rad=float(lat_rad), h_m=float(h_m),
                    C_bn=C_bn[::2], vel_n=vel[::2])
