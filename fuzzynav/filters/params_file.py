"""The one reader of tuned-parameter files (``fuzzynav-baselines``), checking every key and range.

A baseline study writes the best parameters of each classical filter it tunes::

    {"format": "fuzzynav-baselines", "version": 1, "study": "...",
     "filters": {"ekf-tuned": {"q_att": 1.3, "r_pos": 6.1, ...},
                 "sage-husa-tuned": {"b": 0.97, "floor": 0.2, "cap": 40.0}, ...}}

Each filter's parameters are declared once here (:data:`PARAMETERS`) with the values they
may take -- what the filter can run with, wider than what a study searches.  A file that
names an unknown filter or key, leaves a filter's parameters empty (it would silently be
the plain EKF), misses a required key or holds a value outside its range is refused with
one line naming the file and the JSON path.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from fuzzynav.errors import InputFileError, brief
from fuzzynav.filters import measurements

PARAMS_FORMAT = "fuzzynav-baselines"
#: largest tuned-parameter file read (bytes); a study writes a few kilobytes
MAX_FILE_BYTES = 1 << 20
#: range of a constant noise multiplier (Q or R factor): beyond it the filter's covariance
#: is numerically meaningless
MULTIPLIER = (1e-6, 1e6)


@dataclass(frozen=True)
class Param:
    """The values a parameter may take: ``lo``..``hi`` (open ends where said), an integer."""

    lo: float
    hi: float
    lo_open: bool = False
    hi_open: bool = False
    integer: bool = False

    def check(self, value, path, where: str) -> float:
        """``value`` as a float, or :class:`InputFileError` saying what it must be."""
        ok = not isinstance(value, bool) and isinstance(value, (int, float)) \
            and math.isfinite(value)
        if ok and self.integer:
            ok = float(value).is_integer()
        if ok:
            ok = (value > self.lo if self.lo_open else value >= self.lo) and \
                 (value < self.hi if self.hi_open else value <= self.hi)
        if not ok:
            raise InputFileError(path, where, f"must be {self.describe()}, got {brief(value)}")
        return float(value)

    def describe(self) -> str:
        kind = "an integer" if self.integer else "a number"
        return (f"{kind} in {'(' if self.lo_open else '['}{self.lo:g}, {self.hi:g}"
                f"{')' if self.hi_open else ']'}")


_MULT = Param(*MULTIPLIER)
#: Q multipliers of ``ekf-tuned`` / ``als`` (variance factors on the IMU noise densities)
Q_KEYS = ("q_att", "q_vel", "q_gyro_bias", "q_accel_bias")
#: Q multipliers of ``apso`` (paper 004's names)
APSO_Q_KEYS = ("q_scale_att", "q_scale_vel", "q_scale_gyro", "q_scale_accel")

#: tuned filter -> {key: Param}; the per-channel R factors (``r_<channel>``,
#: ``r_scale_<channel>``) are added by :func:`known_keys`
PARAMETERS = {
    "ekf-tuned": {k: _MULT for k in Q_KEYS},
    "als": {k: _MULT for k in Q_KEYS},
    "apso": {**{k: _MULT for k in APSO_Q_KEYS}, "r_scale": _MULT},
    "sage-husa-tuned": {"b": Param(0.0, 1.0, lo_open=True, hi_open=True),
                        "floor": Param(0.0, MULTIPLIER[1], lo_open=True),
                        "cap": Param(0.0, MULTIPLIER[1], lo_open=True)},
    "vb-tuned": {"rho": Param(0.0, 1.0, lo_open=True),
                 "iterations": Param(1, 100, integer=True)},
    "huber-tuned": {"gamma": Param(0.0, 100.0, lo_open=True)},
    "strong-tracking-tuned": {"rho": Param(0.0, 1.0, lo_open=True),
                              "beta": Param(1.0, 1e3),
                              "lam_max": Param(1.0, MULTIPLIER[1], lo_open=True)},
}
#: filters whose every declared key must be given (the others need at least one key)
ALL_REQUIRED = ("sage-husa-tuned", "vb-tuned", "huber-tuned", "strong-tracking-tuned")
#: the per-channel R-factor prefix of each multiplier filter
R_PREFIX = {"ekf-tuned": "r_", "als": "r_", "apso": "r_scale_"}


def _channels() -> tuple:
    models = measurements.MODELS.load()
    return tuple(sorted({c for m in models.values() for c in m.channels}))


def known_keys(name: str) -> dict:
    """Every key filter ``name`` reads, with its :class:`Param`."""
    keys = dict(PARAMETERS[name])
    if name in R_PREFIX:
        keys.update({f"{R_PREFIX[name]}{c}": _MULT for c in _channels()})
    return keys


def check_params(name: str, params, path=None, prefix: str = "") -> dict:
    """Filter ``name``'s parameters checked against :data:`PARAMETERS` (floats)."""
    where = prefix.rstrip(".")
    if not isinstance(params, dict):
        raise InputFileError(path, where, f"must be an object: key -> value, got "
                                          f"{type(params).__name__}")
    if not params:
        raise InputFileError(path, where, "is empty: the filter would silently be the plain "
                                          "EKF; run the baseline study that tunes it")
    keys = known_keys(name)
    out = {}
    for key, value in params.items():
        if key not in keys:
            shown = [k for k in keys if not k.startswith(R_PREFIX.get(name, "\0"))]
            extra = f", {R_PREFIX[name]}<channel>" if name in R_PREFIX else ""
            raise InputFileError(path, f"{prefix}{brief(key)[1:-1]}",
                                 f"unknown parameter of {name} (known: {', '.join(shown)}{extra})")
        out[key] = keys[key].check(value, path, f"{prefix}{key}")
    if name in ALL_REQUIRED:
        missing = [k for k in keys if k not in out]
        if missing:
            raise InputFileError(path, where, f"misses {', '.join(missing)} (a baseline study "
                                              f"writes every parameter of {name})")
    if name == "sage-husa-tuned" and not out["floor"] < out["cap"]:
        raise InputFileError(path, f"{prefix}cap", f"must exceed floor ({out['floor']:g}), "
                                                   f"got {out['cap']:g}")
    return out


def read_params_file(path) -> dict:
    """``{filter: parameters}`` of a tuned-parameter file, every entry checked."""
    path = Path(path)
    try:
        if path.stat().st_size > MAX_FILE_BYTES:
            raise InputFileError(path, "", f"is {path.stat().st_size} bytes; a tuned-parameter "
                                           f"file is at most {MAX_FILE_BYTES}")
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(path, "", f"cannot be read ({exc.__class__.__name__})") from None
    except json.JSONDecodeError as exc:
        raise InputFileError(path, "", f"is not JSON ({exc.msg} at line {exc.lineno})") from None
    if not isinstance(doc, dict) or doc.get("format") != PARAMS_FORMAT:
        raise InputFileError(path, "$.format", f"must be {PARAMS_FORMAT!r} (a file written "
                                               "by a baseline study)")
    filters = doc.get("filters")
    if not isinstance(filters, dict):
        raise InputFileError(path, "$.filters", "must be an object: filter -> parameters")
    out = {}
    for name, params in filters.items():
        if name not in PARAMETERS:
            raise InputFileError(path, f"$.filters.{brief(name)[1:-1]}",
                                 f"not a tuned filter (known: {', '.join(PARAMETERS)})")
        out[name] = check_params(name, params, path, f"$.filters.{name}.")
    return out
