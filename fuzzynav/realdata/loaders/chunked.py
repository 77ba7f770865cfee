"""Reading recording files a bounded number of lines at a time.

The loaders (:func:`fuzzynav.realdata.loaders.rtklib.read_imu_csv`,
:func:`fuzzynav.realdata.loaders.akit_recording.read_table`) parse a file block by block:
only one block of text lines is held at once, the parsed rows are kept as compact float
arrays.  The checks a row can fail on its own (fields, numbers, finiteness) run per block;
the checks between consecutive rows (time increasing) carry the last row of the previous
block across the boundary.  The whole read is the case of one block
(``chunk_rows=None``): both give the same arrays to the last bit, because every row is
parsed by itself.

A whole read reports the *first* defect of a kind in file order, and some kinds before
others (a file too short before a bad field, a bad field anywhere before a time step
backwards).  A chunked read meets the defects block by block, so :class:`FirstErrors`
keeps the first of each kind and :meth:`FirstErrors.raise_first` raises them in the whole
read's order once the file has been read: the same error, whatever the block size.
"""
from __future__ import annotations

from itertools import islice

import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.sim import budget

__all__ = ["DEFAULT_CHUNK_ROWS", "MAX_MEAN_LINE_BYTES", "line_blocks", "FirstErrors",
           "check_chunk_rows", "count_lines", "counted_lines", "Rows"]

#: lines parsed at a time by default: 65 536 lines of the car's IMU CSV are ~3 MB of text
#: (11 minutes at 100 Hz), a block small next to a recording of hours yet large enough that
#: numpy's parser, not the Python loop around it, sets the speed
DEFAULT_CHUNK_ROWS = 1 << 16
#: largest mean line length of a recording's text file [bytes]: their rows are 50-200
#: bytes; a file of megabytes in a few lines (binary, or padded with NULs) would be held
#: whole as one line before its first row is checked
MAX_MEAN_LINE_BYTES = 4096


def check_chunk_rows(chunk_rows):
    """``chunk_rows`` as an int (``None``: the whole file in one block); refuses < 1."""
    if chunk_rows is None:
        return None
    if int(chunk_rows) != chunk_rows or chunk_rows < 1:
        raise ValueError(f"chunk_rows must be a positive whole number of lines or None, got "
                         f"{chunk_rows!r}")
    return int(chunk_rows)


def line_blocks(stream, chunk_rows):
    """Yield ``(first, lines)``: consecutive blocks of at most ``chunk_rows`` lines of an open
    file (``None``: one block of every line), ``first`` the 0-based index of the block's
    first line.  Lines keep their line end (only the file's last may have none)."""
    first = 0
    while True:
        lines = stream.readlines() if chunk_rows is None else list(islice(stream, chunk_rows))
        if not lines:
            return
        yield first, lines
        first += len(lines)
        if chunk_rows is None:
            return


def count_lines(path, universal: bool = False) -> int:
    """How many lines :func:`line_blocks` will yield for ``path`` (the last may lack its
    newline), counted in blocks of 1 MB: of the file opened in binary (lines end at
    ``\\n``) or, ``universal``, in text mode (``\\r\\n``, ``\\r`` and ``\\n`` end a line)."""
    n, tail = 0, b""
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            n += block.count(b"\n")
            if universal:  # a lone \r ends a line too; \r\n (even across blocks) is one end
                n += block.count(b"\r") - block.count(b"\r\n") \
                    - (tail == b"\r" and block[:1] == b"\n")
            tail = block[-1:]
    ends = (b"", b"\n", b"\r") if universal else (b"", b"\n")
    return n + (tail not in ends)


def counted_lines(path, bytes_per_line: float, universal: bool = False,
                  block_lines=None, bytes_per_block_line: float = 0.0, hint: str = "") -> int:
    """:func:`count_lines` of ``path``, refusing, before a line is parsed, a file that is not
    text lines (a mean line over :data:`MAX_MEAN_LINE_BYTES`) or whose lines, held at
    ``bytes_per_line`` each once read, and its block of ``block_lines`` lines being parsed
    (``None``: every line), at ``bytes_per_block_line`` each, need more memory than one run
    may use (:func:`fuzzynav.sim.budget.memory_limit`).

    Memory, not the file's size, is what limits a recording: it is read a block of lines
    at a time and only its parsed rows are held.  ``hint``, if given, ends the refusal
    (how to read the file in less memory).
    """
    n = count_lines(path, universal)
    size = path.stat().st_size
    if size > MAX_MEAN_LINE_BYTES * max(n, 1):
        raise InputFileError(path, "", f"is {budget.human_bytes(size)} in {n} lines: not a "
                                       f"text table (lines of at most {MAX_MEAN_LINE_BYTES} "
                                       "bytes on average, MAX_MEAN_LINE_BYTES)")
    block = n if block_lines is None else min(n, block_lines)
    need = n * bytes_per_line + block * bytes_per_block_line
    limit, source = budget.memory_limit()
    if need > limit:
        raise InputFileError(path, "", f"has {n} lines: read and held they need "
                                       f"~{budget.human_bytes(need)}; the limit is "
                                       f"{budget.human_bytes(limit)} ({source})"
                                       + (f"; {hint}" if hint else ""))
    return n


class Rows:
    """An array of at most ``n`` rows filled block by block.

    The rows of a file are known in number beforehand (:func:`count_lines`), so the blocks
    are written into one array as they are parsed: no list of blocks and no concatenated
    copy of the whole (which would double the memory at the end of the read).

    Parameters
    ----------
    path : path-like
        The file the rows come from (for the message if it grew while read).
    n : int
    width : int, optional
        Columns of a 2-D array; ``None`` for a 1-D one.
    dtype : numpy dtype
    """

    def __init__(self, path, n: int, width=None, dtype=float):
        self.path = path
        self.buf = np.empty((n,) if width is None else (n, width), dtype)
        self.n = 0

    def add(self, a) -> None:
        """Append the rows of ``a``."""
        k = len(a)
        if self.n + k > self.buf.shape[0]:
            raise InputFileError(self.path, "", "grew while it was read (a file still being "
                                                "logged? read a finished copy)")
        self.buf[self.n:self.n + k] = a
        self.n += k

    def array(self) -> np.ndarray:
        """The rows added (a view of the first :attr:`n`)."""
        return self.buf[:self.n]


class FirstErrors:
    """The first error of each kind met while reading, raised in a fixed order of kinds.

    Parameters
    ----------
    order : sequence of str
        The kinds, in the order a whole read checks them.
    """

    def __init__(self, order):
        self.order = tuple(order)
        self.found = {}

    def note(self, kind: str, error: Exception) -> None:
        """Keep ``error`` unless a ``kind`` error was met earlier in the file."""
        if kind not in self.order:
            raise ValueError(f"unknown error kind {kind!r}")
        self.found.setdefault(kind, error)

    def __contains__(self, kind: str) -> bool:
        return kind in self.found

    def raise_first(self) -> None:
        """Raise the error of the first kind (in :attr:`order`) that was met; nothing when
        none was."""
        for kind in self.order:
            if kind in self.found:
                raise self.found[kind]
