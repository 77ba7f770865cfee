"""Which files make an RTKLIB recording: ``imu_<id>.csv``, its ``.tag``, ``gnss_<id>*.pos``.

A directory may hold several recordings (sessions, one ``<id>`` each); :func:`find_files`
picks one and refuses with a line listing the sessions when the choice is ambiguous.
"""
from __future__ import annotations

import glob
from pathlib import Path

from fuzzynav.errors import DataMissingError, InputFileError

__all__ = ["sessions", "find_files"]


def _one(directory: Path, pattern: str, what: str, several: str, keep=None) -> Path:
    found = sorted(p for p in directory.glob(pattern) if keep is None or keep(p.name))
    if not found:
        raise DataMissingError(f"{directory}: no {what} ({pattern}) in the recording directory")
    if len(found) > 1:
        raise InputFileError(directory, pattern, "several files match ("
                             + ", ".join(p.name for p in found) + f"); {several}")
    return found[0]


def sessions(directory) -> list[str]:
    """The ``<id>`` of every ``imu_<id>.csv`` in ``directory``, sorted."""
    return sorted(p.stem[len("imu_"):] for p in Path(directory).glob("imu_*.csv"))


def _imu_file(directory: Path, session) -> Path:
    """``imu_<session>.csv``, or the only IMU file; errors list the sessions there are."""
    ids = ", ".join(sessions(directory)) or "none"
    if session is None:
        return _one(directory, "imu_*.csv", "IMU file",
                    f"choose a session ({ids}) with session=\"<id>\" (command line: "
                    "--data KIND:DIR:SESSION)")
    sid = str(session)
    # the id becomes part of a file name and a glob pattern: a plain name only
    if not sid or sid != Path(sid).name or glob.escape(sid) != sid:
        raise InputFileError(directory, "session", f"{sid!r} is not a session id (a plain "
                                                   f"name; sessions here: {ids})")
    imu = directory / f"imu_{sid}.csv"
    if not imu.exists():
        raise DataMissingError(f"{directory}: no session {sid!r} (no {imu.name}); sessions "
                               f"here: {ids}")
    return imu


def _of_session(name: str, session_id: str) -> bool:
    """``gnss_<id>.pos`` or ``gnss_<id><sep>...pos`` with a separator that is not a letter
    or digit: session 1 must not take session 12's ``gnss_12_sf.pos``."""
    rest = name[len("gnss_" + session_id):-len(".pos")]
    return rest == "" or not rest[0].isalnum()


def find_files(directory, session=None) -> dict:
    """The IMU CSV, its tag and the GNSS solution in ``directory`` (clear errors if not)."""
    directory = Path(directory)
    if not directory.is_dir():
        raise DataMissingError(f"{directory}: recording directory not found")
    imu = _imu_file(directory, session)
    tag = imu.with_name(imu.name + ".tag")
    if not tag.is_file():
        raise DataMissingError(f"{tag}: time-tag file of {imu.name} not found")
    session_id = imu.stem[len("imu_"):]
    pos = _one(directory, f"{glob.escape('gnss_' + session_id)}*.pos", "GNSS solution",
               "keep one solution per session in the directory",
               keep=lambda name: _of_session(name, session_id))
    for what, path in (("IMU file", imu), ("time-tag file", tag), ("GNSS solution", pos)):
        if not path.is_file():
            raise InputFileError(path, "", f"not a regular file (a directory?); the {what} "
                                           "must be one")
    return {"imu": imu, "tag": tag, "pos": pos}
