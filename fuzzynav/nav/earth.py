"""WGS-84 earth model, navigation-frame rates and position conversions.

Conventions
-----------
* Navigation frame n is local-level **ENU** (east, north, up).
* Geodetic position is ``(lat_rad, lon_rad, h_m)``: latitude and longitude in radians,
  ellipsoidal height in metres.  Degrees appear only at the edges (CLI, files, plots).
* Gravity is WGS-84 *normal* gravity (Somigliana on the ellipsoid, second-order height
  correction), pointing along -up; the deflection of the vertical is ignored.

All functions accept scalars or numpy arrays and broadcast; the ``*_nb`` variants are numba
kernels on scalars for the compiled filter loop.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["A", "F", "E2", "B", "OMEGA_IE", "GM", "GAMMA_E", "K_SOMIGLIANA", "M_RATIO",
           "radii_nb", "radii_sin_nb", "radii_gravity_sin_nb", "gravity_nb", "gravity_sin_nb",
           "radii", "gravity", "omega_ie_n", "omega_en_n", "lla_to_ecef", "ecef_to_lla",
           "lla_to_enu", "enu_to_lla", "delta_lla_to_enu", "enu_to_delta_lla"]

#: semi-major axis [m]
A = 6378137.0
#: flattening
F = 1.0 / 298.257223563
#: first eccentricity squared
E2 = F * (2.0 - F)
#: semi-minor axis [m]
B = A * (1.0 - F)
#: earth rotation rate [rad/s]
OMEGA_IE = 7.292115e-5
#: geocentric gravitational constant [m^3/s^2]
GM = 3.986004418e14
#: normal gravity at the equator [m/s^2] and Somigliana's constant
GAMMA_E = 9.7803253359
K_SOMIGLIANA = 0.00193185265241
#: m = omega^2 a^2 b / GM
M_RATIO = OMEGA_IE**2 * A**2 * B / GM


@nb.njit(cache=True, error_model="numpy")
def radii_nb(lat_rad):
    """Meridian and prime-vertical radii of curvature ``(R_M, R_N)`` [m] (numba scalar)."""
    return radii_sin_nb(math.sin(lat_rad))


@nb.njit(cache=True, error_model="numpy")
def radii_sin_nb(sin_lat):
    """:func:`radii_nb` from the sine of the latitude (for callers that already have it)."""
    w2 = 1.0 - E2 * sin_lat * sin_lat
    r_n = A / math.sqrt(w2)
    return r_n * (1.0 - E2) / w2, r_n


#: the height term's coefficient 3 / a^2 of :func:`gravity_sin_nb`, formed once
_G_H2 = 3.0 / (A * A)


@nb.njit(cache=True, error_model="numpy")
def radii_gravity_sin_nb(sin_lat, h_m):
    """``R_M, R_N`` (:func:`radii_sin_nb`) and normal gravity (:func:`gravity_sin_nb`) at
    once, for the strapdown step that needs all three at every IMU sample.

    One square root and one division where the two functions take two and four: the same
    formulas with ``1 / sqrt(1 - e^2 sin^2 L)`` formed once, so the values differ from
    theirs in the last digits only (rounding).
    """
    s2 = sin_lat * sin_lat
    inv_w = 1.0 / math.sqrt(1.0 - E2 * s2)
    r_n = A * inv_w
    g0 = GAMMA_E * (1.0 + K_SOMIGLIANA * s2) * inv_w
    g = g0 * (1.0 - 2.0 / A * (1.0 + F + M_RATIO - 2.0 * F * s2) * h_m + _G_H2 * h_m * h_m)
    return r_n * (1.0 - E2) * (inv_w * inv_w), r_n, g


@nb.njit(cache=True, error_model="numpy")
def gravity_nb(lat_rad, h_m):
    """Magnitude of WGS-84 normal gravity [m/s^2] at latitude and height (numba scalar)."""
    return gravity_sin_nb(math.sin(lat_rad), h_m)


@nb.njit(cache=True, error_model="numpy")
def gravity_sin_nb(sin_lat, h_m):
    """:func:`gravity_nb` from the sine of the latitude (for callers that already have it)."""
    s2 = sin_lat * sin_lat
    g0 = GAMMA_E * (1.0 + K_SOMIGLIANA * s2) / math.sqrt(1.0 - E2 * s2)
    return g0 * (1.0 - 2.0 / A * (1.0 + F + M_RATIO - 2.0 * F * s2) * h_m
                 + 3.0 * h_m * h_m / (A * A))


def radii(lat_rad):
    """Meridian ``R_M`` and prime-vertical ``R_N`` radii of curvature [m].

    Parameters
    ----------
    lat_rad : float or array_like
        Geodetic latitude [rad].

    Returns
    -------
    R_M, R_N : float or ndarray
    """
    s = np.sin(lat_rad)
    w2 = 1.0 - E2 * s * s
    r_n = A / np.sqrt(w2)
    return r_n * (1.0 - E2) / w2, r_n


def gravity(lat_rad, h_m):
    """WGS-84 normal gravity magnitude [m/s^2] with second-order height correction."""
    s2 = np.sin(lat_rad) ** 2
    g0 = GAMMA_E * (1.0 + K_SOMIGLIANA * s2) / np.sqrt(1.0 - E2 * s2)
    return g0 * (1.0 - 2.0 / A * (1.0 + F + M_RATIO - 2.0 * F * s2) * h_m
                 + 3.0 * np.square(h_m) / A**2)


def omega_ie_n(lat_rad):
    """Earth rate in the ENU frame ``[0, w cos L, w sin L]`` [rad/s], shape (..., 3)."""
    lat = np.asarray(lat_rad, dtype=float)
    return np.stack([np.zeros_like(lat), OMEGA_IE * np.cos(lat), OMEGA_IE * np.sin(lat)], -1)


def omega_en_n(lat_rad, h_m, vel_n):
    """Transport rate of the ENU frame over the earth [rad/s], shape (..., 3).

    ``[-v_N/(R_M+h), v_E/(R_N+h), v_E tan(L)/(R_N+h)]``.
    """
    vel_n = np.asarray(vel_n, dtype=float)
    r_m, r_n = radii(lat_rad)
    ve, vn = vel_n[..., 0], vel_n[..., 1]
    return np.stack([-vn / (r_m + h_m), ve / (r_n + h_m),
                     ve * np.tan(lat_rad) / (r_n + h_m)], -1)


def lla_to_ecef(lat_rad, lon_rad, h_m):
    """Geodetic to earth-centred earth-fixed coordinates [m], shape (..., 3)."""
    _, r_n = radii(lat_rad)
    cl = np.cos(lat_rad)
    return np.stack([(r_n + h_m) * cl * np.cos(lon_rad),
                     (r_n + h_m) * cl * np.sin(lon_rad),
                     (r_n * (1.0 - E2) + h_m) * np.sin(lat_rad)], -1)


def ecef_to_lla(xyz_m):
    """ECEF [m] to geodetic ``(lat_rad, lon_rad, h_m)`` (closed form, Vermeille 2004).

    Exact to well below a micrometre for points from the earth's centre region outwards
    (any height above -6 000 km); returns a tuple of arrays.
    """
    xyz = np.asarray(xyz_m, dtype=float)
    x, y, z = xyz[..., 0], xyz[..., 1], xyz[..., 2]
    p2 = x * x + y * y
    p = np.sqrt(p2)
    e4 = E2 * E2
    pp = p2 / A**2
    q = (1.0 - E2) / A**2 * z * z
    r = (pp + q - e4) / 6.0
    s = e4 * pp * q / (4.0 * r**3)
    t = np.cbrt(1.0 + s + np.sqrt(s * (2.0 + s)))
    u = r * (1.0 + t + 1.0 / t)
    v = np.sqrt(u * u + e4 * q)
    w = E2 * (u + v - q) / (2.0 * v)
    k = np.sqrt(u + v + w * w) - w
    d = k * p / (k + E2)
    hyp = np.hypot(d, z)
    lat = 2.0 * np.arctan2(z, d + hyp)
    h = (k + E2 - 1.0) / k * hyp
    lon = np.arctan2(y, x)
    return lat, lon, h


def _ecef_to_enu_matrix(lat0_rad, lon0_rad):
    """Rotation matrix taking ECEF vectors to ENU at the reference point (3x3)."""
    sl, cl = np.sin(lat0_rad), np.cos(lat0_rad)
    so, co = np.sin(lon0_rad), np.cos(lon0_rad)
    return np.array([[-so, co, 0.0],
                     [-sl * co, -sl * so, cl],
                     [cl * co, cl * so, sl]])


def lla_to_enu(lat_rad, lon_rad, h_m, lat0_rad, lon0_rad, h0_m):
    """Geodetic points to local ENU coordinates [m] about a reference point, (..., 3)."""
    d = lla_to_ecef(lat_rad, lon_rad, h_m) - lla_to_ecef(lat0_rad, lon0_rad, h0_m)
    return d @ _ecef_to_enu_matrix(lat0_rad, lon0_rad).T


def enu_to_lla(enu_m, lat0_rad, lon0_rad, h0_m):
    """Local ENU coordinates [m] about a reference point to geodetic (lat, lon, h)."""
    enu = np.asarray(enu_m, dtype=float)
    xyz = enu @ _ecef_to_enu_matrix(lat0_rad, lon0_rad) + lla_to_ecef(lat0_rad, lon0_rad, h0_m)
    return ecef_to_lla(xyz)


def delta_lla_to_enu(dlat_rad, dlon_rad, dh_m, lat_rad, h_m):
    """Small geodetic differences to ENU metres with the local radii (first order), (..., 3).

    Used for filter residuals, where differences are metres to kilometres; for larger
    separations use :func:`lla_to_enu`.
    """
    r_m, r_n = radii(lat_rad)
    return np.stack([np.asarray(dlon_rad) * (r_n + h_m) * np.cos(lat_rad),
                     np.asarray(dlat_rad) * (r_m + h_m),
                     np.broadcast_to(dh_m, np.shape(dlat_rad))], -1)


def enu_to_delta_lla(enu_m, lat_rad, h_m):
    """Inverse of :func:`delta_lla_to_enu`: ENU metres to ``(dlat_rad, dlon_rad, dh_m)``."""
    enu = np.asarray(enu_m, dtype=float)
    r_m, r_n = radii(lat_rad)
    return (enu[..., 1] / (r_m + h_m),
            enu[..., 0] / ((r_n + h_m) * np.cos(lat_rad)),
            enu[..., 2])
