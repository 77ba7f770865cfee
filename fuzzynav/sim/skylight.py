"""Rayleigh single-scattering model of the skylight polarization pattern.

Physics
-------
Sunlight scattered once by air molecules (Rayleigh) towards an observer looking along the
unit vector ``v`` (observer -> sky point) is partially linearly polarized.  With ``s`` the
unit vector observer -> sun, the scattering angle ``gamma`` is the angle between ``v`` and
``s`` and

* the degree of polarization is ``DoP = DoP_max sin^2(gamma) / (1 + cos^2(gamma))`` —
  zero towards the sun and the anti-sun, ``DoP_max`` at 90° from the sun (ideal Rayleigh:
  1; a clear sky reaches 0.6-0.8 because of multiple scattering, aerosols and ground
  reflection, hence the parameter);
* the E-vector (oscillation direction of the polarized part) is perpendicular to the
  scattering plane spanned by ``v`` and ``s``: ``e = (v x s) / |v x s|``, which is also
  perpendicular to ``v``.  Its sign is meaningless (an axis): angles of polarization live
  modulo pi.

The pattern is symmetric about the solar meridian (the vertical plane through the sun).
Single scattering has no neutral points off the sun/anti-sun; the Arago, Babinet and
Brewster neutral points that paper 003 tracks come from multiple scattering and are not
modelled here.

Angle of polarization in a sensor
---------------------------------
A sensor frame ``c`` has its boresight along ``z_c`` and its reference axis along ``x_c``.
For a view direction ``v`` the local reference is the projection of ``x_c`` onto the plane
perpendicular to ``v``, ``x_v = (x_c - (x_c.v) v) / |...|``, and ``y_v = v x x_v``; the
angle of polarization is ``AoP = atan2(e.y_v, e.x_v)`` folded into [-pi/2, pi/2).  On the
boresight this is the ordinary angle from ``x_c`` towards ``y_c`` (counter-clockwise seen
from behind the sensor, looking out).  It is the ideal-optics convention; a real fisheye
camera calibration maps its pixel angles to it.

All functions take stacks of vectors (..., 3) and broadcast.
"""
from __future__ import annotations

import numpy as np

__all__ = ["DOP_MAX_CLEAR", "fold_half_pi", "scattering_angle", "degree_of_polarization",
           "e_vector", "local_reference", "angle_of_polarization", "stokes", "view_direction"]

#: maximum degree of polarization of a clear sky (ideal Rayleigh: 1)
DOP_MAX_CLEAR = 0.75


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def fold_half_pi(angle_rad):
    """Fold axial angles (defined modulo pi) into [-pi/2, pi/2)."""
    return (np.asarray(angle_rad) + 0.5 * np.pi) % np.pi - 0.5 * np.pi


def scattering_angle(view, sun):
    """Scattering angle ``gamma`` [rad] between view and sun directions (any frame).

    ``atan2(|v x s|, v.s)`` keeps full precision near 0 and pi.
    """
    v, s = _unit(view), _unit(sun)
    return np.arctan2(np.linalg.norm(np.cross(v, s), axis=-1), np.sum(v * s, -1))


def degree_of_polarization(view, sun, dop_max=DOP_MAX_CLEAR):
    """Rayleigh degree of polarization ``DoP_max sin^2 g / (1 + cos^2 g)`` [-].

    Parameters
    ----------
    view, sun : array_like, shape (..., 3)
        View direction (observer -> sky) and sun direction, same frame; need not be unit.
    dop_max : float
        Degree of polarization at 90° from the sun.
    """
    v, s = _unit(view), _unit(sun)
    c = np.sum(v * s, -1)
    return dop_max * (1.0 - c * c) / (1.0 + c * c)


def e_vector(view, sun):
    """Unit E-vector ``(v x s)/|v x s|`` (same frame as the inputs), shape (..., 3).

    NaN where the view is (anti-)parallel to the sun: the light there is unpolarized.
    """
    e = np.cross(_unit(view), _unit(sun))
    n = np.linalg.norm(e, axis=-1, keepdims=True)
    return np.where(n > 1e-12, e / np.where(n > 0.0, n, 1.0), np.nan)


def local_reference(view_c):
    """Local image axes ``(x_v, y_v)`` of view directions in a sensor frame, each (..., 3).

    ``x_v`` is the sensor x axis projected perpendicular to the view, ``y_v = v x x_v``;
    undefined (NaN) for views along +-x_c, which no sky sensor uses.
    """
    v = _unit(view_c)
    x_c = np.array([1.0, 0.0, 0.0])
    x_v = x_c - v[..., :1] * v
    n = np.linalg.norm(x_v, axis=-1, keepdims=True)
    x_v = np.where(n > 1e-12, x_v / np.where(n > 0.0, n, 1.0), np.nan)
    return x_v, np.cross(v, x_v)


def angle_of_polarization(view_c, sun_c):
    """Angle of polarization [rad] in [-pi/2, pi/2) seen by a sensor (module convention).

    Parameters
    ----------
    view_c : array_like, shape (..., 3)
        View directions in the sensor frame ``c`` (``z_c`` boresight, ``x_c`` reference).
    sun_c : array_like, shape (..., 3)
        Sun direction in the same frame (``C_cn @ sun_n``).

    Returns
    -------
    ndarray
        AoP, NaN where the view points at the sun or anti-sun.
    """
    e = e_vector(view_c, sun_c)
    x_v, y_v = local_reference(view_c)
    return fold_half_pi(np.arctan2(np.sum(e * y_v, -1), np.sum(e * x_v, -1)))


def stokes(view_c, sun_c, dop_max=DOP_MAX_CLEAR, intensity=1.0):
    """Normalised linear Stokes vector ``[I, Q, U]`` in the sensor's local reference.

    ``Q = I d cos 2 phi``, ``U = I d sin 2 phi``; paper 000's ``phi = atan2(U, Q) / 2`` and
    ``d = sqrt(Q^2 + U^2) / I`` recover :func:`angle_of_polarization` and
    :func:`degree_of_polarization`.  ``V = 0`` (no circular polarization in the sky).
    """
    phi = angle_of_polarization(view_c, sun_c)
    d = degree_of_polarization(view_c, sun_c, dop_max)
    i = np.broadcast_to(np.asarray(intensity, dtype=float), d.shape)
    return np.stack([i, i * d * np.cos(2.0 * phi), i * d * np.sin(2.0 * phi)], -1)


def view_direction(zenith_rad, azimuth_rad):
    """Unit view vectors from an angle off the z axis and an azimuth, shape (..., 3).

    ``azimuth`` is measured from the y axis towards the x axis (clockwise seen from above
    in ENU, i.e. from north; from the forward axis in the body or a zenith sensor frame):
    ``[sin z sin a, sin z cos a, cos z]``.
    """
    z, a = np.asarray(zenith_rad, dtype=float), np.asarray(azimuth_rad, dtype=float)
    return np.stack(np.broadcast_arrays(np.sin(z) * np.sin(a), np.sin(z) * np.cos(a),
                                        np.cos(z)), -1)
