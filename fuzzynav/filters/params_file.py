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
from fuzzynav.filters.multipliers import Q_FIELDS, R_ALL, R_PREFIX, new_name

__all__ = ["PARAMS_FORMAT", "PARAMS_VERSION", "TOP_KEYS", "MAX_FILE_BYTES", "MULTIPLIER",
           "Param", "MULTIPLIER_FILTERS", "PARAMETERS", "ALL_REQUIRED", "known_keys",
           "check_params", "read_params_file"]

PARAMS_FORMAT = "fuzzynav-baselines"
#: the version of the format this reader reads (and :func:`~fuzzynav.tuning.baseline_config.
#: write_params` writes)
PARAMS_VERSION = 1
#: the top-level keys of a tuned-parameter file (what a baseline study writes)
TOP_KEYS = ("format", "version", "study", "baseline", "train", "trials", "train_score",
            "filters", "sampler", "history", "space")
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
#: the constant-multiplier filters (one vocabulary, :mod:`fuzzynav.filters.multipliers`)
MULTIPLIER_FILTERS = ("ekf-tuned", "als", "apso", "ekf-scaled")

#: tuned filter -> {key: Param}; the per-channel R factors ``r_<channel>`` of the
#: multiplier filters are added by :func:`known_keys`
PARAMETERS = {
    **{name: {**{k: _MULT for k in Q_FIELDS}, R_ALL: _MULT} for name in MULTIPLIER_FILTERS},
    "ekf-scaled": {R_ALL: _MULT},  # R only (its options; and r_<channel>)
    "sage-husa-tuned": {"b": Param(0.0, 1.0, lo_open=True, hi_open=True),
                        "floor": Param(0.0, MULTIPLIER[1], lo_open=True),
                        "cap": Param(0.0, MULTIPLIER[1], lo_open=True)},
    "vb-tuned": {"rho": Param(0.0, 1.0, lo_open=True),
                 "iterations": Param(1, 100, integer=True)},
    "huber-tuned": {"gamma": Param(0.0, 100.0, lo_open=True)},
    "strong-tracking-tuned": {"rho": Param(0.0, 1.0, lo_open=True),
                              "beta": Param(1.0, 1e3),
                              "lam_max": Param(1.0, MULTIPLIER[1], lo_open=True)},
    # the alignment KF's constant multipliers (:mod:`fuzzynav.align.tuned`): R0, and the
    # velocity (VRW) and attitude (ARW) rows of Q0 -- its bias rows are zero
    "align-kf-tuned": {R_ALL: _MULT, "q_vel": _MULT, "q_att": _MULT},
}
#: filters whose every declared key must be given (the others need at least one key)
ALL_REQUIRED = ("sage-husa-tuned", "vb-tuned", "huber-tuned", "strong-tracking-tuned")


def _channels() -> tuple:
    models = measurements.MODELS.load()
    return tuple(sorted({c for m in models.values() for c in m.channels}))


def known_keys(name: str) -> dict:
    """Every key filter ``name`` reads, with its :class:`Param`."""
    keys = dict(PARAMETERS[name])
    if name in MULTIPLIER_FILTERS:
        keys.update({f"{R_PREFIX}{c}": _MULT for c in _channels()})
    return keys


def _unknown(name: str, key, keys: dict) -> str:
    """Why ``key`` is not a parameter of ``name``: an old name (with its new one) or unknown."""
    multi = name in MULTIPLIER_FILTERS
    renamed = new_name(key) if multi else None
    if renamed is not None:
        return f"an old name: the multiplier is now {renamed!r} (rename the key)"
    shown = [k for k in keys if not (multi and k.startswith(R_PREFIX) and k != R_ALL)]
    extra = f", {R_PREFIX}<channel>" if multi else ""
    return f"unknown parameter of {name} (known: {', '.join(shown)}{extra})"


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
            raise InputFileError(path, f"{prefix}{brief(key)[1:-1]}", _unknown(name, key, keys))
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
        raise InputFileError(path, "", f"is not JSON ({exc.msg}: line {exc.lineno}, "
                                       f"column {exc.colno})") from None
    if isinstance(doc, dict) and "multipliers" in doc and "format" not in doc:
        raise InputFileError(path, "$.multipliers", "an old APSO result file: rerun the study "
                             "(fuzzynav study run studies/paper004_apso.toml), which writes "
                             f"a {PARAMS_FORMAT!r} file with the multipliers in filters.apso")
    if not isinstance(doc, dict) or doc.get("format") != PARAMS_FORMAT:
        raise InputFileError(path, "$.format", f"must be {PARAMS_FORMAT!r} (a file written "
                                               "by a baseline study)")
    # a file written by hand may leave the version out; one that gives another is refused
    if "version" in doc and (doc["version"] != PARAMS_VERSION
                             or isinstance(doc["version"], bool)):
        raise InputFileError(path, "$.version", f"unsupported version {brief(doc.get('version'))}"
                                                f" (this fuzzynav reads {PARAMS_VERSION})")
    extra = [k for k in doc if k not in TOP_KEYS]
    if extra:
        raise InputFileError(path, f"$.{brief(extra[0])[1:-1]}", "unknown key of a "
                             f"tuned-parameter file (known: {', '.join(TOP_KEYS)})")
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
