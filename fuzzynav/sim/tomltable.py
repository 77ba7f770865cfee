"""Typed reading of one TOML table with one clear error per problem.

Scenario files, sensor specifications and mounting files are plain TOML tables.  A
:class:`Table` hands out their values with the type, unit range and default each field
needs, and :meth:`Table.finish` rejects keys nobody asked for (so a misspelt key is an
error, not a silently ignored setting).  Errors are :class:`fuzzynav.errors.InputFileError`
whose ``where`` is the dotted TOML key path (``sensors.gps.rate_hz``,
``segments[3].turn_deg``); the file is added by whoever knows it (see :func:`with_path`).
"""
from __future__ import annotations

import datetime as _dt
import difflib
import math
import os
import stat
import tomllib
from contextlib import contextmanager
from pathlib import Path

from fuzzynav.errors import DataMissingError, InputFileError

__all__ = ["MAX_TOML_BYTES", "MAX_TOML_DEPTH", "Table", "with_path", "parse_toml", "read_toml"]

_REQUIRED = object()
#: scenario and study files are hand-written: a few kB; anything far larger is a mistake
MAX_TOML_BYTES = 1024 * 1024
#: deepest nesting of tables and arrays a scenario or study file needs is about 4
MAX_TOML_DEPTH = 16


def _type_name(value) -> str:
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, dict):
        return "a table"
    return type(value).__name__


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


class Table:
    """One TOML table being read.

    Parameters
    ----------
    data : dict
        The parsed table.
    where : str
        Its key path in the document ("" for the top level).
    """

    def __init__(self, data, where: str = ""):
        if not isinstance(data, dict):
            raise InputFileError(None, where, f"must be a table, got {_type_name(data)}")
        self.data = data
        self.where = where
        self._used: set[str] = set()

    # -- helpers -----------------------------------------------------------------------
    def key(self, key: str) -> str:
        """Full key path of ``key`` in this table."""
        return f"{self.where}.{key}" if self.where else key

    def error(self, key: str, what: str) -> InputFileError:
        """An error about ``key`` of this table (to be raised by the caller)."""
        return InputFileError(None, self.key(key) if key else self.where, what)

    def has(self, key: str) -> bool:
        """Whether the table sets ``key``."""
        return key in self.data

    def _get(self, key, default):
        self._used.add(key)
        if key in self.data:
            return self.data[key], True
        if default is _REQUIRED:
            close = difflib.get_close_matches(key, [str(k) for k in self.data], n=1,
                                              cutoff=0.75)
            raise self.error(key, "missing required key" + (
                f" (is {close[0]!r} a misspelling of it?)" if close else ""))
        return default, False

    def _check_range(self, key, x, lo, hi, lo_open, hi_open):
        bad_lo = lo is not None and (x <= lo if lo_open else x < lo)
        bad_hi = hi is not None and (x >= hi if hi_open else x > hi)
        if bad_lo or bad_hi:
            left = "(" if lo_open else "["
            right = ")" if hi_open else "]"
            rng = f"{left}{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}{right}"
            raise self.error(key, f"must lie in {rng}, got {x!r}")

    # -- scalars -----------------------------------------------------------------------
    def number(self, key, default=_REQUIRED, *, lo=None, hi=None, lo_open=False,
               hi_open=False):
        """A finite number (int or float) as ``float``; ``None`` default allowed."""
        value, given = self._get(key, default)
        if not given:
            return value
        if not _is_number(value):
            raise self.error(key, f"must be a number, got {_type_name(value)}")
        x = float(value)
        if not math.isfinite(x):
            raise self.error(key, f"must be finite, got {value!r}")
        self._check_range(key, x, lo, hi, lo_open, hi_open)
        return x

    def integer(self, key, default=_REQUIRED, *, lo=None, hi=None):
        """An integer."""
        value, given = self._get(key, default)
        if not given:
            return value
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"must be an integer, got {_type_name(value)}")
        self._check_range(key, value, lo, hi, False, False)
        return int(value)

    def boolean(self, key, default=_REQUIRED) -> bool:
        """A boolean (``true`` / ``false``)."""
        value, given = self._get(key, default)
        if given and not isinstance(value, bool):
            raise self.error(key, f"must be true or false, got {_type_name(value)}")
        return value

    def string(self, key, default=_REQUIRED, *, choices=None):
        """A string, optionally one of ``choices``."""
        value, given = self._get(key, default)
        if not given:
            return value
        if not isinstance(value, str):
            raise self.error(key, f"must be a string, got {_type_name(value)}")
        if choices is not None and value not in choices:
            raise self.error(key, f"must be one of {', '.join(map(repr, choices))}, "
                                  f"got {value!r}")
        return value

    def datetime_utc(self, key, default=_REQUIRED):
        """An offset date-time (TOML ``1979-05-27T07:32:00Z`` or an ISO string) in UTC."""
        value, given = self._get(key, default)
        if not given:
            return value
        if isinstance(value, str):
            try:
                value = _dt.datetime.fromisoformat(value.replace("Z", "+00:00"))
            except ValueError:
                raise self.error(key, f"not an ISO date-time: {value!r}") from None
        if not isinstance(value, _dt.datetime):
            raise self.error(key, f"must be a date-time, got {_type_name(value)}")
        if value.tzinfo is None or value.utcoffset() is None:
            raise self.error(key, "must carry a UTC offset, e.g. 2023-03-05T04:00:00Z")
        return value.astimezone(_dt.timezone.utc)

    # -- vectors -----------------------------------------------------------------------
    def vector(self, key, n, default=_REQUIRED, *, lo=None, hi=None, broadcast=True):
        """``n`` finite numbers as a tuple; a single number is repeated when ``broadcast``."""
        value, given = self._get(key, default)
        if not given:
            return value
        if _is_number(value) and broadcast:
            value = [value] * n
        if not isinstance(value, list) or len(value) != n:
            raise self.error(key, f"must be an array of {n} numbers"
                                  + (" (or one number)" if broadcast else "")
                                  + f", got {_type_name(value)}"
                                  + (f" of length {len(value)}" if isinstance(value, list) else ""))
        out = []
        for i, v in enumerate(value):
            if not _is_number(v) or not math.isfinite(float(v)):
                raise self.error(f"{key}[{i}]", f"must be a finite number, got {v!r}")
            self._check_range(f"{key}[{i}]", float(v), lo, hi, False, False)
            out.append(float(v))
        return tuple(out)

    def matrix(self, key, n, default=_REQUIRED, *, lo=None, hi=None):
        """An ``n`` x ``n`` matrix given as an array of ``n`` rows."""
        value, given = self._get(key, default)
        if not given:
            return value
        if not isinstance(value, list) or len(value) != n:
            raise self.error(key, f"must be an array of {n} rows of {n} numbers")
        rows = Table({f"{key}[{i}]": r for i, r in enumerate(value)}, self.where)
        return tuple(rows.vector(f"{key}[{i}]", n, broadcast=False, lo=lo, hi=hi)
                     for i in range(n))

    def windows(self, key, width, default=()):
        """An array of ``[start_s, end_s, ...]`` rows of ``width`` numbers, start < end."""
        value, given = self._get(key, default)
        if not given:
            return value
        if not isinstance(value, list):
            raise self.error(key, f"must be an array of [start_s, end_s] pairs, "
                                  f"got {_type_name(value)}")
        rows = Table({f"{key}[{i}]": r for i, r in enumerate(value)}, self.where)
        out = []
        for i in range(len(value)):
            row = rows.vector(f"{key}[{i}]", width, broadcast=False)
            if not row[0] < row[1]:
                raise self.error(f"{key}[{i}]", f"start must precede end, got {list(row)}")
            out.append(row)
        return tuple(out)

    # -- sub-tables ----------------------------------------------------------------------
    def table(self, key, required=True):
        """The sub-table ``key`` as a :class:`Table` (``None`` if absent and optional)."""
        value, given = self._get(key, _REQUIRED if required else None)
        if not given:
            return None
        return Table(value, self.key(key))

    def tables(self, key, required=True):
        """An array of tables ``[[key]]`` as a list of :class:`Table`."""
        value, given = self._get(key, _REQUIRED if required else [])
        if not given:
            return []
        if not isinstance(value, list):
            raise self.error(key, f"must be an array of tables, got {_type_name(value)}")
        return [Table(v, f"{self.key(key)}[{i}]") for i, v in enumerate(value)]

    def finish(self):
        """Reject keys that were never read (misspellings, unsupported settings)."""
        unknown = [k for k in self.data if k not in self._used]
        if unknown:
            known = ", ".join(sorted(self._used)) or "none"
            close = difflib.get_close_matches(str(unknown[0]), sorted(self._used), n=1)
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise self.error(unknown[0], f"unknown key; {hint}known keys here: {known}")


@contextmanager
def with_path(path):
    """Attach ``path`` to any :class:`InputFileError` raised inside that has none."""
    try:
        yield
    except InputFileError as exc:
        if exc.path is None and path is not None:
            raise InputFileError(path, exc.where, exc.what) from None
        raise


def _depth_check(doc) -> None:
    """Refuse nesting deeper than :data:`MAX_TOML_DEPTH` (walked without recursion)."""
    stack = [(doc, "", 0)]
    while stack:
        node, where, depth = stack.pop()
        if depth > MAX_TOML_DEPTH:
            raise InputFileError(None, where, f"nesting deeper than {MAX_TOML_DEPTH} levels")
        items = node.items() if isinstance(node, dict) else \
            enumerate(node) if isinstance(node, list) else ()
        for k, v in items:
            if isinstance(v, (dict, list)):
                key = f"{where}[{k}]" if isinstance(node, list) else \
                    (f"{where}.{k}" if where else str(k))
                stack.append((v, key, depth + 1))


def _read_bytes(path: Path, what: str) -> bytes:
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise DataMissingError(f"{path}: {what} not found") from None
    except OSError as exc:  # ENAMETOOLONG, ENOTDIR, ELOOP, EACCES ...
        raise InputFileError(path, "", f"cannot read the {what}: {exc.strerror}") from None
    if stat.S_ISDIR(st.st_mode):
        raise InputFileError(path, "", f"is a directory, not a {what}")
    if not stat.S_ISREG(st.st_mode):  # a FIFO or a device would block or never end
        raise InputFileError(path, "", f"is not a regular file (a {what} is a TOML file)")
    if st.st_size > MAX_TOML_BYTES:
        raise InputFileError(path, "", f"file is {st.st_size} bytes; a {what} may be at "
                                       f"most {MAX_TOML_BYTES} bytes")
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_TOML_BYTES + 1)
    except OSError as exc:
        raise InputFileError(path, "", f"cannot read the {what}: {exc.strerror}") from None
    if len(data) > MAX_TOML_BYTES:  # /proc files report size 0
        raise InputFileError(path, "", f"a {what} may be at most {MAX_TOML_BYTES} bytes")
    return data


def parse_toml(data: bytes) -> dict:
    """Parse TOML bytes; every problem is an :class:`InputFileError` without a file."""
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputFileError(None, "", f"not UTF-8 text ({exc.reason} at byte {exc.start})") \
            from None
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputFileError(None, "", f"invalid TOML: {exc}") from None
    except RecursionError:
        raise InputFileError(None, "", f"invalid TOML: nesting deeper than {MAX_TOML_DEPTH} "
                                       f"levels") from None
    _depth_check(doc)
    if not doc:
        raise InputFileError(None, "", "the file is empty (no keys)")
    return doc


def read_toml(path, what: str) -> dict:
    """Read and parse a TOML file of at most :data:`MAX_TOML_BYTES` bytes.

    Parameters
    ----------
    path : path-like
    what : str
        What the file is, for messages ("scenario file", "study file").

    Raises
    ------
    DataMissingError
        The file does not exist.
    InputFileError
        A directory or a special file, too large, not UTF-8, not TOML, nested deeper
        than :data:`MAX_TOML_DEPTH`, or empty (naming the file).
    """
    path = Path(path)
    with with_path(str(path)):
        return parse_toml(_read_bytes(path, what))
