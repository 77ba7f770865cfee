"""RTKLIB time-tag files (``<stream>.tag``) and the logging-PC clock they record.

Layout (little-endian), as RTKLIB (demo5) writes it beside a logged stream:

* 60 bytes of text header, ``TIMETAG RTKLIB <version>``, NUL padded;
* ``uint32`` — named "tick frequency" in the dataset README; RTKLIB stores here the logging
  PC's millisecond tick at file open (``tick_f``), which the file's records do not need;
* ``uint32`` integer seconds and ``float64`` fractional seconds: the GPST of file open, as
  a count of seconds since 1970-01-01 in the GPS time scale (no leap seconds applied);
* then records of (``uint32`` tick [ms since file open], ``uint32`` file position [bytes]):
  by that tick the logged file had reached that size.

A trailing partial record (an interrupted write) is ignored.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fuzzynav.errors import InputFileError

__all__ = ["kept_arrivals", "HEADER_TEXT_LEN", "HEADER_LEN", "RECORD", "TimeTag", "read_timetag",
           "arrival_ticks", "logged_line_ends", "fit_clock"]

HEADER_TEXT_LEN = 60
_FIXED = struct.Struct("<IId")
HEADER_LEN = HEADER_TEXT_LEN + _FIXED.size   # 76
RECORD = np.dtype([("tick_ms", "<u4"), ("fpos", "<u4")])


@dataclass(frozen=True)
class TimeTag:
    """A parsed time-tag file.

    Attributes
    ----------
    header : str
        The text header (``TIMETAG RTKLIB demo5``).
    tick_f : int
        The uint32 after the text (the PC tick at file open; unused).
    start_int_s, start_frac_s : int, float
        GPST of file open: seconds since 1970 (GPS scale) and fraction.
    tick_ms : ndarray of int64, shape (R,)
        Record ticks [ms since file open].
    fpos : ndarray of int64, shape (R,)
        File size reached by each record's tick [bytes].
    """

    header: str
    tick_f: int
    start_int_s: int
    start_frac_s: float
    tick_ms: np.ndarray
    fpos: np.ndarray

    @property
    def duration_s(self) -> float:
        """Time from file open to the last record [s]."""
        return float(self.tick_ms[-1]) / 1000.0


def read_timetag(path) -> TimeTag:
    """Parse an RTKLIB ``.tag`` file (one :class:`InputFileError` per problem)."""
    path = Path(path)
    raw = path.read_bytes()
    if len(raw) < HEADER_LEN + RECORD.itemsize:
        raise InputFileError(path, "header", f"{len(raw)} bytes: too short for a time-tag file")
    text = raw[:HEADER_TEXT_LEN].split(b"\0", 1)[0]
    if not text.startswith(b"TIMETAG"):
        raise InputFileError(path, "header", f"does not start with 'TIMETAG' ({text[:20]!r})")
    tick_f, start_int, start_frac = _FIXED.unpack_from(raw, HEADER_TEXT_LEN)
    if not 0.0 <= start_frac < 1.0:
        raise InputFileError(path, "header.fractional_seconds",
                             f"must lie in [0, 1), got {start_frac!r}")
    n = (len(raw) - HEADER_LEN) // RECORD.itemsize
    rec = np.frombuffer(raw, dtype=RECORD, count=n, offset=HEADER_LEN)
    tick = rec["tick_ms"].astype(np.int64)
    fpos = rec["fpos"].astype(np.int64)
    for name, arr in (("tick", tick), ("file position", fpos)):
        bad = np.flatnonzero(np.diff(arr) < 0)
        if bad.size:
            raise InputFileError(path, f"record {bad[0] + 1}",
                                 f"{name} decreases ({arr[bad[0]]} -> {arr[bad[0] + 1]})")
    return TimeTag(header=text.decode("ascii", "replace"), tick_f=int(tick_f),
                   start_int_s=int(start_int), start_frac_s=float(start_frac),
                   tick_ms=tick, fpos=fpos)


def arrival_ticks(tag: TimeTag, line_end_bytes) -> np.ndarray:
    """The tick [ms] by which each line had been written completely (-1: after the last).

    Parameters
    ----------
    line_end_bytes : ndarray of int, shape (L,)
        Offset just past each line (its newline included) in the file as logged.
    """
    i = np.searchsorted(tag.fpos, np.asarray(line_end_bytes), side="left")
    out = np.full(i.shape, -1, dtype=np.int64)
    ok = i < tag.fpos.size
    out[ok] = tag.tick_ms[i[ok]]
    return out


def logged_line_ends(tag: TimeTag, line_lengths, file_size: int):
    """Byte offsets just past each line in the file *as logged*, or ``None`` if unmatched.

    Returns ``(ends, crlf_restored)``: the offsets (ndarray of int) and whether the stored
    copy had lost the CR of CR LF line ends.

    The tag counts bytes as the logger wrote them.  A copy of the file may have had its
    CR LF line ends turned into LF (git does this), which shifts each offset by the number
    of lines before it; the size the last record reports tells which is the case.

    Parameters
    ----------
    line_lengths : ndarray of int, shape (L,)
        Length of every line of the file as stored, without its ``\\n``.
    file_size : int
        Size of the file as stored [bytes].
    """
    lengths = np.asarray(line_lengths, dtype=np.int64)
    slack = int(lengths.max(initial=0)) + 2   # logging may stop inside a line
    last = int(tag.fpos[-1])
    for extra in (1, 2):                       # as stored (LF or CR LF); CR restored
        if abs(file_size + (extra - 1) * lengths.size - last) <= slack:
            return np.cumsum(lengths + extra), extra == 2
    return None


def kept_arrivals(tag: TimeTag, kept, line_lengths, file_size: int):
    """``(arrival, crlf_restored)``: the tick [ms] by which each kept line had been written
    (:func:`arrival_ticks` as floats, -1 after the last record) and whether CR LF line ends were
    restored (:func:`logged_line_ends`), or ``None`` when the tag does not fit the file.

    Parameters
    ----------
    kept : ndarray of int
        0-based index of each data line in the file.
    line_lengths, file_size
        As :func:`logged_line_ends`.
    """
    matched = logged_line_ends(tag, line_lengths, file_size)
    if matched is None:
        return None
    ends, crlf = matched
    arrival = arrival_ticks(tag, ends[kept])
    del ends
    return arrival.astype(float), crlf  # what the fit takes (whole ms: exact)


def fit_clock(imu_ms, arrival_ms):
    """Straight line ``arrival = a + b imu`` through the arrival ticks, outliers removed.

    Arrivals lag their samples by a latency that varies with the logger's buffering; a
    least-squares line, refitted without points more than 5 robust sigmas off, gives the
    clock rate ``b`` (PC ms per IMU ms) and the mean latency in ``a``.

    Returns
    -------
    a_ms, b : float
    resid_sd_ms : float
        Robust standard deviation of the residuals [ms].
    n_used : int
    """
    x = np.asarray(imu_ms, dtype=float)
    y = np.asarray(arrival_ms, dtype=float)
    keep = np.ones(x.size, dtype=bool)
    for _ in range(3):
        # all kept: the arrays themselves (the same numbers, no copies of millions of points)
        b, a = np.polyfit(*((x, y) if keep.all() else (x[keep], y[keep])), 1)
        r = y - (a + b * x)
        rk = r if keep.all() else r[keep]
        sd = 1.4826 * np.median(np.abs(rk - np.median(rk)))
        del rk
        new = np.abs(r) <= 5.0 * max(sd, 0.5)
        if np.array_equal(new, keep):
            break
        keep = new
    return float(a), float(b), float(sd), int(keep.sum())
