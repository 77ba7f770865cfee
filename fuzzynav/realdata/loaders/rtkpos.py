"""RTKLIB solution files (``.pos``) in geodetic form with GPST calendar times.

Header lines start with ``%``; the last of them names the columns, e.g. ::

    %  GPST  latitude(deg) longitude(deg) height(m) Q ns sdn(m) sde(m) sdu(m) sdne(m) ...
       ... age(s) ratio vn(m/s) ve(m/s) vu(m/s) sdvn sdve sdvu sdvne sdveu sdvun

Columns are located by these names, so files with or without the velocity block load.
Quality ``Q``: 1 fixed, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP.
"""
from __future__ import annotations

import calendar
import datetime
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fuzzynav.errors import InputFileError

__all__ = ["PosFile", "read_pos"]

#: columns after the two date-time fields, by header name -> our name
_COLUMNS = {"latitude(deg)": "lat_deg", "longitude(deg)": "lon_deg", "height(m)": "h_m",
            "Q": "q", "ns": "ns", "sdn(m)": "sd_n", "sde(m)": "sd_e", "sdu(m)": "sd_u",
            "age(s)": "age_s", "ratio": "ratio", "vn(m/s)": "vel_n", "ve(m/s)": "vel_e",
            "vu(m/s)": "vel_u", "sdvn": "sd_vn", "sdve": "sd_ve", "sdvu": "sd_vu"}
_REQUIRED = ("lat_deg", "lon_deg", "h_m", "q", "sd_n", "sd_e", "sd_u")
_VELOCITY = ("vel_e", "vel_n", "vel_u", "sd_ve", "sd_vn", "sd_vu")
_HEADER = {ours: theirs for theirs, ours in _COLUMNS.items()}
#: our name -> (lowest, highest) value a solution can hold; NaN is refused in these columns
_RANGES = {"lat_deg": (-90.0, 90.0), "lon_deg": (-180.0, 360.0), "h_m": (-1e5, 1e8),
           "q": (1, 6), "sd_n": (0.0, np.inf), "sd_e": (0.0, np.inf), "sd_u": (0.0, np.inf)}


@dataclass(frozen=True)
class PosFile:
    """Columns of a ``.pos`` file.

    Attributes
    ----------
    time_int_s, time_frac_s : ndarray
        GPST of each epoch as seconds since 1970 (GPS scale), integer and fraction.
    columns : dict
        name -> ndarray (N,): ``lat_deg lon_deg h_m q ns sd_n sd_e sd_u age_s ratio`` and,
        when present, ``vel_e vel_n vel_u sd_ve sd_vn sd_vu`` (NaN where the file has none).
    """

    time_int_s: np.ndarray
    time_frac_s: np.ndarray
    columns: dict


def _header_columns(path, header_line: str) -> dict:
    names = header_line.lstrip("%").split()
    if not names or names[0] != "GPST":
        raise InputFileError(path, "header", "expected the time column 'GPST' in calendar form "
                                             f"(RTKLIB 'yyyy/mm/dd hh:mm:ss'), got {names[:1]}")
    # the date-time is two whitespace-separated fields under one header name
    index = {_COLUMNS[n]: k + 1 for k, n in enumerate(names[1:], start=1) if n in _COLUMNS}
    missing = [c for c in _REQUIRED if c not in index]
    if missing:
        raise InputFileError(path, "header", "not a geodetic RTKLIB solution: no column "
                             + ", ".join(missing) + " (llh output with latitude(deg) ... needed)")
    return index


def _parse_time(path, lineno, date: str, clock: str):
    try:
        y, mo, d = (int(v) for v in date.split("/"))
        hh, mm, ss = clock.split(":")
        sec = float(ss)
        whole = int(np.floor(sec))
        # datetime refuses what timegm alone would roll over (day 38 into the next month;
        # seconds past 59: GPS time has no leap second); an infinite second overflows int
        stamp = datetime.datetime(y, mo, d, int(hh), int(mm), whole)
        return calendar.timegm(stamp.timetuple()), sec - whole
    except (ValueError, TypeError, OverflowError):
        raise InputFileError(path, f"line {lineno}",
                             f"bad GPST date-time {date} {clock!r}") from None


def _check_values(path, columns: dict, linenos) -> None:
    """Refuse NaN, infinite or impossible values in the columns the loader uses."""
    for name, (lo, hi) in _RANGES.items():
        v = columns[name]
        bad = np.flatnonzero(~((v >= lo) & (v <= hi)))
        if name == "q":
            bad = np.union1d(bad, np.flatnonzero(v != np.round(v)))
        if bad.size:
            k = bad[0]
            what = (f"{v[k]:g} is not a finite number" if not np.isfinite(v[k]) else
                    f"{v[k]:g} is outside {lo:g} .. {hi:g}"
                    + (" (RTKLIB quality flags: whole numbers 1-6)" if name == "q" else ""))
            raise InputFileError(path, f"line {linenos[k]}, column {_HEADER[name]}", what)


def read_pos(path) -> PosFile:
    """Parse an RTKLIB ``.pos`` file (llh, GPST)."""
    path = Path(path)
    index, n_fields, rows, t_int, t_frac, linenos = None, 0, [], [], [], []
    with open(path, encoding="ascii", errors="replace") as f:
        for lineno, line in enumerate(f, start=1):
            if line.startswith("%"):
                tokens = line.lstrip("%").split()
                if len(tokens) >= 4 and (tokens[0] in ("GPST", "UTC", "JST")
                                         or "latitude(deg)" in tokens):
                    index = _header_columns(path, line)
                    n_fields = len(tokens) + 1       # the date-time is two fields
                continue
            if not line.strip():
                continue
            if index is None:
                raise InputFileError(path, "header", "no column header line ('%  GPST ...') "
                                                     "before the first solution")
            fields = line.split()
            cut = "" if line.endswith("\n") else " (the file ends inside it: truncated?)"
            if len(fields) < n_fields:
                raise InputFileError(path, f"line {lineno}", f"{len(fields)} fields, the header "
                                     f"names {n_fields}{cut}")
            try:
                rows.append([float(fields[k]) for k in index.values()])
            except ValueError:
                raise InputFileError(path, f"line {lineno}", f"expected numbers in the "
                                     f"columns {', '.join(_HEADER[n] for n in index)}{cut}") \
                    from None
            ti, tf = _parse_time(path, lineno, fields[0], fields[1])
            t_int.append(ti)
            t_frac.append(tf)
            linenos.append(lineno)
    if not rows:
        raise InputFileError(path, "lines", "no solution epochs in the file (only header "
                                            "or blank lines)")
    data = np.array(rows, dtype=float)
    columns = {name: data[:, j] for j, name in enumerate(index)}
    _check_values(path, columns, linenos)
    for name in _VELOCITY + ("ns", "age_s", "ratio"):
        columns.setdefault(name, np.full(data.shape[0], np.nan))
    t_int, t_frac = np.array(t_int, dtype=np.int64), np.array(t_frac)
    bad = np.flatnonzero(np.diff((t_int - t_int[0]) + t_frac) <= 0.0)
    if bad.size:
        raise InputFileError(path, f"line {linenos[bad[0] + 1]}",
                             "epoch not after the previous one (times must increase)")
    return PosFile(time_int_s=t_int, time_frac_s=t_frac, columns=columns)
