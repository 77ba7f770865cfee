"""Main geomagnetic field at a place and date: IGRF (via ``ppigrf``) or a centred dipole.

``igrf`` evaluates the International Geomagnetic Reference Field with the maintained,
pure-Python ``ppigrf`` package (IGRF-14 coefficients, geodetic coordinates, MIT licence);
it is what a magnetometer simulation should use, since the declination and inclination at
the scenario's place then match the published calculators (NOAA/BGS) to a few nT.
``dipole`` keeps only the degree-1 terms of IGRF-2020 (a tilted centred dipole); it needs
nothing beyond numpy and is wrong by several degrees of declination in most places, which
is fine for tests of the filter but not for a place-specific simulation.

Both return the field in ENU components, tesla.
"""
from __future__ import annotations

import datetime as _dt
import math

import numpy as np

from fuzzynav import units
from fuzzynav.errors import DataMissingError, UnknownNameError

__all__ = ["FIELD_MODELS", "DIPOLE_2020_NT", "IGRF_RADIUS_M", "field_enu_t", "dipole_enu_t",
           "declination_rad", "inclination_rad"]

FIELD_MODELS = ("igrf", "dipole")
#: IGRF-13 degree-1 Gauss coefficients for epoch 2020.0 [nT] (Alken et al. 2021, Table 2)
DIPOLE_2020_NT = {"g10": -29404.8, "g11": -1450.9, "h11": 4652.5}
#: IGRF reference radius [m]
IGRF_RADIUS_M = 6371.2e3


def _naive_utc(when) -> _dt.datetime:
    """``when`` (datetime, ISO string or None) as a naive UTC datetime (what ppigrf takes)."""
    if when is None:
        raise DataMissingError("the magnetic field model needs a date (scenario start.utc)")
    if isinstance(when, str):
        when = _dt.datetime.fromisoformat(when.replace("Z", "+00:00"))
    if not isinstance(when, _dt.datetime):  # numpy datetime64
        when = _dt.datetime.fromisoformat(str(np.datetime_as_string(when, unit="s")))
    if when.tzinfo is not None:
        when = when.astimezone(_dt.timezone.utc).replace(tzinfo=None)
    return when


def field_enu_t(lat_rad, lon_rad, h_m, when, model: str = "igrf",
                coeff_file=None) -> np.ndarray:
    """Main field at geodetic positions, ENU components [T], shape (n, 3).

    Parameters
    ----------
    lat_rad, lon_rad, h_m : array_like, shape (n,)
        Geodetic latitude, longitude [rad] and ellipsoidal height [m].
    when : datetime or ISO string
        UTC date (the field changes by tens of nT per year).
    model : {"igrf", "dipole"}
    coeff_file : path, optional
        ``igrf`` only: another coefficient file in ppigrf's ``.shc`` format (default:
        ppigrf's IGRF-14; it also ships ``IGRF13.shc``).
    """
    lat, lon, h = (np.atleast_1d(np.asarray(a, float)) for a in (lat_rad, lon_rad, h_m))
    if model == "igrf":
        try:
            import ppigrf
        except ImportError:  # pragma: no cover - ppigrf is a dependency
            raise DataMissingError("field_model = 'igrf' needs the ppigrf package "
                                   "(pip install ppigrf), or use field_model = 'dipole'")
        kw = {} if coeff_file is None else {"coeff_fn": str(coeff_file)}
        be, bn, bu = ppigrf.igrf(np.degrees(lon), np.degrees(lat), h / 1e3, _naive_utc(when),
                                 **kw)
        return np.column_stack([np.ravel(be), np.ravel(bn), np.ravel(bu)]) * units.NT
    if model == "dipole":
        return dipole_enu_t(lat, lon, h)
    raise UnknownNameError("magnetic field model", model, FIELD_MODELS)


def dipole_enu_t(lat_rad, lon_rad, h_m, coeffs=None) -> np.ndarray:
    """Degree-1 (dipole) part of the main field, ENU [T], shape (n, 3).

    The potential ``V = a (a/r)^2 [g10 cos t + (g11 cos l + h11 sin l) sin t]`` with
    ``t`` the colatitude; ``B = -grad V``.  Latitude is taken as geocentric and
    ``r = a + h`` (a dipole is no better than that difference).
    """
    c = DIPOLE_2020_NT if coeffs is None else coeffs
    lat, lon, h = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, float))
                                        for a in (lat_rad, lon_rad, h_m)))
    theta = 0.5 * math.pi - lat
    k = (IGRF_RADIUS_M / (IGRF_RADIUS_M + h)) ** 3
    eq = c["g11"] * np.cos(lon) + c["h11"] * np.sin(lon)
    b_r = 2.0 * k * (c["g10"] * np.cos(theta) + eq * np.sin(theta))
    b_theta = k * (c["g10"] * np.sin(theta) - eq * np.cos(theta))
    b_phi = k * (c["g11"] * np.sin(lon) - c["h11"] * np.cos(lon))
    return np.column_stack([b_phi, -b_theta, b_r]) * units.NT


def declination_rad(field_enu) -> np.ndarray:
    """Declination (clockwise from true north) of ENU field vectors [rad]."""
    f = np.atleast_2d(field_enu)
    return np.arctan2(f[:, 0], f[:, 1])


def inclination_rad(field_enu) -> np.ndarray:
    """Inclination (positive downwards) of ENU field vectors [rad]."""
    f = np.atleast_2d(field_enu)
    return np.arctan2(-f[:, 2], np.hypot(f[:, 0], f[:, 1]))
