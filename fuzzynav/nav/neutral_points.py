"""Neutral points of skylight polarization and their fisheye image (paper 003).

Single (Rayleigh) scattering has zero polarization only at the sun and the antisun.  Multiple
scattering splits each of these index +1 singularities into two index +1/2 ones on the solar
meridian (Berry, Dennis & Lee 2004, "Polarization singularities in the clear sky", New J.
Phys. 6:162, §2-3): the **Babinet** point above the sun and the **Brewster** point below it,
the **Arago** point above the antisun and a fourth one below it.  In their model the
polarization field on the stereographic sky is a quartic with these four zeros: Babinet and
Brewster on the sun's vertical, an angle ``sep`` apart and centred on the sun, Arago and the
fourth point their antipodes.  Our points are exactly those zeros with ``sep = 2 delta``
(``tests/nav/test_neutral_points_published.py`` checks it against the transcribed field):
each point at ``delta`` from the sun (or antisun) along the solar vertical, independent of
the sun's elevation in that model.  Observed distances are about 20 deg (AMS Glossary,
"Arago point", after Neuberger 1951; 15-25 deg over sources and turbidity), the default
and the range of ``delta`` here.  A point's elevation is therefore

    Babinet: h + delta,   Brewster: h - delta   (azimuth of the sun),
    Arago:  -h + delta,   fourth:  -h - delta   (azimuth of the antisun),

with ``h`` the sun's elevation (an elevation past 90 deg continues over the zenith).

Camera: a fisheye aligned with the body (boresight ``z_b`` up, ``x_b`` right, ``y_b``
forward), equidistant projection ``r = theta`` (unit focal length): a direction ``v_b`` at
zenith angle ``theta`` images at ``theta (v_x, v_y) / |(v_x, v_y)|``.  Paper 003 measures the
angle of the line from the antisun-side point A to the sun-side point B,
``beta = atan2(y_B - y_A, x_B - x_A)``; the 180-deg ambiguity of a line is resolved by the
brighter sun side (we label the points by which side of the zenith they are on, which is
what the intensity tells).  For a level camera and the pair (Arago, Babinet),
``heading = sun_azimuth + beta - 90 deg`` (:func:`heading_from_beta`).
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["neutral_points_n", "image_point", "pair_beta", "images", "heading_from_beta"]

#: point pairs used, by code: the line from Arago (or Brewster) to Babinet
PAIR_ARAGO_BABINET, PAIR_BREWSTER_BABINET = 0, 1


@nb.njit(cache=True, error_model="numpy")
def neutral_points_n(sun_n, delta, out):
    """Unit ENU directions of (Babinet, Brewster, Arago, fourth) into ``out`` (4, 3)."""
    h = math.asin(max(-1.0, min(1.0, sun_n[2])))
    horiz = math.hypot(sun_n[0], sun_n[1])
    ae, an = (sun_n[0] / horiz, sun_n[1] / horiz) if horiz > 1e-12 else (0.0, 1.0)
    elev = (h + delta, h - delta, -h + delta, -h - delta)
    for k in range(4):
        sgn = 1.0 if k < 2 else -1.0  # sun side, then antisun side
        ce = math.cos(elev[k])
        out[k, 0] = sgn * ce * ae
        out[k, 1] = sgn * ce * an
        out[k, 2] = math.sin(elev[k])


@nb.njit(cache=True, error_model="numpy")
def image_point(C_bn, v_n):
    """Fisheye image ``(x, y, theta)`` of direction ``v_n`` for attitude ``C_bn``."""
    vx = C_bn[0, 0] * v_n[0] + C_bn[1, 0] * v_n[1] + C_bn[2, 0] * v_n[2]
    vy = C_bn[0, 1] * v_n[0] + C_bn[1, 1] * v_n[1] + C_bn[2, 1] * v_n[2]
    vz = C_bn[0, 2] * v_n[0] + C_bn[1, 2] * v_n[1] + C_bn[2, 2] * v_n[2]
    rho = math.hypot(vx, vy)
    theta = math.atan2(rho, vz)
    if rho < 1e-15:
        return 0.0, 0.0, theta
    return theta * vx / rho, theta * vy / rho, theta


@nb.njit(cache=True, error_model="numpy")
def pair_beta(C_bn, sun_n, delta, pair, pts):
    """Angle ``beta`` [rad] of the image line A -> B of point pair ``pair`` (``pts``: (4, 3))."""
    neutral_points_n(sun_n, delta, pts)
    a = 2 if pair == PAIR_ARAGO_BABINET else 1
    xa, ya, _ = image_point(C_bn, pts[a])
    xb, yb, _ = image_point(C_bn, pts[0])
    return math.atan2(yb - ya, xb - xa)


def images(C_bn, sun_n, delta) -> np.ndarray:
    """``(4, 3)`` rows ``(x, y, theta)`` of the four points (for tests, plots, the simulator)."""
    pts = np.zeros((4, 3))
    neutral_points_n(np.asarray(sun_n, float), float(delta), pts)
    C = np.ascontiguousarray(C_bn, dtype=float)
    return np.array([image_point(C, p) for p in pts])


def heading_from_beta(beta, sun_azimuth):
    """Heading [rad, 0..2pi) of a level camera from the Arago->Babinet line angle ``beta``."""
    return np.mod(np.asarray(sun_azimuth) + np.asarray(beta) - 0.5 * np.pi, 2.0 * np.pi)
