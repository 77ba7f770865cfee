"""Alignment scenarios (``kind = "alignment"`` TOML): a base at a fixed place, an IMU,
sway, the true noise of the zero-velocity reference and the filter's assumptions.

Built-ins live in ``fuzzynav/papers/paper002/scenarios`` (``paper002`` and its variants); a file may
start from a built-in or a file next to it with ``base = "paper002"`` (tables merge key by
key; the reader is the navigation scenarios', :func:`fuzzynav.sim.scenario.read_file`).
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields
from pathlib import Path

from fuzzynav import units
from fuzzynav.align.model import AlignNoise
from fuzzynav.align.simulate import Sway
from fuzzynav.errors import InputFileError
from fuzzynav.sim.imu import ImuSpec
from fuzzynav.sim.scenario import builtin_files, merge_base, read_file
from fuzzynav.sim.tomltable import Table, read_toml, with_path

__all__ = ["AlignScenario", "list_alignment_scenarios", "is_alignment_scenario",
           "load_alignment_scenario"]

#: [filter] keys in datasheet units -> (AlignNoise field, SI factor)
_FILTER_KEYS = {
    "vel_sigma_mps": ("vel_sigma_mps", 1.0),
    "att_sigma_deg": ("att_sigma_rad", units.DEG),
    "accel_bias_sigma_ug": ("accel_bias_sigma_mps2", units.UG),
    "gyro_bias_sigma_dph": ("gyro_bias_sigma_rps", units.DPH),
    "accel_noise_ug": ("accel_noise_mps2_psqrts", units.UG),
    "gyro_noise_dph": ("gyro_noise_rps_psqrts", units.DPH),
    "r0_sigma_mps": ("meas_sigma_mps", 1.0),
}


@dataclass(frozen=True)
class AlignScenario:
    """One alignment scenario (see the built-in TOML files for the meaning of each key)."""

    name: str
    description: str
    lat_deg: float
    h_m: float
    att_deg: tuple
    duration_s: float
    misalign_deg: tuple
    meas_sigma_mps: float
    noise_windows: tuple
    threshold_arcmin: float
    imu: ImuSpec
    sway: Sway
    noise: AlignNoise = field(default_factory=AlignNoise)


def list_alignment_scenarios() -> list[str]:
    """Names of the built-in alignment scenarios (paper folders' ``kind = "alignment"``)."""
    return sorted(builtin_files(alignment=True))


def is_alignment_scenario(name_or_path) -> bool:
    """Whether a name or file is an alignment scenario (built-in, or ``kind = "alignment"``)."""
    s = str(name_or_path)
    if s in list_alignment_scenarios():
        return True
    if s.endswith(".toml") and Path(s).is_file():
        try:
            return read_toml(Path(s), "scenario file").get("kind") == "alignment"
        except InputFileError:
            return False
    return False


def _document(name_or_path, depth=0):
    """Document, stem and label of an alignment scenario, its ``base =`` merged in (the
    navigation scenarios' reader, :func:`fuzzynav.sim.scenario.read_file`)."""
    doc, stem, label, here = read_file(name_or_path, "alignment scenario",
                                       builtin_files(alignment=True))
    with with_path(label):
        doc = merge_base(doc, stem, here, depth, lambda base, d: _document(base, d)[0])
    return doc, stem, label


def _sway(t: Table | None) -> Sway:
    if t is None:
        return Sway()
    d = Sway()
    kw = {f.name: (t.vector(f.name, 3, getattr(d, f.name), lo=0.0 if "amp" in f.name else None)
                   if isinstance(getattr(d, f.name), tuple)
                   else t.number(f.name, getattr(d, f.name), lo=0.0))
          for f in fields(Sway)}
    t.finish()
    return Sway(**kw)


def _noise(t: Table | None) -> AlignNoise:
    if t is None:
        return AlignNoise()
    kw = {}
    for key, (attr, factor) in _FILTER_KEYS.items():
        value = t.number(key, None, lo=0.0, lo_open=True)
        if value is not None:
            kw[attr] = value * factor
    t.finish()
    return AlignNoise(**kw)


def _parse(doc: dict, stem: str) -> AlignScenario:
    t = Table(doc)
    t.string("kind", choices=("alignment",))
    scn = AlignScenario(
        name=t.string("name", stem), description=t.string("description", ""),
        lat_deg=t.number("lat_deg", lo=-89.0, hi=89.0), h_m=t.number("h_m", 0.0),
        att_deg=t.vector("att_deg", 3, (0.0, 0.0, 0.0)),
        duration_s=t.number("duration_s", lo=10.0, hi=86400.0),
        misalign_deg=t.vector("misalign_deg", 3, (1.0, 1.0, 1.0), lo=-30.0, hi=30.0),
        meas_sigma_mps=t.number("meas_sigma_mps", 0.05, lo=0.0),
        noise_windows=t.windows("noise_windows", 3),
        threshold_arcmin=t.number("threshold_arcmin", 10.0, lo=0.0, lo_open=True),
        imu=ImuSpec.from_dict(doc.get("imu", {}), "imu"), sway=_sway(t.table("sway", False)),
        noise=_noise(t.table("filter", False)))
    t.table("imu", False)
    t.finish()
    return scn


def load_alignment_scenario(name_or_path) -> AlignScenario:
    """A built-in alignment scenario by name, or a TOML file by path.

    Raises
    ------
    UnknownNameError, DataMissingError, InputFileError
        Unknown name, missing file, or a bad key (naming the file and the key).
    """
    doc, stem, label = _document(name_or_path)
    with with_path(label):
        return _parse(doc, stem)
