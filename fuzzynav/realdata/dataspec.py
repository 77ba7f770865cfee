"""Recording specs of a study: ``KIND:DIR[:SESSION][@WINDOW][?OPTIONS]``, the data directory,
windows.

A study (``[train] recordings = [...]``, ``docs/studies.md``) names recordings by the
``--data`` syntax (:func:`fuzzynav.realdata.sources.parse_data_spec`) with two differences:

* a relative ``DIR`` is looked up in the **data directories**
  (:mod:`fuzzynav.realdata.datasets`: ``$FUZZYNAV_DATA`` when set, else the user cache
  ``fuzzynav data fetch`` writes into), so a study file commits no absolute path
  (``akit:akit:1-4`` is ``<data directory>/akit``, trajectories 1-4); a dataset name is
  the same recording (``akit:1-4``, ``rtklib-drive@0-50%``; ``akit:N`` is the dataset
  whenever ``N`` is a trajectory selection) and the run is named the long way
  (``akit:akit:3``, ``rtklib:rtklib-drive@0-50%``);
* ``@A-B`` (seconds after the recording's first IMU sample) or ``@A-B%`` (percent of its
  span) keeps a **time window**: the filter runs from the recording's start (its
  initialisation needs the start) up to ``B`` and is scored on the epochs in ``[A, B]`` only,
  so a run on ``@0-50%`` uses no data of ``@50-100%``;
* a ``?key=value&...`` suffix sets the loader's start options, as on the command line
  (``docs/data.md``; e.g. ``rtklib:walk?min_speed=0.5``).

A spec with several sessions (``akit:akit:1-4``) stands for one run per session
(:func:`expand`); the run's name is its single-session spec (``akit:akit:3``).
Parsing needs no file; :func:`resolve` checks the directory.
"""
from __future__ import annotations

import os
import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from fuzzynav.errors import DataMissingError, FuzzynavError
from fuzzynav.realdata.datasets import (
    DATA_DIR_ENV,
    DATASETS,
    data_dirs,
    find_directory,
    missing_dataset_message,
)
from fuzzynav.realdata.sources import (
    SOURCES,
    data_options,
    split_dataset_spec,
    split_options,
)

__all__ = ["Window", "RecordingSpec", "is_recording_name", "parse_window",
           "parse_recording_spec", "resolve", "expand", "identity", "overlaps",
           "until", "within"]

_WINDOW_RE = re.compile(r"^\s*(\d+(?:\.\d*)?)\s*-\s*(\d+(?:\.\d*)?)\s*(%?)\s*$")


@dataclass(frozen=True)
class Window:
    """A time window ``[lo, hi]``: seconds after the first IMU sample, or percent of the span."""

    lo: float
    hi: float
    percent: bool = False

    def bounds(self, t_first: float, t_last: float) -> tuple:
        """The window in the recording's clock [s], given its first and last IMU times."""
        scale = (t_last - t_first) / 100.0 if self.percent else 1.0
        return t_first + self.lo * scale, min(t_first + self.hi * scale, t_last)

    def __str__(self) -> str:
        return f"{self.lo:g}-{self.hi:g}{'%' if self.percent else ''}"


@dataclass(frozen=True)
class RecordingSpec:
    """A parsed recording spec (module docstring)."""

    kind: str
    directory: str          # as written: relative ones are read from the data directory
    session: str | None
    window: Window | None
    #: the ``?key=value&...`` start options as written (``None``: the loader's defaults)
    options: str | None = None

    def __str__(self) -> str:
        s = f"{self.kind}:{self.directory}"
        s += f":{self.session}" if self.session is not None else ""
        s += f"@{self.window}" if self.window is not None else ""
        return s + (f"?{self.options}" if self.options is not None else "")


def is_recording_name(name: str) -> bool:
    """Whether a run name is a recording spec (``KIND:...`` with a registered kind)."""
    kind, sep, _ = str(name).partition(":")
    return bool(sep) and kind in SOURCES


def parse_window(text: str) -> Window:
    """``"0-50%"`` or ``"0-270"`` -> :class:`Window` (lo < hi; percentages up to 100)."""
    m = _WINDOW_RE.match(text)
    if not m:
        raise FuzzynavError(f"time window {text!r}: expected A-B (seconds after the first "
                            "IMU sample) or A-B% (percent of the recording), e.g. 0-50%")
    lo, hi, pct = float(m.group(1)), float(m.group(2)), bool(m.group(3))
    if not lo < hi or (pct and hi > 100.0):
        raise FuzzynavError(f"time window {text!r}: needs A < B" + (" <= 100" if pct else ""))
    return Window(lo, hi, pct)


def parse_recording_spec(text) -> RecordingSpec:
    """Split ``KIND:DIR[:SESSION][@WINDOW]`` or ``NAME[:SESSION][@WINDOW]`` (a dataset; the
    spec is then ``KIND:NAME[:SESSION]``, as if written the long way; no file is read).

    Raises
    ------
    FuzzynavError
        When it is not a string of that form, the kind is not registered, or the window is
        malformed.
    """
    if not isinstance(text, str):
        raise FuzzynavError(f"expected a recording spec KIND:DIR[:SESSION][@A-B[%]], "
                            f"got {text!r}")
    bare, options = split_options(text)
    if options is not None:
        data_options(text)      # a bad option is refused here, naming it
    body, at, win = bare.partition("@")
    short = split_dataset_spec(body, directory_exists=lambda _: False)
    if short is not None:
        kind, name, session = short
        if session == "":
            raise FuzzynavError(f"{text!r}: empty session after {name}:")
        return RecordingSpec(kind, name, session, parse_window(win) if at else None, options)
    kind, sep, rest = body.partition(":")
    if not sep or not kind or not rest:
        raise FuzzynavError(f"{text!r}: expected KIND:DIR[:SESSION][@A-B[%]] or a dataset "
                            "NAME[:SESSION][@A-B[%]] (e.g. akit:akit:1-4, akit:1-4 or "
                            "rtklib-drive@0-50%)")
    if kind not in SOURCES:
        raise FuzzynavError(f"{text!r}: unknown recording kind {kind!r} "
                            f"(known: {', '.join(sorted(SOURCES))})")
    directory, colon, session = rest.rpartition(":")
    if not colon:
        directory, session = rest, None
    if not directory or session == "":
        raise FuzzynavError(f"{text!r}: empty directory or session")
    return RecordingSpec(kind, directory, session, parse_window(win) if at else None, options)


def resolve(spec: RecordingSpec) -> Path:
    """The recording directory of a spec (relative ones: the first of the data
    directories holding it, :func:`fuzzynav.realdata.datasets.find_directory`).

    Raises
    ------
    DataMissingError
        When it does not exist (the message says where it was looked for and how to get
        it: ``fuzzynav data fetch NAME`` for a dataset, ``$FUZZYNAV_DATA`` otherwise).
    """
    path = Path(spec.directory).expanduser()
    if path.is_absolute():
        if not path.is_dir():
            raise DataMissingError(f"{spec}: recording directory {path} not found")
        return path
    found = find_directory(path)
    if found is not None:
        return found
    if spec.directory in DATASETS:
        raise DataMissingError(f"{spec}: {missing_dataset_message(spec.directory)}")
    looked = ", ".join(str(b) for b in data_dirs())
    raise DataMissingError(f"{spec}: recording directory {spec.directory} not found in "
                           f"{looked} (relative directories are read from {DATA_DIR_ENV} "
                           f"when set, else from the user cache)")


def expand(spec: RecordingSpec) -> list[RecordingSpec]:
    """One spec per session: a source with a ``split`` (A-KIT: ``1-4`` -> 1, 2, 3, 4; no
    session -> the source's default, A-KIT's 1-8)."""
    split = SOURCES[spec.kind].split
    if split is None:
        return [spec]
    return [replace(spec, session=str(s)) for s in split(spec.session)]


def identity(spec: RecordingSpec) -> tuple:
    """``(kind, directory, sessions)`` of what a spec reads, however it is spelled: the
    directory's real path (``akit``, ``./akit/`` and ``/data/akit`` are one recording; as
    written, normalised, when it cannot be found) and the set of sessions it covers."""
    try:
        where = os.path.realpath(resolve(spec))
    except FuzzynavError:
        where = os.path.normpath(os.path.expanduser(spec.directory))
    split = SOURCES[spec.kind].split
    sessions = frozenset(str(s) for s in split(spec.session)) if split is not None \
        else frozenset([spec.session])
    return spec.kind, where, sessions


def overlaps(a: RecordingSpec, b: RecordingSpec) -> bool:
    """Whether two specs share data that is scored (the same recording by
    :func:`identity`, a session in common, overlapping windows; windows of different units
    are taken to overlap)."""
    (kind_a, dir_a, ses_a), (kind_b, dir_b, ses_b) = identity(a), identity(b)
    if (kind_a, dir_a) != (kind_b, dir_b) or not ses_a & ses_b:
        return False
    if a.window is None or b.window is None or a.window.percent != b.window.percent:
        return True
    return a.window.lo < b.window.hi and b.window.lo < a.window.hi


# -- cutting a loaded recording at the end of its window ----------------------------------------
def _cut_array(value, n: int, keep: np.ndarray):
    """Rows of a per-sample (``n``) or per-increment (``n - 1``) array inside ``keep``."""
    if isinstance(value, np.ndarray) and value.ndim >= 1:
        if value.shape[0] == n:
            return value[keep]
        if value.shape[0] == n - 1 and n > 1:
            return value[keep[1:]]
    return value


def until(stream, t_end: float):
    """A copy of a time-stamped dataclass (``ImuData``, ``SensorData``, a reference) with
    the samples after ``t_end`` removed, including per-sample arrays in its ``meta``."""
    return within(stream, -np.inf, t_end)


def within(stream, lo: float, hi: float):
    """The samples of a time-stamped dataclass in ``[lo, hi]``.

    Increment arrays (one row fewer than ``time_s``, as ``ImuData``'s) stay consistent only
    when ``lo`` is before the first sample: cut an IMU with :func:`until`.
    """
    t = np.asarray(stream.time_s, float)
    keep = (t >= lo - 1e-9) & (t <= hi + 1e-9)
    n = t.size
    fields = {k: _cut_array(getattr(stream, k), n, keep)
              for k in stream.__dataclass_fields__ if k != "meta"}
    if "meta" in stream.__dataclass_fields__:
        fields["meta"] = {k: _cut_array(v, n, keep) for k, v in stream.meta.items()}
    return replace(stream, **fields)
