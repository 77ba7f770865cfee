"""Bounded text reading and atomic text writing, shared by the rule-file formats."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

from fuzzynav.errors import DataMissingError, OutputError
from fuzzynav.fuzzy._where import FisError

#: larger files are refused before parsing
MAX_FILE_BYTES = 8 * 1024 * 1024


def read_text(path, what: str = "rule file") -> str:
    """Read a UTF-8 text file of at most :data:`MAX_FILE_BYTES` bytes."""
    p = Path(path)
    try:
        with open(p, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            if size > MAX_FILE_BYTES:
                raise FisError(p, "", f"file is {size} bytes; a {what} may be at most "
                                      f"{MAX_FILE_BYTES} bytes")
            data = fh.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError:
        raise DataMissingError(f"{p}: no such {what}") from None
    except IsADirectoryError:
        raise FisError(p, "", f"is a directory, not a {what}") from None
    except PermissionError:
        raise FisError(p, "", "permission denied") from None
    if len(data) > MAX_FILE_BYTES:
        raise FisError(p, "", f"a {what} may be at most {MAX_FILE_BYTES} bytes")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise FisError(p, "", f"not UTF-8 text (byte {exc.start})") from None


def write_text_atomic(path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and ``os.replace``.

    A failure (read-only directory, full disk) raises :class:`~fuzzynav.errors.OutputError`
    with ``path`` unchanged and no temporary file left.  (``fuzzynav.fileio`` does the same
    for the rest of the package; the fuzzy engine imports nothing of it.)
    """
    p = Path(path)
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent or ".")
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)  # mkstemp makes 0600: give the file the usual mode
        os.replace(tmp, p)
    except OSError as exc:
        raise OutputError(p, exc) from None
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
