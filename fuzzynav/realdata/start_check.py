"""A second, independent heading beside the chosen one: stop when the two disagree.

The GNSS course and track give the heading of the body's *forward (y) axis* assumed to be
the direction of travel; an IMU carried reversed (a phone back to front, a robot driving
backwards) makes them 180 degrees wrong while the gyro's turns still agree with the
course's (a rotation about the vertical is the same for a reversed x/y pair).  The
specific-force method does not assume the direction of travel: it matches the levelled
specific force to the GNSS velocity change, so it resolves that ambiguity.  The start
therefore computes it beside ``course``/``track`` (:func:`resolve_direction`): when the
chosen heading turned by 180 degrees agrees with it, the heading is turned (an IMU carried
backwards) and the start says so; when neither agrees within :data:`CONSISTENCY_SIGMAS`
combined sigmas plus :data:`CONSISTENCY_FLOOR_DEG`, the start is refused.  Course and track
assume the same direction of travel, so between them (:func:`check_headings`) any
disagreement is refused.  An explicit ``heading=DEG`` is not checked (the user's choice).
"""
from __future__ import annotations

import math

import numpy as np

from fuzzynav.errors import InputFileError

__all__ = ["CONSISTENCY_SIGMAS", "CONSISTENCY_FLOOR_DEG", "circular_sigma",
           "check_headings", "resolve_direction"]

#: disagreement, in combined 1-sigma, beyond which two start headings are refused
CONSISTENCY_SIGMAS = 3.0
#: added to the threshold [deg]: unmodelled errors (gyro propagation, mounting)
CONSISTENCY_FLOOR_DEG = 10.0


def circular_sigma(d, n_independent=None) -> float:
    """1-sigma [rad] of the circular mean of the angles ``d``: their circular spread
    ``sqrt(-2 ln R)`` over ``sqrt(n)`` (``n_independent``: the independent samples)."""
    d = np.asarray(d, float)
    r = min(float(np.hypot(np.sin(d).mean(), np.cos(d).mean())), 1.0)
    spread = math.sqrt(max(-2.0 * math.log(max(r, 1e-300)), 0.0))
    n = d.size if n_independent is None else n_independent
    return spread / math.sqrt(max(n, 1))


def _gap_deg(h1, h2) -> float:
    return abs((math.degrees(h1 - h2) + 180.0) % 360.0 - 180.0)


def _limit_deg(s1, s2) -> float:
    return CONSISTENCY_SIGMAS * math.degrees(math.hypot(s1, s2)) + CONSISTENCY_FLOOR_DEG


def _refuse(first, second, diff, limit, hint="") -> None:
    (m1, h1, s1), (m2, h2, s2) = first, second
    raise InputFileError(None, "initialisation", (
        f"start headings disagree by {diff:.0f} deg > {limit:.0f} deg: {m1} "
        f"{math.degrees(h1) % 360:.1f} +- {math.degrees(s1):.1f} deg, {m2} "
        f"{math.degrees(h2) % 360:.1f} +- {math.degrees(s2):.1f} deg{hint}; choose "
        f"with ?heading=DEG (and heading_sigma=DEG) or another heading= method"))


def check_headings(first, second) -> None:
    """Refuse (one line) when two ``(method, heading_rad, sigma_rad)`` estimates that
    assume the same direction of travel disagree.

    Raises
    ------
    InputFileError
        Naming both headings, their sigmas and the options that choose a method.
    """
    diff, limit = _gap_deg(first[1], second[1]), _limit_deg(first[2], second[2])
    if diff > limit:
        _refuse(first, second, diff, limit, " (about 180 deg: is the GNSS velocity's sign "
                "or frame wrong?)" if diff > 150.0 else "")


def resolve_direction(chosen, specific_force) -> tuple:
    """The heading [rad] of ``chosen`` (``course``/``track``), turned by 180 degrees when the
    specific-force estimate says the forward axis points backward, and what was found.

    Parameters
    ----------
    chosen, specific_force : tuple
        ``(method, heading_rad, sigma_rad)``.

    Returns
    -------
    heading_rad : float
    finding : str
        ``agrees with specific-force ...``, ``turned 180 deg ...`` or, when the
        specific-force heading is too uncertain to tell the two directions apart,
        ``direction not checked ...``.

    Raises
    ------
    InputFileError
        When neither direction agrees with the specific-force heading.
    """
    (_, h1, s1), (_, h2, s2) = chosen, specific_force
    limit = _limit_deg(s1, s2)
    ahead, behind = _gap_deg(h1, h2), _gap_deg(h1 + math.pi, h2)
    sf = f"specific-force {math.degrees(h2) % 360:.1f} +- {math.degrees(s2):.1f} deg"
    if ahead <= limit and behind <= limit:
        return h1, f"direction not checked: {sf} is too uncertain"
    if ahead <= limit:
        return h1, f"agrees with {sf}"
    if behind <= limit:
        return ((h1 + math.pi) % (2.0 * math.pi), f"turned 180 deg: {sf} says the IMU's "
                f"forward axis points backward")
    _refuse(chosen, specific_force, ahead, limit)
