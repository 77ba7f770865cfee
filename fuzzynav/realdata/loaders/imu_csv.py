"""The IMU CSV of an RTKLIB-logged recording, read a block of lines at a time.

``imu_<id>.csv`` has no header; ``acc x, y, z [g], gyro x, y, z [deg/s], tick [ms since IMU
power-up]``; the first and the last line may be cut (logging started or stopped inside
them): the first line is always dropped, the last unless the file ends with a newline.
Blank lines and whole-line ``#`` comments are skipped (their bytes still count for the
time tag, :mod:`.timetag`).  The blocks are those of :mod:`.chunked`.
"""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.realdata.loaders import chunked
from fuzzynav.realdata.loaders.chunked import DEFAULT_CHUNK_ROWS

__all__ = ["read_imu_csv", "parsed_blocks", "HELD_BYTES_PER_LINE", "BLOCK_BYTES_PER_LINE"]

#: peak memory of loading a recording per line of its IMU CSV beyond its parse block
#: [bytes]: measured 170 and 198 (the growth of the peak tracemalloc traces over
#: ``load_rtklib`` between synthetic drives of 186 401 and 726 401 lines, and of 106 401 and
#: 306 401: the parsed rows, the timing columns, the increments;
#: ``benchmarks/bench_memory_figures.py``), rounded up
HELD_BYTES_PER_LINE = 256
#: peak memory per line of the block being parsed and integrated [bytes]: the lines' text
#: and the block's rates, areas and running integrals; measured 330-460 (a drive's peak less
#: its lines, over a block of 65 536), rounded up.  The 54 860-line drive, one block, traced
#: 484 B a line in all against 768 estimated
BLOCK_BYTES_PER_LINE = 512

_CSV_COLUMNS = 7
_CSV_NAMES = ("acc x", "acc y", "acc z", "gyro x", "gyro y", "gyro z", "tick")
_CSV_LAYOUT = "acc x,y,z [g], gyro x,y,z [deg/s], tick [ms]"


#: what a line that is blank by ``bytes.strip`` starts with: ASCII whitespace
_BLANK_STARTS = tuple(bytes([c]) for c in b" \t\n\r\x0b\x0c")


def _data_lines(lines, first: int, blob: bytes) -> np.ndarray:
    """Positions in ``lines`` (a block whose first line is line ``first`` of the file, 0-based,
    ``blob`` their bytes joined) of the lines that hold data.

    The file's first line is dropped (logging started inside it), and its last unless it
    ends with a newline (only the last line can lack one).  Blank lines and whole-line ``#``
    comments (an edited or concatenated copy) are skipped; their bytes still count in the
    offsets matched against the tag.  A block without a ``#`` and without a line that starts
    with whitespace (which every blank line does) holds data on every line: that is found on
    its bytes at once, the usual case, without looking at each line.
    """
    if b"#" in blob or blob.startswith(_BLANK_STARTS) or \
            any(b"\n" + c in blob for c in _BLANK_STARTS):
        return np.array([j for j, line in enumerate(lines)
                         if first + j >= 1 and line.endswith(b"\n") and line.strip()
                         and not line.lstrip().startswith(b"#")], dtype=np.int64)
    rows = np.arange(len(lines) - (not lines[-1].endswith(b"\n")), dtype=np.int64)
    return rows[1:] if first == 0 else rows


def _refuse_line(path, lineno: int, line: bytes):
    """Raise the error naming what is wrong in one line that did not parse."""
    fields = line.split(b",")
    if len(fields) != _CSV_COLUMNS:
        raise InputFileError(path, f"line {lineno}", f"{len(fields)} fields, expected "
                                                     f"{_CSV_COLUMNS}: {_CSV_LAYOUT}")
    for name, field in zip(_CSV_NAMES, fields):
        text = field.strip().decode("ascii", "replace")[:24]
        try:
            value = float(field)
        except ValueError:
            raise InputFileError(path, f"line {lineno}, column {name}",
                                 f"{text!r} is not a number ({_CSV_LAYOUT})") from None
        if not np.isfinite(value):
            raise InputFileError(path, f"line {lineno}, column {name}",
                                 f"{text!r} is not a finite number")


def _tick_error(path, tick, lineno):
    """The error of the first tick that does not increase (``None`` if all do); ``lineno``
    the 1-based line of each tick."""
    step = np.diff(tick)
    bad = np.flatnonzero(step <= 0)
    if not bad.size:
        return None
    k = bad[0]
    what = (f"repeats the previous tick {tick[k]:.0f}" if step[k] == 0 else
            f"{tick[k + 1]:.0f} after {tick[k]:.0f}")
    return InputFileError(path, f"line {lineno[k + 1]}, column tick",
                          f"{what}: ticks must increase")


def _parse_block(path, lines, rows, blob) -> np.ndarray:
    """The numbers of the data lines ``rows`` of a block (positions in ``lines``, ``blob``
    their bytes joined), parsed at once; ``None`` when some line does not parse
    (:func:`_refuse_line` then says which)."""
    if rows.size and rows[-1] - rows[0] + 1 == rows.size:  # consecutive: a slice of blob
        head = sum(len(x) for x in lines[:rows[0]])  # the lines before and after: a few
        body = blob[head:len(blob) - sum(len(x) for x in lines[rows[-1] + 1:])]
    else:
        body = b"".join(lines[j] for j in rows)
    try:
        data = np.loadtxt(io.BytesIO(body), delimiter=",", ndmin=2, comments=None)
    except ValueError:
        data = None
    if data is None or data.shape[1] != _CSV_COLUMNS or not np.all(np.isfinite(data)):
        return None
    return data


#: what a whole read refuses first (after too few lines): a line that does not parse, a file
#: that does not parse although no line fails alone, a tick that does not increase
_ERROR_ORDER = ("line", "csv", "tick")


def read_imu_csv(path, chunk_rows=DEFAULT_CHUNK_ROWS, columns=slice(None),
                 held_bytes_per_line=HELD_BYTES_PER_LINE, hint: str = ""):
    """Rows of an IMU CSV with partial first/last lines, blank and comment lines dropped.

    The file is read ``chunk_rows`` lines at a time (:mod:`.chunked`; ``None``: at once):
    each block's lines are parsed and checked, the tick order across block boundaries too;
    every block size gives the same arrays and the same error.

    Parameters
    ----------
    path : path-like
    chunk_rows : int or None
    columns : slice or int, optional
        The columns of the rows kept (default all; ``6``: the ticks alone, what the timing
        of a recording read again later needs, :mod:`.imu_file`).
    held_bytes_per_line : float
        Memory held per line of the file once read, for the size check before reading
        (:func:`~.chunked.counted_lines`, whose refusal ends with ``hint``).

    Returns
    -------
    data : ndarray, shape (K, 7), or the kept ``columns`` of it
    kept : ndarray of int, shape (K,)
        0-based line index of each row in the file.
    line_lengths : ndarray of int
        Length of every line of the file (without ``\\n``).
    file_size : int
    """
    path = Path(path)
    chunk_rows = chunked.check_chunk_rows(chunk_rows)
    n = chunked.counted_lines(path, held_bytes_per_line, block_lines=chunk_rows,
                              bytes_per_block_line=BLOCK_BYTES_PER_LINE, hint=hint)
    # every line's length, the data lines' indices and rows: at most one per line (int32:
    # a file of 2**31 lines would need hundreds of GB; the clock fits are a day's peak)
    lengths, kept_rows = (chunked.Rows(path, n, None, np.int32) for _ in range(2))
    width = np.empty(_CSV_COLUMNS)[columns].size
    data_rows = chunked.Rows(path, n, width if isinstance(columns, slice) else None)
    for lines, first, rows, data in parsed_blocks(path, chunk_rows):
        lengths.add([len(x) - x.endswith(b"\n") for x in lines])
        kept_rows.add(rows + first)
        if data is not None:
            data_rows.add(data[:, columns])
    kept = kept_rows.array()
    return data_rows.array(), kept, lengths.array(), path.stat().st_size


def parsed_blocks(path, chunk_rows=DEFAULT_CHUNK_ROWS):
    """Yield ``(lines, first, rows, data)`` for each block of an IMU CSV: its lines, the index
    of its first line, the positions of its data lines and their parsed numbers (K, 7), or
    ``None`` once a line failed (then only the lines are counted).

    The checks run as the blocks are read (fields, numbers, ticks increasing, also across
    blocks); the first error of each kind is raised, in the whole read's order, after the
    last block (:class:`~.chunked.FirstErrors`), or at once if the file holds fewer than two
    sample lines.
    """
    errors = chunked.FirstErrors(_ERROR_ORDER)
    last = None  # (tick, line number) of the previous block's last row
    n_rows = 0
    with open(path, "rb") as f:
        for first, lines in chunked.line_blocks(f, chunk_rows):
            blob = b"".join(lines)
            rows = _data_lines(lines, first, blob)
            n_rows += rows.size
            data = None if not rows.size or "line" in errors else \
                _parse_block(path, lines, rows, blob)
            del blob
            if data is None and rows.size and "line" not in errors:
                try:
                    for j in rows:
                        _refuse_line(path, first + j + 1, lines[j][:-1])  # without its "\n"
                    errors.note("csv", InputFileError(path, "", f"not a CSV of {_CSV_LAYOUT}"))
                except InputFileError as exc:
                    errors.note("line", exc)
            if data is not None:
                lineno = rows + (first + 1)
                tick = data[:, 6] if last is None else np.concatenate([[last[0]], data[:, 6]])
                bad = _tick_error(path, tick, lineno if last is None else
                                  np.concatenate([[last[1]], lineno]))
                if bad is not None:
                    errors.note("tick", bad)
                last = (data[-1, 6], lineno[-1])
            yield lines, first, rows, data
    if n_rows < 2:
        raise InputFileError(path, "lines", "fewer than two complete sample lines")
    errors.raise_first()
