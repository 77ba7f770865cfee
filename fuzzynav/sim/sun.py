"""Position of the sun seen from a point on the earth at a UTC epoch.

Algorithm
---------
The solar coordinates are those of Meeus, *Astronomical Algorithms* (2nd ed., 1998), ch. 25
("low accuracy": geometric mean longitude, mean anomaly and a three-term equation of the
centre), completed with the terms that matter at the 0.001° level:

* the largest planetary and lunar perturbations of the longitude and distance (Meeus,
  *Astronomical Formulae for Calculators*, 1979);
* nutation in longitude and obliquity from the four largest terms (Meeus ch. 22), used for
  the apparent longitude, the true obliquity and the apparent sidereal time;
* annual aberration (-20.4898"/R);
* Greenwich mean sidereal time from the IAU 1982 expression (Meeus eq. 12.4) plus the
  equation of the equinoxes;
* topocentric parallax of the sun (8.794"/R), so that the elevation is the one seen from the
  earth's surface (as pvlib/NREL SPA report it), not from its centre.

Atmospheric refraction is *not* in :attr:`SunPosition.elevation_rad` (the true, geometric
elevation, which the skylight model needs); :func:`refraction_rad` gives the Bennett /
Saemundsson refraction for an apparent elevation.

Accuracy and validity
---------------------
Measured against NREL SPA (``pvlib.solarposition.get_solarposition``) over 1950-2050 at
latitudes -75°..+75°: elevation and azimuth·cos(elevation) within 0.004° (see
``tests/sim/test_sun.py`` and ``docs/polarization.md``).  The series are fits around
J2000; the error grows slowly with distance from 2000 and the method is meant for 1900-2100.
UT1 is taken equal to UTC (|UT1-UTC| < 0.9 s, i.e. < 0.004° of hour angle).  The terrestrial
time offset ``delta_t_s = TT - UT`` only moves the sun along the ecliptic (0.0007° per
minute of error), so a constant default is enough.

Frames: azimuth clockwise from north, elevation above the local horizontal of the geodetic
(ellipsoid-normal) vertical; the unit sun vector is in the local ENU frame of
:mod:`fuzzynav.nav.earth`.
"""
from __future__ import annotations

import datetime as _dt
import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from fuzzynav.nav.attitude import wrap_pi

__all__ = ["J2000_JD", "UNIX_EPOCH_JD", "DELTA_T_S", "julian_day", "sun_position_nb",
           "sun_vector_nb", "SunPosition", "sun_position", "sun_vector_n", "refraction_rad"]

#: Julian day of the J2000.0 epoch (2000-01-01 12:00 TT)
J2000_JD = 2451545.0
#: Julian day of the Unix epoch 1970-01-01 00:00 UTC
UNIX_EPOCH_JD = 2440587.5
#: default TT - UT [s] (IERS: 69.2 s in 2024; the sun is insensitive to it, see module doc)
DELTA_T_S = 69.2
#: solar parallax at 1 au [rad]
_SOLAR_PARALLAX = math.radians(8.794 / 3600.0)
_ARCSEC = math.radians(1.0 / 3600.0)


def julian_day(utc):
    """Julian day (UT) of a UTC epoch.

    Parameters
    ----------
    utc : datetime.datetime, numpy.datetime64, str or array of datetime64
        A timezone-aware datetime is converted to UTC; a naive one is taken as UTC.  A string
        is read as ISO 8601 (``"2024-06-21T04:00:00Z"``).

    Returns
    -------
    float or ndarray
        Julian day number [days] on the UT time scale.
    """
    if isinstance(utc, str):
        utc = _dt.datetime.fromisoformat(utc.strip().replace("Z", "+00:00"))
    if isinstance(utc, _dt.datetime):
        if utc.tzinfo is not None:
            utc = utc.astimezone(_dt.timezone.utc).replace(tzinfo=None)
        # integer microseconds: float seconds since 1970 would lose precision to rounding
        us = (utc - _dt.datetime(1970, 1, 1)) // _dt.timedelta(microseconds=1)
        return UNIX_EPOCH_JD + us / 86_400e6
    ns = np.asarray(utc, dtype="datetime64[ns]").astype(np.int64)
    return UNIX_EPOCH_JD + ns / 86_400e9


@nb.njit(cache=True)
def sun_position_nb(jd_ut, lat_rad, lon_rad, delta_t_s):
    """Sun position at one epoch and place (numba scalar kernel).

    Parameters
    ----------
    jd_ut : float
        Julian day on the UT scale.
    lat_rad, lon_rad : float
        Geodetic latitude and longitude (east positive) [rad].
    delta_t_s : float
        TT - UT [s].

    Returns
    -------
    decl_rad, eot_s, hour_angle_rad, elev_rad, azim_rad, dist_au : float
        Apparent declination, equation of time (apparent minus mean solar time) [s], local
        hour angle (positive west, in [-pi, pi)), topocentric true elevation (no refraction),
        azimuth clockwise from north in [0, 2 pi), earth-sun distance [au].
    """
    d2r = math.pi / 180.0
    t = (jd_ut + delta_t_s / 86400.0 - J2000_JD) / 36525.0  # Julian centuries of TT
    l0 = (280.46646 + t * (36000.76983 + t * 0.0003032)) * d2r
    m = (357.52911 + t * (35999.05029 - t * 0.0001537)) * d2r
    ecc = 0.016708634 - t * (0.000042037 + t * 0.0000001267)
    c = ((1.914602 - t * (0.004817 + t * 0.000014)) * math.sin(m)
         + (0.019993 - t * 0.000101) * math.sin(2.0 * m)
         + 0.000289 * math.sin(3.0 * m)) * d2r
    nu = m + c
    dl, dr = _perturbations(t + 1.0)
    dist_au = 1.000001018 * (1.0 - ecc * ecc) / (1.0 + ecc * math.cos(nu)) + dr
    # nutation: the four largest terms (longitude of the moon's node, sun and moon longitude)
    om = (125.04452 - t * 1934.136261) * d2r
    ls = (280.4665 + t * 36000.7698) * d2r
    lm = (218.3165 + t * 481267.8813) * d2r
    dpsi = (-17.20 * math.sin(om) - 1.32 * math.sin(2 * ls) - 0.23 * math.sin(2 * lm)
            + 0.21 * math.sin(2 * om)) * _ARCSEC
    deps = (9.20 * math.cos(om) + 0.57 * math.cos(2 * ls) + 0.10 * math.cos(2 * lm)
            - 0.09 * math.cos(2 * om)) * _ARCSEC
    eps0 = (84381.448 - t * (46.8150 + t * (0.00059 - t * 0.001813))) * _ARCSEC
    eps = eps0 + deps
    lam = l0 + c + dl + dpsi - 20.4898 * _ARCSEC / dist_au
    ra = math.atan2(math.cos(eps) * math.sin(lam), math.cos(lam))
    decl = math.asin(math.sin(eps) * math.sin(lam))
    # apparent sidereal time at Greenwich (UT scale), Meeus eq. 12.4 + equation of equinoxes
    du = jd_ut - J2000_JD
    tu = du / 36525.0
    gmst = (280.46061837 + 360.98564736629 * du + tu * tu * (0.000387933 - tu / 38710000.0))
    gast = gmst * d2r + dpsi * math.cos(eps)
    hour = wrap_pi(gast + lon_rad - ra)
    # mean solar time is UT + longitude; the equation of time is what the sun is ahead of it
    ut_angle = 2.0 * math.pi * ((jd_ut - 0.5) % 1.0)
    eot_s = wrap_pi(hour + math.pi - ut_angle - lon_rad) * 86400.0 / (2.0 * math.pi)
    sl, cl = math.sin(lat_rad), math.cos(lat_rad)
    sd, cd = math.sin(decl), math.cos(decl)
    east = -cd * math.sin(hour)
    north = sd * cl - cd * sl * math.cos(hour)
    up = sd * sl + cd * cl * math.cos(hour)
    elev = math.atan2(up, math.hypot(east, north))
    elev -= math.asin(_SOLAR_PARALLAX / dist_au * math.cos(elev))
    azim = math.atan2(east, north) % (2.0 * math.pi)
    return decl, eot_s, hour, elev, azim, dist_au


@nb.njit(cache=True)
def _perturbations(t1900):
    """Largest perturbations of the solar longitude [rad] and distance [au].

    Venus, Jupiter and the moon, plus a long-period term (Meeus, *Astronomical Formulae for
    Calculators*, 1979, ch. 18); ``t1900`` counts Julian centuries of TT from JD 2415020.0.
    Against SPA they cut the longitude error from 28" to 12" (max, 1900-2100).
    """
    d2r = math.pi / 180.0
    a = (153.23 + 22518.7541 * t1900) * d2r
    b = (216.57 + 45037.5082 * t1900) * d2r
    c = (312.69 + 32964.3577 * t1900) * d2r
    d = (350.74 + t1900 * (445267.1142 - 0.00144 * t1900)) * d2r
    e = (231.19 + 20.20 * t1900) * d2r
    h = (353.40 + 65928.7155 * t1900) * d2r
    dl = (0.00134 * math.cos(a) + 0.00154 * math.cos(b) + 0.00200 * math.cos(c)
          + 0.00179 * math.sin(d) + 0.00178 * math.sin(e)) * d2r
    dr = (5.43e-6 * math.sin(a) + 1.575e-5 * math.sin(b) + 1.627e-5 * math.sin(c)
          + 3.076e-5 * math.cos(d) + 9.27e-6 * math.sin(h))
    return dl, dr


@nb.njit(cache=True)
def sun_vector_nb(jd_ut, lat_rad, lon_rad, delta_t_s):
    """Unit ENU vector towards the sun (topocentric, no refraction), numba scalar kernel.

    Returns
    -------
    ndarray, shape (3,)
        ``[cos(el) sin(az), cos(el) cos(az), sin(el)]``.
    """
    out = np.empty(3)
    _, _, _, elev, azim, _ = sun_position_nb(jd_ut, lat_rad, lon_rad, delta_t_s)
    out[0] = math.cos(elev) * math.sin(azim)
    out[1] = math.cos(elev) * math.cos(azim)
    out[2] = math.sin(elev)
    return out


@nb.njit(cache=True)
def _sun_position_loop(jd_ut, lat_rad, lon_rad, delta_t_s, out):
    for i in range(jd_ut.shape[0]):
        res = sun_position_nb(jd_ut[i], lat_rad[i], lon_rad[i], delta_t_s[i])
        for j in range(6):
            out[j, i] = res[j]


@dataclass(frozen=True)
class SunPosition:
    """Sun position at one or many (epoch, place) pairs; arrays share the broadcast shape.

    Attributes
    ----------
    declination_rad : ndarray
        Apparent declination [rad].
    equation_of_time_s : ndarray
        Apparent minus mean solar time [s] (positive: the sun dial is ahead of the clock).
    hour_angle_rad : ndarray
        Local hour angle, positive west (afternoon), in [-pi, pi) [rad].
    elevation_rad : ndarray
        Topocentric true elevation above the horizon, no refraction [rad].
    azimuth_rad : ndarray
        Azimuth clockwise from north, in [0, 2 pi) [rad].
    distance_au : ndarray
        Earth-sun distance [au].
    """

    declination_rad: np.ndarray
    equation_of_time_s: np.ndarray
    hour_angle_rad: np.ndarray
    elevation_rad: np.ndarray
    azimuth_rad: np.ndarray
    distance_au: np.ndarray

    @property
    def sun_n(self) -> np.ndarray:
        """Unit vector towards the sun in ENU, shape (..., 3)."""
        return _angles_to_enu(self.elevation_rad, self.azimuth_rad)

    def apparent_elevation_rad(self, pressure_hpa=1010.0, temperature_c=10.0):
        """Elevation including atmospheric refraction [rad] (see :func:`refraction_rad`)."""
        return self.elevation_rad + refraction_rad(self.elevation_rad, pressure_hpa,
                                                   temperature_c)


def sun_position(jd_ut, lat_rad, lon_rad, delta_t_s=DELTA_T_S) -> SunPosition:
    """Sun position for epochs and places (broadcast).

    Parameters
    ----------
    jd_ut : float or array_like
        Julian day on the UT scale (see :func:`julian_day`).
    lat_rad, lon_rad : float or array_like
        Geodetic latitude and longitude (east positive) [rad].
    delta_t_s : float or array_like
        TT - UT [s].

    Returns
    -------
    SunPosition
    """
    arrs = np.broadcast_arrays(*(np.asarray(a, dtype=float)
                                 for a in (jd_ut, lat_rad, lon_rad, delta_t_s)))
    shape = arrs[0].shape
    flat = [np.ascontiguousarray(a).ravel() for a in arrs]
    out = np.empty((6, flat[0].size))
    _sun_position_loop(*flat, out)
    return SunPosition(*(row.reshape(shape) for row in out))


def sun_vector_n(jd_ut, lat_rad, lon_rad, delta_t_s=DELTA_T_S) -> np.ndarray:
    """Unit ENU vector towards the sun, shape (..., 3) (see :func:`sun_position`)."""
    return sun_position(jd_ut, lat_rad, lon_rad, delta_t_s).sun_n


def refraction_rad(elevation_rad, pressure_hpa=1010.0, temperature_c=10.0):
    """Atmospheric refraction to add to a true elevation [rad] (Saemundsson 1986).

    ``R = 1.02' / tan(h + 10.3 / (h + 5.11))`` with ``h`` the true elevation in degrees,
    scaled by ``(P / 1010 hPa) (283 K / T)``; zero once the sun's upper limb is below the
    horizon (true elevation < -0.8333°).  About 0.5° at the horizon, 0.016° at 45°.
    """
    h_deg = np.degrees(np.asarray(elevation_rad, dtype=float))
    h_safe = np.maximum(h_deg, -0.8333)  # keeps the formula away from its pole
    r_arcmin = (1.02 / np.tan(np.radians(h_safe + 10.3 / (h_safe + 5.11)))
                * (pressure_hpa / 1010.0) * (283.0 / (273.0 + temperature_c)))
    return np.where(h_deg >= -0.8333, np.radians(r_arcmin / 60.0), 0.0)


def _angles_to_enu(elev_rad, azim_rad):
    ce = np.cos(elev_rad)
    return np.stack([ce * np.sin(azim_rad), ce * np.cos(azim_rad), np.sin(elev_rad)], -1)
