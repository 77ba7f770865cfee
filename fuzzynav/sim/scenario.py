"""Scenarios: a typed description of a simulated run, read from TOML or a built-in name.

File layout (every key, unit and default in ``docs/simulation.md``)::

    name = "paper000"                 # optional, default: the file name
    description = "..."
    [start]                           # lat_deg, lon_deg, h_m, speed_mps, heading_deg, utc
    [imu]                             # ImuSpec fields (datasheet units) and rate_hz
    [[segments]]                      # Segment fields, one table per segment, in order
    [sensors.<name>]                  # kind = "<registered kind>" and that kind's fields
    [sea]                             # optional: ship roll/pitch/yaw/heave and current

Every problem is one :class:`fuzzynav.errors.InputFileError` naming the file, the TOML key
path (``segments[3].turn_deg``, ``sensors.gps.rate_hz``) and what was wrong.
"""
from __future__ import annotations

import datetime as _dt
import difflib
import functools
import json
import re
import types
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from fuzzynav.errors import DataMissingError, InputFileError, UnknownNameError
from fuzzynav.registry import paper_files
from fuzzynav.sim.imu import ImuSpec
from fuzzynav.sim.scenario_checks import as_base, check_scenario
from fuzzynav.sim.sea import SeaState
from fuzzynav.sim.segments import SEGMENT_KINDS, Profile, Segment
from fuzzynav.sim.sensors import SENSOR_KINDS, spec_class
from fuzzynav.sim.tomltable import Table, parse_toml, read_toml, with_path

__all__ = ["DEFAULT_UTC", "Scenario", "scenario_from_dict", "builtin_files", "list_scenarios",
           "merge_tables", "read_file", "merge_base", "load_scenario"]

_SENSOR_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_-]{0,39}$")
#: a scenario name is printed in one-line messages and tables and becomes part of file
#: names: printable, without path separators, and short
_SCENARIO_NAME = re.compile(r"^[^\x00-\x1f\x7f/\\]{1,100}$")
#: bounds of a turn: a hundred full circles per segment, a gyro's usual 1000 deg/s range
_MAX_TURN_DEG, _MAX_RATE_DPS = 36000.0, 1000.0
#: default start time: the 2024 March equinox, 04:00 UTC (about noon in China)
DEFAULT_UTC = _dt.datetime(2024, 3, 20, 4, 0, tzinfo=_dt.timezone.utc)


@dataclass(frozen=True)
class Scenario:
    """A simulated run: start state, motion, IMU and aiding sensors.

    Attributes
    ----------
    name, description : str
    start_lat_deg, start_lon_deg : float
        Start position [deg] (north, east positive).
    start_h_m : float
        Start ellipsoidal height [m].
    initial_speed_mps : float
        Speed at ``t = 0`` [m/s].
    initial_heading_deg : float
        Heading at ``t = 0`` [deg], clockwise from north.
    start_utc : datetime.datetime
        UTC time of ``t = 0`` (for the sun, used by polarization sensors).
    segments : tuple of Segment
    imu : ImuSpec
    sensors : Mapping[str, Spec]
        Sensor name -> registered sensor ``Spec`` (read-only mapping).
    sea : SeaState or None
        Hull oscillations and water current of a ship (:mod:`fuzzynav.sim.sea`).
    """

    name: str
    description: str
    start_lat_deg: float
    start_lon_deg: float
    start_h_m: float
    initial_speed_mps: float
    initial_heading_deg: float
    start_utc: _dt.datetime
    segments: tuple
    imu: ImuSpec
    sensors: types.MappingProxyType
    sea: SeaState | None = None

    def __post_init__(self):
        object.__setattr__(self, "segments", tuple(self.segments))
        object.__setattr__(self, "sensors", types.MappingProxyType(dict(self.sensors)))
        # a Scenario built in Python gets the checks of a scenario file (errors name the key
        # of the file format: start.lat_deg, sensors.gps.rate_hz, ...)
        start = {"start_lat_deg": self.start_lat_deg, "start_lon_deg": self.start_lon_deg,
                 "start_h_m": self.start_h_m, "initial_speed_mps": self.initial_speed_mps,
                 "initial_heading_deg": self.initial_heading_deg}
        # sizes and cross-field meaning before anything is allocated (Profile builds pieces)
        check_scenario(self.segments, self.imu, self.sensors, start)
        # the motion too (a static segment while moving, a turn at rest, ...), so that a bad
        # scenario fails when it is made and not in the middle of a study
        Profile(self.segments, self.initial_speed_mps, np.deg2rad(self.initial_heading_deg))

    @property
    def start_lla_rad(self) -> np.ndarray:
        """Start latitude [rad], longitude [rad], height [m]."""
        return np.array([np.deg2rad(self.start_lat_deg), np.deg2rad(self.start_lon_deg),
                         self.start_h_m])

    @property
    def duration_s(self) -> float:
        """Total length of the segments [s]."""
        return float(sum(s.duration_s for s in self.segments))

    # -- canonical form -----------------------------------------------------------------
    def to_dict(self) -> dict:
        """The scenario as a TOML-ready table (round-trips through :func:`scenario_from_dict`)."""
        return {
            "name": self.name, "description": self.description,
            "start": {"lat_deg": self.start_lat_deg, "lon_deg": self.start_lon_deg,
                      "h_m": self.start_h_m, "speed_mps": self.initial_speed_mps,
                      "heading_deg": self.initial_heading_deg,
                      "utc": self.start_utc.isoformat()},
            "imu": self.imu.to_dict(),
            "segments": [{k: v for k, v in asdict(s).items() if v is not None}
                         for s in self.segments],
            "sensors": {name: _sensor_dict(spec) for name, spec in self.sensors.items()},
        } | ({"sea": self.sea.to_dict()} if self.sea is not None else {})

    def canonical(self) -> str:
        """Canonical JSON of everything that shapes the data (not name or description)."""
        d = self.to_dict()
        del d["name"], d["description"]
        return json.dumps(d, sort_keys=True, separators=(",", ":"), allow_nan=False)


def _sensor_dict(spec) -> dict:
    if hasattr(spec, "to_dict"):
        return spec.to_dict()
    return {"kind": spec.kind, **asdict(spec)}


# -- parsing ------------------------------------------------------------------------------
def _segment(t: Table) -> Segment:
    kind = t.string("kind", choices=SEGMENT_KINDS)
    kw = dict(kind=kind,
              duration_s=t.number("duration_s", lo=0.0, lo_open=True),
              speed_change_mps=t.number("speed_change_mps", 0.0),
              turn_deg=t.number("turn_deg", 0.0, lo=-_MAX_TURN_DEG, hi=_MAX_TURN_DEG),
              turn_rate_dps=t.number("turn_rate_dps", None, lo=-_MAX_RATE_DPS,
                                     hi=_MAX_RATE_DPS),
              radius_m=t.number("radius_m", None, lo=0.0, lo_open=True),
              pitch_deg=t.number("pitch_deg", 0.0, lo=-80.0, hi=80.0, lo_open=True,
                                 hi_open=True),
              bank=t.boolean("bank", False),
              n_turns=t.integer("n_turns", 2, lo=1))
    t.finish()
    try:
        return Segment(**kw)
    except InputFileError as exc:
        raise InputFileError(None, exc.where.replace("segment", t.where, 1), exc.what) from None


def _sensor(t: Table, name: str, others=()):
    if not _SENSOR_NAME.match(name):
        raise t.error("", "a sensor name must start with a letter and use only letters, "
                          "digits, '_' and '-' (at most 40)")
    if not t.has("kind"):  # a new sensor needs its kind; a misspelt name makes a new one
        close = difflib.get_close_matches(name, [o for o in others if o != name], n=1)
        raise t.error("kind", "missing required key: a sensor table needs kind = one of "
                              f"{', '.join(sorted(SENSOR_KINDS.load()))}" + (
                                  f" (or is it the sensor {close[0]!r}, misspelt?)"
                                  if close else ""))
    kind = t.string("kind")
    try:
        cls = spec_class(kind)
    except UnknownNameError as exc:
        raise t.error("kind", str(exc)) from None
    return cls.from_dict({k: v for k, v in t.data.items() if k != "kind"}, t.where)


def scenario_from_dict(d: dict, default_name: str = "scenario") -> Scenario:
    """Build a :class:`Scenario` from a parsed TOML document (errors carry no file)."""
    top = Table(d)
    name = top.string("name", default_name)
    if top.has("name") and not _SCENARIO_NAME.match(name):
        raise top.error("name", "must be 1 to 100 printable characters without '/' or '\\' "
                                f"(it names cache and figure files), got {name[:40]!r}"
                                + ("..." if len(name) > 40 else ""))
    description = top.string("description", "")
    st = top.table("start")
    start = dict(start_lat_deg=st.number("lat_deg", lo=-90.0, hi=90.0),
                 start_lon_deg=st.number("lon_deg", lo=-180.0, hi=360.0),
                 start_h_m=st.number("h_m", 0.0, lo=-1000.0, hi=1e5),
                 initial_speed_mps=st.number("speed_mps", 0.0, lo=0.0),
                 initial_heading_deg=st.number("heading_deg", 0.0),
                 start_utc=st.datetime_utc("utc", DEFAULT_UTC))
    st.finish()
    imu_table = top.table("imu")
    imu = ImuSpec.from_dict(imu_table.data, imu_table.where)
    segments = tuple(_segment(t) for t in top.tables("segments"))
    if not segments:
        raise top.error("segments", "needs at least one [[segments]] table")
    sens = top.table("sensors", required=False)
    sensors = {}
    if sens is not None:
        for key in list(sens.data):
            sensors[key] = _sensor(sens.table(key), key, list(sens.data))
    sea_table = top.table("sea", required=False)
    sea = SeaState.from_dict(sea_table.data, sea_table.where) if sea_table else None
    top.finish()
    # Scenario() runs the cross-field checks (scenario_checks) and the motion check
    return Scenario(name=name, description=description, segments=segments, imu=imu,
                    sensors=sensors, sea=sea, **start)


# -- built-ins and loading -------------------------------------------------------------------
@functools.lru_cache(maxsize=None)
def _is_alignment(label: str, data: bytes) -> bool:
    with with_path(label):
        return parse_toml(data).get("kind") == "alignment"


def builtin_files(alignment: bool = False) -> dict:
    """``{name: file}`` of the built-in scenarios: every paper folder's ``scenarios/*.toml``
    (:func:`fuzzynav.registry.paper_files`), navigation ones or (``alignment``) those of
    ``kind = "alignment"``."""
    files = paper_files("scenarios", ".toml")
    return {n: f for n, f in files.items()
            if _is_alignment(f"<built-in {n}.toml>", f.read_bytes()) == alignment}


def list_scenarios() -> list[str]:
    """Names of the built-in scenarios."""
    return sorted(builtin_files())


def _looks_like_path(name_or_path) -> bool:
    s = str(name_or_path)
    return isinstance(name_or_path, Path) or s.endswith(".toml") or "/" in s or "\\" in s


def merge_tables(base: dict, over: dict) -> dict:
    """``over`` on top of ``base``: tables merge key by key, everything else replaces."""
    out = dict(base)
    for k, v in over.items():
        out[k] = merge_tables(base[k], v) if isinstance(v, dict) and isinstance(base.get(k), dict) \
            else v
    return out


def _base_path(base: str, here: Path) -> Path:
    """A ``base =`` file: inside the scenario's own directory (or below), never elsewhere."""
    path = (here / base).resolve()
    if not path.is_relative_to(here.resolve()):
        raise InputFileError(None, "base", f"{base!r} points outside the scenario's own "
                                           "directory; use a built-in name or a file next "
                                           "to this one")
    return path


def read_file(name_or_path, what: str = "scenario", builtins: dict | None = None):
    """Parsed document, stem, label and directory (None for a built-in) of a scenario file
    or built-in name; ``builtins`` (default: the navigation scenarios) and ``what`` (named
    in errors) serve the alignment scenarios too (:mod:`fuzzynav.align.scenario`)."""
    builtins = builtin_files() if builtins is None else builtins
    if _looks_like_path(name_or_path):
        path = Path(name_or_path)
        return read_toml(path, f"{what} file"), path.stem, str(path), path.parent
    name = str(name_or_path)
    if name not in builtins:
        exc = UnknownNameError(what, name, sorted(builtins))
        if builtins.keys() != (aligns := builtin_files(alignment=True)).keys() and name in aligns:
            exc.args = (f"{exc.args[0]} ({name!r} is an alignment scenario: a file that "
                        'derives from it needs kind = "alignment")',)
        raise exc
    label = f"<built-in {name}.toml>"
    with with_path(label):
        doc = parse_toml(builtins[name].read_bytes())
    return doc, name, label, None


def merge_base(doc: dict, stem: str, here, depth: int, parent_doc) -> dict:
    """``doc`` (from :func:`read_file`, inside its ``with_path``) on top of the document of
    its ``base =``, if any: a built-in name, or a file next to this one (``here``) or below.

    ``parent_doc(base, depth + 1)`` gives the base's document (its own base merged); the
    file keeps its own name (its stem unless it says one), never the base's.
    """
    if "base" not in doc:
        return doc
    base = doc.pop("base")
    if not isinstance(base, str):
        raise InputFileError(None, "base", "must be a scenario name or a file path")
    if depth >= 8:
        raise InputFileError(None, "base", "scenarios derive from each other in a loop")
    if _looks_like_path(base):
        if here is None:
            raise InputFileError(None, "base", "a built-in derives from built-ins only")
        base = _base_path(base, here)
    doc.setdefault("name", stem)
    try:
        parent = parent_doc(base, depth + 1)
    except (UnknownNameError, DataMissingError) as exc:  # name this file and key
        raise InputFileError(None, "base", str(exc)) from None
    return merge_tables(parent, doc)


def _base_doc(base, depth: int) -> dict:
    """The document of a ``base =`` scenario, checked as a scenario but for its run's size
    (:func:`~fuzzynav.sim.scenario_checks.as_base`: the derived scenario's is checked)."""
    with as_base():
        return _load(base, depth).to_dict()


def _load(name_or_path, depth=0) -> Scenario:
    doc, stem, label, here = read_file(name_or_path)
    with with_path(label):
        doc = merge_base(doc, stem, here, depth, _base_doc)
        return scenario_from_dict(doc, default_name=stem)


def load_scenario(name_or_path) -> Scenario:
    """A built-in scenario by name, or a scenario TOML file by path.

    A file may start from another scenario with ``base = "paper000"`` (a built-in name or
    a path relative to the file): its tables are merged key by key onto the base's, arrays
    (such as ``segments``) replace the base's.

    Raises
    ------
    UnknownNameError
        Not a built-in name (and not a path).
    DataMissingError
        The file does not exist.
    InputFileError
        The file is not valid TOML or not a valid scenario (file, key path, problem): a
        directory, over 1 MiB, nested too deep, a ``base`` outside the file's directory,
        a run too large for memory (:mod:`fuzzynav.sim.budget`) or values that would mean
        nothing (:mod:`fuzzynav.sim.scenario_checks`).
    """
    return _load(name_or_path)
