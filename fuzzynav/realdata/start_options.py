"""How a recording's initial state is found: every platform-specific number, as an option.

The defaults are those of the car drive (``docs/data.md`` §5): rest until the GNSS speed
passes 0.2 m/s, heading from the GNSS course of epochs faster than 2 m/s in the first 30 s
of motion (60 s for the specific-force method).  A slow platform (a pedestrian, a robot, a
boat at idle) lowers ``min_speed`` or takes the heading from the GNSS track over a
baseline of metres (``heading=track``); a platform whose heading is poorly known starts
with a larger ``heading_sigma`` and lets the filter converge.

On the command line they follow the data spec after a ``?``, joined by ``&``::

    --data "rtklib:DIR?min_speed=0.5&window=60"
    --data "rtklib:DIR:SESSION?heading=track&baseline=15&heading_sigma=20"

=================  ==========================================================  ===========
key                meaning                                                     default
=================  ==========================================================  ===========
``rest_speed``     GNSS speed [m/s] above which the opening rest ends          0.2
``min_rest``       shortest opening rest [s] (levelling, gyro bias)            2
``min_speed``      slowest GNSS epoch [m/s] whose course gives the heading     2
``window``         how long after the rest the heading is looked for [s]       30 (60 for
                                                                               specific-force)
``heading``        ``auto``, ``course``, ``track``, ``specific-force`` or a    auto
                   number [deg] (``auto``: course with a mounting, else
                   specific-force)
``baseline``       ``track``: shortest chord between two fixes [m]             10
``heading_sigma``  initial heading 1-sigma the filter is given [deg]           the IMU
                                                                               model's (3)
``lever_arm``      antenna minus IMU, body right,forward,up [m]                the
                                                                               mounting's
=================  ==========================================================  ===========
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from fuzzynav.errors import InputFileError
from fuzzynav.sim.sensors.gnss import MAX_LEVER_ARM_M

__all__ = ["HEADING_METHODS", "StartOptions", "KEYS", "parse_start_options"]

HEADING_METHODS = ("auto", "course", "track", "specific-force")


@dataclass(frozen=True)
class StartOptions:
    """The options of the module docstring (attribute names carry their units).

    Attributes
    ----------
    rest_speed_mps, min_rest_s, min_speed_mps : float
    window_s : float or None
        ``None``: 30 s for ``course``/``track``, 60 s for ``specific-force``.
    heading : str
        One of :data:`HEADING_METHODS`, or ``given`` with ``heading_deg``.
    heading_deg : float or None
        A known heading [deg] (``heading=DEG`` on the command line).
    track_baseline_m : float
    heading_sigma_deg : float or None
        ``None``: the IMU model's initial heading sigma.
    lever_arm_b_m : tuple of 3 float or None
        ``None``: the mounting's (zero without one).
    """

    rest_speed_mps: float = 0.2
    min_rest_s: float = 2.0
    min_speed_mps: float = 2.0
    window_s: float | None = None
    heading: str = "auto"
    heading_deg: float | None = None
    track_baseline_m: float = 10.0
    heading_sigma_deg: float | None = None
    lever_arm_b_m: tuple | None = None

    def method(self, forward_known: bool) -> str:
        """The heading method to use (``auto`` resolved)."""
        if self.heading == "auto":
            return "course" if forward_known else "specific-force"
        return self.heading

    def window_for(self, method: str) -> float:
        """The heading window [s] of ``method``."""
        if self.window_s is not None:
            return float(self.window_s)
        return 60.0 if method == "specific-force" else 30.0


def _positive(text):
    x = float(text)
    if not (math.isfinite(x) and x > 0.0):
        raise ValueError("must be a number > 0")
    return x


def _non_negative(text):
    x = float(text)
    if not (math.isfinite(x) and x >= 0.0):
        raise ValueError("must be a number >= 0")
    return x


def _triple(text):
    parts = [float(p) for p in text.split(",")]
    if len(parts) != 3 or not all(math.isfinite(p) for p in parts):
        raise ValueError("must be three numbers x,y,z [m] (body right, forward, up)")
    if max(abs(p) for p in parts) > MAX_LEVER_ARM_M:
        raise ValueError(f"each component must be within +-{MAX_LEVER_ARM_M:g} m (larger "
                         "than any vehicle)")
    return tuple(parts)


#: command-line key -> (attribute, parser of the value text)
KEYS = {"rest_speed": ("rest_speed_mps", _positive), "min_rest": ("min_rest_s", _non_negative),
        "min_speed": ("min_speed_mps", _non_negative), "window": ("window_s", _positive),
        "baseline": ("track_baseline_m", _positive),
        "heading_sigma": ("heading_sigma_deg", _positive),
        "lever_arm": ("lever_arm_b_m", _triple)}


def _heading(text) -> dict:
    if text in HEADING_METHODS:
        return {"heading": text}
    try:
        deg = float(text)
    except ValueError:
        deg = float("nan")
    if not math.isfinite(deg):
        raise ValueError(f"must be one of {', '.join(HEADING_METHODS)} or a heading in "
                         f"degrees")
    return {"heading": "given", "heading_deg": deg}


def parse_start_options(query: str, spec: str = "") -> StartOptions:
    """``key=value&key=value`` (the part of a data spec after ``?``) to :class:`StartOptions`.

    Raises
    ------
    InputFileError
        Naming ``--data`` and the option for an unknown key or a bad value.
    """
    values = {}
    for item in filter(None, query.split("&")):
        key, eq, text = item.partition("=")
        where = f"--data {spec} option {key}".replace("  ", " ")
        if key not in KEYS and key != "heading":
            raise InputFileError(None, where, f"unknown option; known: "
                                 f"{', '.join(sorted([*KEYS, 'heading']))}")
        if not eq or not text:
            raise InputFileError(None, where, "expected key=value")
        try:
            if key == "heading":
                values.update(_heading(text))
            else:
                values[KEYS[key][0]] = KEYS[key][1](text)
        except ValueError as exc:
            raise InputFileError(None, where, f"{text!r}: {exc}") from None
    return StartOptions(**values)

